#include "occupancy_fusion/ros/camera_info_message.h"

#include <algorithm>
#include <stdexcept>

namespace occupancy_fusion {
namespace {

// binning 0 means 1 (no binning), as in sensor_msgs/CameraInfo.
std::uint32_t binning(std::uint32_t value) { return std::max<std::uint32_t>(1, value); }

}  // namespace

std::uint32_t binnedWidth(const sensor_msgs::CameraInfo& info) {
  return info.width / binning(info.binning_x);
}

std::uint32_t binnedHeight(const sensor_msgs::CameraInfo& info) {
  return info.height / binning(info.binning_y);
}

CameraIntrinsics intrinsicsOf(const sensor_msgs::CameraInfo& info) {
  if (info.roi.width != 0 || info.roi.height != 0) {
    throw std::invalid_argument("camera_info of '" + info.header.frame_id +
                                "' has a region of interest (not supported)");
  }
  const double binning_x = binning(info.binning_x);
  const double binning_y = binning(info.binning_y);
  const bool has_projection = info.P[0] != 0.0;
  CameraIntrinsics camera;
  camera.width = static_cast<int>(binnedWidth(info));
  camera.height = static_cast<int>(binnedHeight(info));
  camera.fx = (has_projection ? info.P[0] : info.K[0]) / binning_x;
  camera.fy = (has_projection ? info.P[5] : info.K[4]) / binning_y;
  camera.cx = (has_projection ? info.P[2] : info.K[2]) / binning_x;
  camera.cy = (has_projection ? info.P[6] : info.K[5]) / binning_y;
  if (!(camera.fx > 0.0) || !(camera.fy > 0.0)) {
    throw std::invalid_argument("camera_info of '" + info.header.frame_id +
                                "' has focal length fx = " + std::to_string(camera.fx) +
                                ", fy = " + std::to_string(camera.fy));
  }
  camera.validate();
  return camera;
}

}  // namespace occupancy_fusion
