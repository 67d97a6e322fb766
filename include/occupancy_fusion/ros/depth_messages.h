// sensor_msgs/Image depth images and their sensor_msgs/CameraInfo to the core's DepthImageView +
// CameraIntrinsics: the one conversion of the DepthMapper nodelet and offline_mapper's bag reader.
// What is wrong with a frame is named in the exception, and its reason kept, so the mapper counts
// drops by reason. Bad pixels are no reason to drop a frame: NaN, +-inf, 0 and negative depths (and
// 0 mm) pass through, and the integrator skips them as "no measurement".
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

// True for the encodings depthInMetres reads: 16UC1 / mono16 (mm) and 32FC1 (m).
bool isDepthEncoding(const std::string& encoding);

// The intrinsics of a camera_info that must describe this very image, by intrinsicsOf's rule (P
// where set, else K; camera_info_message.h). Throws DepthImageRejected (kCameraInfo) when its
// size (after binning) differs from the image's, and for whatever intrinsicsOf rejects (a region
// of interest, a focal length that is not positive, invalid intrinsics).
CameraIntrinsics depthCameraIntrinsics(const sensor_msgs::CameraInfo& info,
                                       const sensor_msgs::Image& image);

}  // namespace occupancy_fusion
