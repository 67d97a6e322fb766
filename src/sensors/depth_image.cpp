#include "occupancy_fusion/sensors/depth_image.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace occupancy_fusion {

void CameraIntrinsics::validate() const {
  if (width <= 0) throw std::invalid_argument("CameraIntrinsics.width must be > 0");
  if (height <= 0) throw std::invalid_argument("CameraIntrinsics.height must be > 0");
  if (!(std::isfinite(fx) && fx > 0.0)) {
    throw std::invalid_argument("CameraIntrinsics.fx must be finite and > 0");
  }
  if (!(std::isfinite(fy) && fy > 0.0)) {
    throw std::invalid_argument("CameraIntrinsics.fy must be finite and > 0");
  }
  if (!std::isfinite(cx)) throw std::invalid_argument("CameraIntrinsics.cx must be finite");
  if (!std::isfinite(cy)) throw std::invalid_argument("CameraIntrinsics.cy must be finite");
}

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
