#include "ray_bundles.h"

#include <cmath>

#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

namespace {

bool isUsable(const Eigen::Vector3d& point, const Eigen::Vector3d& origin, double resolution,
              bool needs_direction) {
  if (!point.allFinite()) return false;
  const double range = (point - origin).norm();
  if (needs_direction && !(range > 0)) return false;  // the walk past the point needs a direction
  // Keys hold 2^20 voxels each way; the walk may continue a few sigma past the
  // point.
  const double limit = 0.5 * kMaxKeyCoordinate3D * resolution;
  return ((point - origin).array().abs() < limit).all();
}

// Per point: the key of its end voxel and its squared range, or kUnusableRay. Independent per
// point, so computed on every thread before the (sequential) grouping.
constexpr std::uint64_t kUnusableRay = ~std::uint64_t{0};  // packKey uses 63 bits
constexpr std::size_t kParallelPoints = 8192;

struct EndVoxel {
  std::uint64_t key;
  double squared_range;
};

std::vector<EndVoxel> endVoxels(const std::vector<Eigen::Vector3f>& points,
                                const std::vector<float>& sigmas, const Eigen::Vector3d& origin,
                                double resolution, bool needs_direction) {
  std::vector<EndVoxel> ends(points.size());
  const long count = static_cast<long>(points.size());
#pragma omp parallel for schedule(static) if (points.size() >= kParallelPoints)
  for (long i = 0; i < count; ++i) {
    const Eigen::Vector3d point = points[i].cast<double>();
    ends[i] =
        isUsableRay(point, sigmas[i], origin, resolution, needs_direction)
            ? EndVoxel{packKey(voxelIndexOf(point, resolution)), (point - origin).squaredNorm()}
            : EndVoxel{kUnusableRay, 0.0};
  }
  return ends;
}

}  // namespace

bool isUsableRay(const Eigen::Vector3d& point, float sigma, const Eigen::Vector3d& origin,
                 double resolution, bool needs_direction) {
  return isUsable(point, origin, resolution, needs_direction) && std::isfinite(sigma) && sigma >= 0;
}

std::vector<std::uint32_t> bundleRaysByEndVoxel(const std::vector<Eigen::Vector3f>& points,
                                                const std::vector<float>& sigmas,
                                                const Eigen::Vector3d& origin, double resolution,
                                                bool visibility_mode, std::size_t* skipped) {
  const bool needs_direction = visibility_mode, needs_depth = visibility_mode;
  struct Bundle {
    std::uint32_t nearest, farthest;
    double nearest_squared_range, farthest_squared_range;
  };
  const std::vector<EndVoxel> ends = endVoxels(points, sigmas, origin, resolution, needs_direction);
  std::vector<Bundle> bundles;
  SpatialKeyMap<std::uint32_t> bundle_of_voxel;
  std::uint64_t last_key = kUnusableRay;
  std::uint32_t last_bundle = 0;
  for (std::uint32_t i = 0; i < ends.size(); ++i) {
    const auto [key, squared_range] = ends[i];
    if (key == kUnusableRay) {
      ++*skipped;
      continue;
    }
    if (key != last_key) {
      const auto [it, inserted] =
          bundle_of_voxel.try_emplace(key, static_cast<std::uint32_t>(bundles.size()));
      if (inserted) bundles.push_back({i, i, squared_range, squared_range});
      last_key = key;
      last_bundle = it->second;
    }
    Bundle& bundle = bundles[last_bundle];
    if (squared_range < bundle.nearest_squared_range) {  // ties: the first point
      bundle.nearest = i;
      bundle.nearest_squared_range = squared_range;
    }
    if (squared_range > bundle.farthest_squared_range) {
      bundle.farthest = i;
      bundle.farthest_squared_range = squared_range;
    }
  }
  std::vector<std::uint32_t> rays;
  rays.reserve(2 * bundles.size());
  for (const Bundle& bundle : bundles) {
    rays.push_back(bundle.nearest);
    if (needs_depth && bundle.farthest != bundle.nearest) rays.push_back(bundle.farthest);
  }
  return rays;
}

}  // namespace occupancy_fusion
