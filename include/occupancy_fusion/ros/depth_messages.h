// sensor_msgs/Image depth images and their sensor_msgs/CameraInfo to the core's DepthImageView +
// CameraIntrinsics (DepthMapper). What is wrong with a frame is named in the exception, and its
// reason kept, so the mapper counts drops by reason. Bad pixels are no reason to drop a frame:
// NaN, +-inf, 0 and negative depths (and 0 mm) pass through, and the integrator skips them as
// "no measurement".
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "occupancy_fusion/sensors/camera_intrinsics.h"
#include "occupancy_fusion/sensors/depth_image.h"

namespace occupancy_fusion {

// Why a depth image cannot be integrated: its encoding or layout, or its camera_info.
class DepthImageRejected : public std::invalid_argument {
 public:
  enum class Reason { kEncoding, kCameraInfo };
  DepthImageRejected(Reason reason, const std::string& message)
      : std::invalid_argument(message), reason_(reason) {}
  Reason reason() const { return reason_; }

 private:
  Reason reason_;
};

// The image's pixels as z-depth in metres (16UC1 / mono16 in mm, 32FC1 in m, host byte order),
// in `storage` when they need converting or copying, else pointing into the message. Throws
// DepthImageRejected (kEncoding) for another encoding, a foreign byte order, or a step or data
// size too small for the image.
DepthImageView depthInMetres(const sensor_msgs::Image& image, std::vector<float>* storage);

// Intrinsics from K of a camera_info that must describe this very image. Throws
// DepthImageRejected (kCameraInfo) when its size differs from the image's, for binning or a
// region of interest, for a focal length that is not positive, and for intrinsics that fail
// CameraIntrinsics::validate().
CameraIntrinsics depthCameraIntrinsics(const sensor_msgs::CameraInfo& info,
                                       const sensor_msgs::Image& image);

}  // namespace occupancy_fusion
