#include "occupancy_fusion/ros/disparity_messages.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include <sensor_msgs/image_encodings.h>

#include "occupancy_fusion/ros/camera_info_message.h"
#include "occupancy_fusion/ros/image_bytes.h"

namespace occupancy_fusion {
namespace {

void requireConsistentLayout(const sensor_msgs::Image& image) {
  if (image.encoding != sensor_msgs::image_encodings::TYPE_32FC1) {
    throw std::invalid_argument("disparity image encoding must be 32FC1, got '" + image.encoding +
                                "'");
  }
  if (isEmptyImage(image)) {
    throw std::invalid_argument("disparity image is empty");
  }
  if (!rowsFitData(image, sizeof(float))) {
    throw std::invalid_argument("disparity image of " + std::to_string(image.width) + "x" +
                                std::to_string(image.height) + " has step " +
                                std::to_string(image.step) + " and " +
                                std::to_string(image.data.size()) + " bytes");
  }
}

bool insideWindow(const sensor_msgs::RegionOfInterest& window, std::uint32_t u, std::uint32_t v) {
  if (window.width == 0 || window.height == 0) return true;  // not set: the whole image
  return u >= window.x_offset && u < window.x_offset + window.width && v >= window.y_offset &&
         v < window.y_offset + window.height;
}

}  // namespace

std::vector<float> validDisparities(const stereo_msgs::DisparityImage& message) {
  const sensor_msgs::Image& image = message.image;
  requireConsistentLayout(image);
  const bool swap = needsByteSwap(image);
  const bool has_upper_bound = message.max_disparity > message.min_disparity;
  constexpr float kInvalid = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> disparity(static_cast<std::size_t>(image.width) * image.height);
  for (std::uint32_t v = 0; v < image.height; ++v) {
    const std::uint8_t* row = image.data.data() + static_cast<std::size_t>(v) * image.step;
    for (std::uint32_t u = 0; u < image.width; ++u) {
      const float d = readValue<float>(row + u * sizeof(float), swap);
      const bool valid = std::isfinite(d) && d >= message.min_disparity &&
                         (!has_upper_bound || d <= message.max_disparity) &&
                         insideWindow(message.valid_window, u, v);
      disparity[static_cast<std::size_t>(v) * image.width + u] = valid ? d : kInvalid;
    }
  }
  return disparity;
}

StereoCamera stereoCameraOf(const stereo_msgs::DisparityImage& message,
                            const sensor_msgs::CameraInfo& left_info) {
  if (binnedWidth(left_info) != message.image.width ||
      binnedHeight(left_info) != message.image.height) {
    throw std::invalid_argument(
        "camera_info is for " + std::to_string(binnedWidth(left_info)) + "x" +
        std::to_string(binnedHeight(left_info)) + " images, the disparity image is " +
        std::to_string(message.image.width) + "x" + std::to_string(message.image.height));
  }
  // f and T describe the disparity image itself (a matcher may scale them); the rest is the
  // left camera's, by the one camera_info rule.
  const CameraIntrinsics left = intrinsicsOf(left_info);
  StereoCamera camera;
  camera.fx = message.f;
  camera.baseline = message.T;
  camera.fy = left.fy;
  camera.cx = left.cx;
  camera.cy = left.cy;
  camera.validate();
  return camera;
}

stereo_msgs::DisparityImage disparityImageMessage(const std::vector<float>& disparity, int width,
                                                  int height, const StereoCamera& camera) {
  if (disparity.size() != static_cast<std::size_t>(width) * height) {
    throw std::invalid_argument("disparity buffer does not hold width x height values");
  }
  stereo_msgs::DisparityImage message;
  message.image.width = static_cast<std::uint32_t>(width);
  message.image.height = static_cast<std::uint32_t>(height);
  message.image.encoding = sensor_msgs::image_encodings::TYPE_32FC1;
  message.image.is_bigendian = hostByteOrderFlag();
  message.image.step = static_cast<std::uint32_t>(width * sizeof(float));
  message.image.data.resize(disparity.size() * sizeof(float));
  std::vector<float> written(disparity);
  for (float& d : written) {
    if (!std::isfinite(d)) d = -1.0f;
  }
  std::memcpy(message.image.data.data(), written.data(), message.image.data.size());
  message.f = static_cast<float>(camera.fx);
  message.T = static_cast<float>(camera.baseline);
  message.valid_window.width = message.image.width;
  message.valid_window.height = message.image.height;
  message.min_disparity = 0.0f;
  message.max_disparity = static_cast<float>(width);
  message.delta_d = 1.0f / 16.0f;
  return message;
}

sensor_msgs::CameraInfo leftCameraInfoMessage(const StereoCamera& camera, int width, int height) {
  return cameraInfoMessage(camera.leftIntrinsics(width, height), "", ros::Time());
}

}  // namespace occupancy_fusion
