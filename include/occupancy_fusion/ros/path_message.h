// Eigen poses as a nav_msgs/Path, shared by the Simulator nodelet and the tools (header-only, as
// transform_message.h).
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include <nav_msgs/Path.h>
#include <ros/time.h>
#include <tf2_eigen/tf2_eigen.h>

namespace occupancy_fusion {

// The path of poses[i] (of a body in frame_id) stamped stamps[i] (as many), the path itself
// stamped `stamp`.
inline nav_msgs::Path pathMessage(const std::vector<Eigen::Isometry3d>& poses,
                                  const std::vector<ros::Time>& stamps, const std::string& frame_id,
                                  const ros::Time& stamp) {
  nav_msgs::Path path;
  path.header.frame_id = frame_id;
  path.header.stamp = stamp;
  path.poses.reserve(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    geometry_msgs::PoseStamped pose;
    pose.header.frame_id = frame_id;
    pose.header.stamp = stamps.at(i);
    pose.pose = tf2::toMsg(poses[i]);
    path.poses.push_back(pose);
  }
  return path;
}

}  // namespace occupancy_fusion
