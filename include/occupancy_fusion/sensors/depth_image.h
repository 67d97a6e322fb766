// A depth camera's image and its pinhole intrinsics, as the core's depth integrator reads them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "occupancy_fusion/sensors/camera_intrinsics.h"

namespace occupancy_fusion {

// A non-owning, row-major view of z-depth in metres (the z coordinate in the optical frame, not
// the length of the ray). 0 and NaN mark pixels without a measurement. It can wrap a
// std::vector, a cv::Mat of CV_32FC1 or a decoded ROS image without copying.
struct DepthImageView {
  int width = 0;
  int height = 0;
  const float* depth = nullptr;  // depth[v * row_stride + u]
  int row_stride = 0;            // floats per row; 0 means width

  float at(int u, int v) const {
    return depth[static_cast<std::size_t>(v) * (row_stride > 0 ? row_stride : width) + u];
  }
  // Throws std::invalid_argument unless the view is non-null and matches the camera's size.
  void validateAgainst(const CameraIntrinsics& camera) const;
};

// Depth cameras' 16-bit millimetre encoding (16UC1) to metres; 0 stays 0 (no measurement).
std::vector<float> depthFromMillimetres(const std::uint16_t* millimetres, std::size_t count);

}  // namespace occupancy_fusion
