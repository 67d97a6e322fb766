// A SLAM system's keyframes as the reanchoring reads them (mapping/map_reanchoring.h): each pose
// of a nav_msgs/Path with its own stamp (header-only, as transform_message.h).
#pragma once

#include <vector>

#include <nav_msgs/Path.h>
#include <tf2_eigen/tf2_eigen.h>

#include "occupancy_fusion/mapping/trajectory_corrections.h"

namespace occupancy_fusion {

inline std::vector<StampedPose> keyframesOf(const nav_msgs::Path& path) {
  std::vector<StampedPose> keyframes;
  keyframes.reserve(path.poses.size());
  for (const geometry_msgs::PoseStamped& pose : path.poses) {
    Eigen::Isometry3d T_map_base;
    tf2::fromMsg(pose.pose, T_map_base);
    keyframes.push_back({pose.header.stamp.toSec(), T_map_base});
  }
  return keyframes;
}

}  // namespace occupancy_fusion
