// stereo_msgs/DisparityImage + the left sensor_msgs/CameraInfo -> disparities, StereoCamera and
// 3D points (Eq. 7), as the disparity mapper converts every frame (src/ros/disparity_messages.cpp,
// src/sensors/disparity_image.cpp). Any input must be rejected with std::invalid_argument or give
// finite points in front of the camera with non-negative sigma_z.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include <sensor_msgs/image_encodings.h>

#include "fuzz_input.h"
#include "occupancy_fusion/ros/disparity_messages.h"

namespace occupancy_fusion {
namespace fuzz {
namespace {

template <typename Codec>
void describe(Codec* codec, stereo_msgs::DisparityImage* message, sensor_msgs::CameraInfo* info,
              DisparityConversionConfig* config, std::uint8_t* resolution) {
  sensor_msgs::Image& image = message->image;
  codec->field(&image.width);
  codec->field(&image.height);
  codec->field(&image.step);
  codec->field(&image.is_bigendian);
  codec->field(&image.encoding);
  codec->bytes(&image.data);
  codec->field(&message->f);
  codec->field(&message->T);
  codec->field(&message->min_disparity);
  codec->field(&message->max_disparity);
  codec->field(&message->valid_window.x_offset);
  codec->field(&message->valid_window.y_offset);
  codec->field(&message->valid_window.width);
  codec->field(&message->valid_window.height);
  codec->field(&info->width);
  codec->field(&info->height);
  codec->field(&info->binning_x);
  codec->field(&info->binning_y);
  for (double& k : info->K) codec->field(&k);
  for (double& p : info->P) codec->field(&p);
  codec->field(&config->disparity_sigma_px);
  codec->field(&config->min_disparity_px);
  codec->field(&config->max_depth_sigma_ratio);
  codec->field(resolution);
}

}  // namespace

void writeSeeds() {
  StereoCamera camera;
  camera.fx = camera.fy = 10.0;
  camera.cx = 2.0;
  camera.cy = 1.5;
  camera.baseline = 0.1;
  const std::vector<float> disparity = {1.0f, 2.0f, -1.0f, 4.0f, 0.5f, 8.0f,
                                        3.0f, 2.5f, 1.5f,  6.0f, 7.0f, 0.0f};
  for (std::uint8_t resolution : {1, 2, 4}) {
    stereo_msgs::DisparityImage message = disparityImageMessage(disparity, 4, 3, camera);
    sensor_msgs::CameraInfo info = leftCameraInfoMessage(camera, 4, 3);
    DisparityConversionConfig config;
    writeSeed("seed_resolution_" + std::to_string(resolution),
              encodeFields(describe<FuzzWriter>, &message, &info, &config, &resolution));
  }
}

namespace {

InputResolution resolutionOf(std::uint8_t code) {
  return code == 4   ? InputResolution::kQuarter
         : code == 2 ? InputResolution::kHalf
                     : InputResolution::kFull;
}

}  // namespace
}  // namespace fuzz
}  // namespace occupancy_fusion

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occupancy_fusion;
  stereo_msgs::DisparityImage message;
  sensor_msgs::CameraInfo info;
  DisparityConversionConfig config;
  std::uint8_t resolution = 1;
  fuzz::decodeFields(fuzz::describe<fuzz::FuzzReader>, data, size, &message, &info, &config,
                     &resolution);
  config.input_resolution = fuzz::resolutionOf(resolution);
  try {
    const std::vector<float> disparity = validDisparities(message);
    if (disparity.size() != static_cast<std::size_t>(message.image.width) * message.image.height) {
      std::abort();
    }
    const StereoCamera camera = stereoCameraOf(message, info);
    const DisparityImageView view{static_cast<int>(message.image.width),
                                  static_cast<int>(message.image.height), disparity.data(), 0};
    const StereoPoints points = disparityToPoints(view, camera, config);
    if (points.depth_sigmas.size() != points.points.size()) std::abort();
    for (std::size_t i = 0; i < points.size(); ++i) {
      // The ray caster walks from the camera to each point: it must be finite and in front.
      if (!points.points[i].allFinite() || !(points.points[i].z() > 0.0f) ||
          !(points.depth_sigmas[i] >= 0.0f)) {
        std::abort();
      }
    }
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
