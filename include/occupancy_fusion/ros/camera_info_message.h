// A sensor_msgs/CameraInfo for an ideal pinhole camera (no distortion, no rectification), as the
// simulator publishes and simulated recordings store it. Header only, so that the nodelets and
// the tools (occupancy_fusion_tools, which does not link the nodelets) share one definition.
#pragma once

#include <cstdint>
#include <string>

#include <ros/time.h>
#include <sensor_msgs/CameraInfo.h>

#include "occupancy_fusion/sensors/camera_intrinsics.h"

namespace occupancy_fusion {

inline sensor_msgs::CameraInfo cameraInfoMessage(const CameraIntrinsics& camera,
                                                 const std::string& frame_id,
                                                 const ros::Time& stamp) {
  sensor_msgs::CameraInfo info;
  info.header.frame_id = frame_id;
  info.header.stamp = stamp;
  info.width = static_cast<std::uint32_t>(camera.width);
  info.height = static_cast<std::uint32_t>(camera.height);
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  info.K = {camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0};
  info.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.P = {camera.fx, 0.0, camera.cx, 0.0, 0.0, camera.fy, camera.cy, 0.0, 0.0, 0.0, 1.0, 0.0};
  return info;
}

}  // namespace occupancy_fusion
