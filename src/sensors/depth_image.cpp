#include "occupancy_fusion/sensors/depth_image.h"

#include <stdexcept>
#include <string>

namespace occupancy_fusion {

void DepthImageView::validateAgainst(const CameraIntrinsics& camera) const {
  if (depth == nullptr) throw std::invalid_argument("DepthImageView.depth is null");
  if (width != camera.width || height != camera.height) {
    throw std::invalid_argument("DepthImageView size " + std::to_string(width) + "x" +
                                std::to_string(height) + " differs from the camera's " +
                                std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
  if (row_stride != 0 && row_stride < width) {
    throw std::invalid_argument("DepthImageView.row_stride must be 0 or >= width");
  }
}

std::vector<float> depthFromMillimetres(const std::uint16_t* millimetres, std::size_t count) {
  std::vector<float> metres(count);
  for (std::size_t i = 0; i < count; ++i) metres[i] = 0.001f * static_cast<float>(millimetres[i]);
  return metres;
}

}  // namespace occupancy_fusion
