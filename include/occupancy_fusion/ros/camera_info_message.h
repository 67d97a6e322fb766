// sensor_msgs/CameraInfo and the core's CameraIntrinsics, both ways: the one rule by which every
// input (the DepthMapper and DisparityMapper nodelets, offline_mapper's bag reader) takes a
// camera's intrinsics from its camera_info, and the camera_info of an ideal pinhole camera that
// the simulator publishes and simulated recordings store.
#pragma once

#include <cstdint>
#include <string>

#include <ros/time.h>
#include <sensor_msgs/CameraInfo.h>

#include "occupancy_fusion/sensors/camera_intrinsics.h"

namespace occupancy_fusion {

// The intrinsics of the images a camera_info describes. fx, fy, cx, cy come from the projection
// matrix P when it is set (P[0] != 0): depth and disparity images are rectified (depth_image_proc
// registers into, and stereo_image_proc matches in, the rectified image, whose intrinsics are
// P's, as image_geometry's PinholeCameraModel projects), and P = [K | 0] for a camera that needs
// no rectification. K is used only when P is unset (all zero), as older drivers leave it. Binning
// divides the image size and the intrinsics, as image_geometry does. Throws std::invalid_argument
// for a region of interest (not supported), a focal length that is not positive ("focal
// length") and intrinsics that fail CameraIntrinsics::validate().
CameraIntrinsics intrinsicsOf(const sensor_msgs::CameraInfo& info);

// The image size intrinsicsOf gives: width / binning_x x height / binning_y.
std::uint32_t binnedWidth(const sensor_msgs::CameraInfo& info);
std::uint32_t binnedHeight(const sensor_msgs::CameraInfo& info);

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
