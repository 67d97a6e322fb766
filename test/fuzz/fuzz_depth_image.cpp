// sensor_msgs/Image + sensor_msgs/CameraInfo -> DepthImageView + CameraIntrinsics, as the depth
// mapper converts every frame (src/ros/depth_messages.cpp). Any input must either be rejected with
// DepthImageRejected or give a view whose every pixel can be read.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include <sensor_msgs/image_encodings.h>

#include "fuzz_input.h"
#include "occupancy_fusion/ros/depth_messages.h"

namespace occupancy_fusion {
namespace fuzz {
namespace {

template <typename Codec>
void describe(Codec* codec, sensor_msgs::Image* image, sensor_msgs::CameraInfo* info) {
  codec->field(&image->width);
  codec->field(&image->height);
  codec->field(&image->step);
  codec->field(&image->is_bigendian);
  codec->field(&image->encoding);
  codec->bytes(&image->data);
  codec->field(&info->width);
  codec->field(&info->height);
  codec->field(&info->binning_x);
  codec->field(&info->binning_y);
  codec->field(&info->roi.width);
  codec->field(&info->roi.height);
  for (double& k : info->K) codec->field(&k);
}

}  // namespace

void writeSeeds() {
  namespace enc = sensor_msgs::image_encodings;
  const struct {
    const char* name;
    std::string encoding;
    std::uint32_t pixel_bytes, padding;
  } kinds[] = {{"seed_16uc1", enc::TYPE_16UC1, 2, 0},
               {"seed_32fc1", enc::TYPE_32FC1, 4, 0},
               {"seed_32fc1_padded", enc::TYPE_32FC1, 4, 2},
               {"seed_mono16_padded", enc::MONO16, 2, 4}};
  for (const auto& kind : kinds) {
    sensor_msgs::Image image;
    image.width = 4;
    image.height = 3;
    image.encoding = kind.encoding;
    image.step = image.width * kind.pixel_bytes + kind.padding;
    image.data.assign(static_cast<std::size_t>(image.step) * image.height, 0x3f);
    sensor_msgs::CameraInfo info;
    info.width = image.width;
    info.height = image.height;
    info.K = {5.0, 0.0, 1.5, 0.0, 5.0, 1.0, 0.0, 0.0, 1.0};
    writeSeed(kind.name, encodeFields(describe<FuzzWriter>, &image, &info));
  }
}

}  // namespace fuzz
}  // namespace occupancy_fusion

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occupancy_fusion;
  sensor_msgs::Image image;
  sensor_msgs::CameraInfo info;
  fuzz::decodeFields(fuzz::describe<fuzz::FuzzReader>, data, size, &image, &info);
  try {
    std::vector<float> storage;
    const DepthImageView view = depthInMetres(image, &storage);
    const CameraIntrinsics camera = depthCameraIntrinsics(info, image);
    view.validateAgainst(camera);
    // The integrator reads every pixel: so does the harness (ASan checks the view's bounds).
    double sum = 0.0;
    for (int v = 0; v < view.height; ++v) {
      for (int u = 0; u < view.width; ++u) sum += std::isfinite(view.at(u, v)) ? 1.0 : 0.0;
    }
    if (sum > static_cast<double>(view.width) * view.height) std::abort();
  } catch (const DepthImageRejected&) {
  } catch (const std::invalid_argument&) {  // validateAgainst
  }
  return 0;
}
