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

// The squared length of v, its sum written out in the order Eigen's squaredNorm() takes on x86-64
// (SSE2), so that the frame's conversion, which computes it for many pixels at once, gives the
// same bits on every build.
inline double squaredLength(const Eigen::Vector3d& v) {
  return (v.x() * v.x() + v.y() * v.y()) + v.z() * v.z();
}

// The squared range of a point the ray caster can walk to from origin, or -1: finite, within the
// frame's key range (keys hold 2^20 voxels each way; the walk may continue a few sigma past the
// point) and, with needs_direction, apart from the origin (the walk past the point needs a
// direction). The squared range, not the range: no square root for a test against 0. Given the
// point's finiteness, its offset from the origin and squaredLength(offset).
inline double usableSquaredRange(bool finite, const Eigen::Vector3d& offset, double squared_range,
                                 double resolution, bool needs_direction) {
  if (!finite) return -1.0;
  if (needs_direction && !(squared_range > 0)) return -1.0;
  const double limit = 0.5 * kMaxKeyCoordinate3D * resolution;
  return (offset.array().abs() < limit).all() ? squared_range : -1.0;
}

inline double usableSquaredRange(const Eigen::Vector3d& point, const Eigen::Vector3d& origin,
                                 double resolution, bool needs_direction) {
  const Eigen::Vector3d offset = point - origin;
  return usableSquaredRange(point.allFinite(), offset, squaredLength(offset), resolution,
                            needs_direction);
}

// Where the ray of a point with range sigma `sigma` goes, given usableSquaredRange of the point
// and its coordinates in voxels (point / resolution, read only where the point is usable): its
// end voxel, or key = RayTarget::kUnusable where the range or the sigma (not finite, negative)
// rules it out (isUsable).
inline bool isUsable(double usable_squared_range, float sigma) {
  return usable_squared_range >= 0 && std::isfinite(sigma) && sigma >= 0;
}

inline RayTarget rayTargetOf(double usable_squared_range, float sigma,
                             const Eigen::Vector3d& point_in_voxels) {
  if (!isUsable(usable_squared_range, sigma)) return RayTarget{RayTarget::kUnusable, 0.0};
  const VoxelIndex voxel(floorToInt(point_in_voxels.x()), floorToInt(point_in_voxels.y()),
                         floorToInt(point_in_voxels.z()));  // voxelIndexOf
  return RayTarget{packKey(voxel), usable_squared_range};
}

// The point's RayTarget seen from origin (the overload above). Inline: called per point.
inline RayTarget rayTargetOf(const Eigen::Vector3f& point_f, float sigma,
                             const Eigen::Vector3d& origin, double resolution,
                             bool needs_direction) {
  const Eigen::Vector3d point = point_f.cast<double>();
  return rayTargetOf(usableSquaredRange(point, origin, resolution, needs_direction), sigma,
                     point / resolution);
}

// rayTargetOf of every point, on every thread of a parallel region for a large frame.
std::vector<RayTarget> rayTargetsOf(const std::vector<Eigen::Vector3f>& points,
                                    const std::vector<float>& sigmas, const Eigen::Vector3d& origin,
                                    double resolution, bool needs_direction);

// One walk of bundle_rays: to the point `farthest`, with the P(I_v) of the point `nearest` too
// (the same point where the end voxel has one, and always for OctoMap's update).
struct BundledRay {
  std::uint32_t farthest, nearest;
};

// bundle_rays: per end voxel the nearest and the farthest usable point (see
// VisibilityStereoConfig::bundle_rays), in the order of each voxel's first point, so that
// neighbouring pixels stay neighbouring rays for the previous-ray cache; one point where they are
// the same, and always the nearest alone for OctoMap's update, whose ray ends at the voxel's
// centre. Neighbouring pixels mostly share their end voxel, so the last voxel is checked before
// the hash table.
// visibility_mode: the farthest point of each voxel too.
// skipped: incremented per unusable point (slots without a point are not counted).
std::vector<BundledRay> bundleRaysByEndVoxel(const std::vector<RayTarget>& ends,
                                             bool visibility_mode, std::size_t* skipped);

// The rays of an image's points (slot = row * columns + column, as FrameRays lays them out)
// reordered tile by tile: the rays whose farthest point lies in one kRayTilePx x kRayTilePx tile
// together, in their order, and the tiles along a Z-order curve. Rays that follow each other
// then cross nearly the same voxels, from both sides: the walks' tables of the frame's voxels
// stay in cache, and each thread's contiguous share of the rays is a compact part of the image
// (row by row, a ray's neighbour in the row above came a whole image row earlier). The walks
// reduce by maximum, so the order changes no update.
constexpr int kRayTilePx = 8;
void orderByImageTiles(int columns, std::vector<BundledRay>* rays);

}  // namespace occupancy_fusion
