// A depth camera's image and its pinhole intrinsics, as the core's depth integrator reads them.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace occupancy_fusion {

// Pinhole intrinsics in the ROS (sensor_msgs/CameraInfo) convention: pixel (u, v) has its
// centre at the integer coordinates (u, v), u to the right, v down, (cx, cy) in the same
// coordinates. The optical frame has z forward, x right, y down.
struct CameraIntrinsics {
  int width = 640;
  int height = 480;
  double fx = 525.0;  // px
  double fy = 525.0;  // px
  double cx = 319.5;  // px
  double cy = 239.5;  // px

  void validate() const;  // throws std::invalid_argument naming the bad field

  // Direction of pixel (u, v) in the optical frame, with z component 1 (not unit length).
  Eigen::Vector3d pixelRay(double u, double v) const { return {(u - cx) / fx, (v - cy) / fy, 1.0}; }
  // Pixel coordinates of a point in the optical frame (z > 0).
  Eigen::Vector2d project(const Eigen::Vector3d& point) const {
    return {fx * point.x() / point.z() + cx, fy * point.y() / point.z() + cy};
  }
};

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
