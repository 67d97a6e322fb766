// The rays of a stereo frame: which points can be walked to, their end voxels, and bundle_rays'
// grouping of the points by end voxel (VisibilityStereoConfig::bundle_rays). Internal to the
// stereo integrator.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/map/spatial_key.h"

namespace occupancy_fusion {

// Where a point's ray goes: its end voxel (the packed key) and squared range from the sensor.
struct RayTarget {
  // packKey uses 63 bits, so neither marker is a voxel's key.
  static constexpr std::uint64_t kUnusable = ~std::uint64_t{0};  // a point no ray can reach
  static constexpr std::uint64_t kNoPoint = kUnusable - 1;       // a slot without a point

  std::uint64_t key;
  double squared_range;

  bool isPoint() const { return key != kNoPoint; }
  bool isUsable() const { return key < kNoPoint; }
};

// The squared range of a point the ray caster can walk to from origin, or -1: finite, within the
// frame's key range (keys hold 2^20 voxels each way; the walk may continue a few sigma past the
// point) and, with needs_direction, apart from the origin (the walk past the point needs a
// direction). The squared range, not the range: no square root for a test against 0.
inline double usableSquaredRange(const Eigen::Vector3d& point, const Eigen::Vector3d& origin,
                                 double resolution, bool needs_direction) {
  if (!point.allFinite()) return -1.0;
  const Eigen::Vector3d offset = point - origin;
  const double squared_range = offset.squaredNorm();
  if (needs_direction && !(squared_range > 0)) return -1.0;
  const double limit = 0.5 * kMaxKeyCoordinate3D * resolution;
  return (offset.array().abs() < limit).all() ? squared_range : -1.0;
}

// The point's end voxel when the ray caster can walk to it from origin (usableSquaredRange) and
// its range sigma is finite and non-negative; otherwise key = RayTarget::kUnusable. Inline: called
// per pixel by the frame's conversion.
inline RayTarget rayTargetOf(const Eigen::Vector3f& point_f, float sigma,
                             const Eigen::Vector3d& origin, double resolution,
                             bool needs_direction) {
  const Eigen::Vector3d point = point_f.cast<double>();
  const double squared_range = usableSquaredRange(point, origin, resolution, needs_direction);
  const bool usable_sigma = std::isfinite(sigma) && sigma >= 0;
  return squared_range >= 0 && usable_sigma
             ? RayTarget{packKey(voxelIndexOf(point, resolution)), squared_range}
             : RayTarget{RayTarget::kUnusable, 0.0};
}

// rayTargetOf of every point, on every thread of a parallel region for a large frame.
std::vector<RayTarget> rayTargetsOf(const std::vector<Eigen::Vector3f>& points,
                                    const std::vector<float>& sigmas, const Eigen::Vector3d& origin,
                                    double resolution, bool needs_direction);

// bundle_rays: per end voxel the nearest and the farthest usable point (see
// VisibilityStereoConfig::bundle_rays), in the order of each voxel's first point, so that
// neighbouring pixels stay neighbouring rays for the previous-ray cache; one ray where they are the
// same point, and always one for OctoMap's update, whose ray ends at the voxel's centre.
// Neighbouring pixels mostly share their end voxel, so the last voxel is checked
// before the hash table.
// visibility_mode: the farthest point of each voxel too.
// skipped: incremented per unusable point (slots without a point are not counted).
std::vector<std::uint32_t> bundleRaysByEndVoxel(const std::vector<RayTarget>& ends,
                                                bool visibility_mode, std::size_t* skipped);

}  // namespace occupancy_fusion
