// An Eigen pose as a tf message, shared by the nodelets and the tools (header-only, so the tools
// need not link the nodelet library).
#pragma once

#include <Eigen/Geometry>
#include <string>

#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <tf2_eigen/tf2_eigen.h>

namespace occupancy_fusion {

// parent_T_child as a tf message: it maps points from child_frame to parent_frame.
inline geometry_msgs::TransformStamped transformMessage(const Eigen::Isometry3d& parent_T_child,
                                                        const std::string& parent_frame,
                                                        const std::string& child_frame,
                                                        const ros::Time& stamp) {
  geometry_msgs::TransformStamped message = tf2::eigenToTransform(parent_T_child);
  message.header.frame_id = parent_frame;
  message.header.stamp = stamp;
  message.child_frame_id = child_frame;
  return message;
}

}  // namespace occupancy_fusion
