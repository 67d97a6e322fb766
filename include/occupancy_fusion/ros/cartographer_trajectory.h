// cartographer's optimised trajectory (the answer of its trajectory_query service) as the
// nav_msgs/Path of keyframes that reanchoring:=path reads (header-only, as path_message.h). The
// cartographer_path_relay polls the service and republishes the path when the graph moved.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Path.h>
#include <tf2_eigen/tf2_eigen.h>

namespace occupancy_fusion {

// The trajectory's nodes as a path in the first node's frame, ordered by stamp. Nodes in another
// frame, with a zero stamp or a pose that is not a finite rigid transform are left out (counted in
// *left_out when given).
inline nav_msgs::Path trajectoryPath(const std::vector<geometry_msgs::PoseStamped>& nodes,
                                     std::size_t* left_out = nullptr) {
  nav_msgs::Path path;
  if (!nodes.empty()) path.header.frame_id = nodes.front().header.frame_id;
  for (const geometry_msgs::PoseStamped& node : nodes) {
    const auto& q = node.pose.orientation;
    const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    const auto& p = node.pose.position;
    const bool usable = node.header.frame_id == path.header.frame_id &&
                        !node.header.stamp.isZero() && std::isfinite(p.x + p.y + p.z) &&
                        std::abs(norm - 1.0) < 1e-3;
    if (usable) path.poses.push_back(node);
  }
  if (left_out != nullptr) *left_out = nodes.size() - path.poses.size();
  std::stable_sort(path.poses.begin(), path.poses.end(),
                   [](const auto& a, const auto& b) { return a.header.stamp < b.header.stamp; });
  if (!path.poses.empty()) path.header.stamp = path.poses.back().header.stamp;
  return path;
}

// Whether `next` tells the map something `last` did not: other nodes, another frame, or a node
// moved farther than min_translation (m) or turned more than min_rotation (rad).
inline bool pathMoved(const nav_msgs::Path& last, const nav_msgs::Path& next,
                      double min_translation, double min_rotation) {
  if (last.header.frame_id != next.header.frame_id || last.poses.size() != next.poses.size()) {
    return true;
  }
  for (std::size_t i = 0; i < next.poses.size(); ++i) {
    if (last.poses[i].header.stamp != next.poses[i].header.stamp) return true;
    Eigen::Isometry3d before, after;
    tf2::fromMsg(last.poses[i].pose, before);
    tf2::fromMsg(next.poses[i].pose, after);
    const Eigen::Isometry3d change = before.inverse() * after;
    if (change.translation().norm() > min_translation ||
        Eigen::AngleAxisd(change.linear()).angle() > min_rotation) {
      return true;
    }
  }
  return false;
}

}  // namespace occupancy_fusion
