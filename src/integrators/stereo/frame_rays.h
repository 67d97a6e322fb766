// A disparity frame's rays in the map frame: its points, their range sigmas and end voxels,
// computed in one pass per pixel on every thread. Internal to the stereo integrator.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <functional>
#include <vector>

#include "occupancy_fusion/sensors/disparity_image.h"
#include "ray_bundles.h"

namespace occupancy_fusion {

// One slot per pixel read (at the input resolution), in pixel order, so that rows converted on
// different threads are not joined: ends[i].isPoint() is false where the pixel gave no point.
struct FrameRays {
  std::vector<Eigen::Vector3f> points;  // map frame
  std::vector<float> range_sigmas;      // m, sigma_z scaled by range / z
  std::vector<RayTarget> ends;          // rayTargetOf each point
  int columns = 0;                      // slots per image row (slot = row * columns + column)
  std::size_t points_count = 0;         // slots with a point
  std::size_t dropped_uncertain = 0;    // valid disparities dropped for sigma_z / z
};

// The standard deviation along the ray of a camera point with depth standard deviation sigma_z:
// sigma_z is along the optical axis; along the ray it grows by range / z.
// The norm's sum is written out, in the order Eigen's norm() takes on x86-64, so that the frame's
// conversion, which computes it for many pixels at once, gives the same bits on every build.
inline float rangeSigmaOf(const Eigen::Vector3f& camera_point, float sigma_z) {
  const float x = camera_point.x(), y = camera_point.y(), z = camera_point.z();
  return sigma_z * std::sqrt(x * x + (y * y + z * z)) / z;
}

// transform * point, its sums written out as Eigen's (see rangeSigmaOf).
inline Eigen::Vector3f transformPoint(const Eigen::Isometry3f& transform,
                                      const Eigen::Vector3f& point) {
  const Eigen::Matrix3f& r = transform.linear();
  const Eigen::Vector3f& t = transform.translation();
  return {t.x() + ((r(0, 0) * point.x() + r(0, 1) * point.y()) + r(0, 2) * point.z()),
          t.y() + ((r(1, 0) * point.x() + r(1, 1) * point.y()) + r(1, 2) * point.z()),
          t.z() + ((r(2, 0) * point.x() + r(2, 1) * point.y()) + r(2, 2) * point.z())};
}

// disparityToPoints' points, moved to the map frame as VisibilityStereoIntegrator's
// disparityToMapPoints does, with their end voxels seen from the camera's origin. Inside a
// parallel region the rows are tasks of the enclosing team, and this thread runs `alongside` (other
// work of the frame, such as the measured surface, whose serial parts then overlap the rows)
// before it waits for them; outside one everything runs on this thread.
void convertFrameRays(const DisparityImageView& disparity, const StereoCamera& camera,
                      const DisparityConversionConfig& conversion,
                      const Eigen::Isometry3d& T_map_camera, double resolution,
                      bool needs_direction, FrameRays* rays,
                      const std::function<void()>& alongside = {});

}  // namespace occupancy_fusion
