// Pinhole intrinsics shared by the depth integrator's input (sensors/) and the simulator's
// renderers (sim/). Header-only, so that the simulator needs no link to the integrators' library.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <stdexcept>

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

  // Throws std::invalid_argument naming the bad field.
  void validate() const {
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

  // Direction of pixel (u, v) in the optical frame, with z component 1 (not unit length).
  Eigen::Vector3d pixelRay(double u, double v) const { return {(u - cx) / fx, (v - cy) / fy, 1.0}; }
  // Pixel coordinates of a point in the optical frame (z > 0).
  Eigen::Vector2d project(const Eigen::Vector3d& point) const {
    return {fx * point.x() / point.z() + cx, fy * point.y() / point.z() + cy};
  }
};

}  // namespace occupancy_fusion
