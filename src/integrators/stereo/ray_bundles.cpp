#include "ray_bundles.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

namespace {

constexpr std::size_t kParallelPoints = 8192;

}  // namespace

std::vector<RayTarget> rayTargetsOf(const std::vector<Eigen::Vector3f>& points,
                                    const std::vector<float>& sigmas, const Eigen::Vector3d& origin,
                                    double resolution, bool needs_direction) {
  std::vector<RayTarget> ends(points.size());
  const long count = static_cast<long>(points.size());
#pragma omp parallel for schedule(static) if (points.size() >= kParallelPoints)
  for (long i = 0; i < count; ++i) {
    ends[i] = rayTargetOf(points[i], sigmas[i], origin, resolution, needs_direction);
  }
  return ends;
}

namespace {

struct Bundle {
  std::uint64_t key;
  std::uint32_t nearest, farthest;
  double nearest_squared_range, farthest_squared_range;
};

// The end voxels' bundles of points [first, last), in the order of each voxel's first point.
struct Bundles {
  std::vector<Bundle> list;
  SpatialKeyMap<std::uint32_t> of_voxel;  // key -> position in list
  std::size_t skipped = 0;
};

void groupByEndVoxel(const std::vector<RayTarget>& ends, std::uint32_t first, std::uint32_t last,
                     Bundles* out) {
  // Room for a bundle per eight points up front: growing the table rehashes every entry again.
  out->of_voxel.reserve((last - first) / 8);
  out->list.reserve((last - first) / 8);
  // The bundle of the points' run of one end voxel is kept in locals and written back when the
  // run ends: the nearer / farther choices then take no branch (a point's range within its voxel
  // is noise to a branch predictor).
  std::uint64_t last_key = RayTarget::kUnusable;
  Bundle current{};
  Bundle* bundle = nullptr;
  for (std::uint32_t i = first; i < last; ++i) {
    const auto [key, squared_range] = ends[i];
    if (key >= RayTarget::kNoPoint) {
      if (key == RayTarget::kUnusable) ++out->skipped;
      continue;
    }
    if (key != last_key) {
      if (bundle != nullptr) *bundle = current;
      const auto [it, inserted] =
          out->of_voxel.try_emplace(key, static_cast<std::uint32_t>(out->list.size()));
      if (inserted) out->list.push_back({key, i, i, squared_range, squared_range});
      last_key = key;
      bundle = &out->list[it->second];
      current = *bundle;
    }
    const bool nearer = squared_range < current.nearest_squared_range;  // ties: the first point
    current.nearest = nearer ? i : current.nearest;
    current.nearest_squared_range = nearer ? squared_range : current.nearest_squared_range;
    const bool farther = squared_range > current.farthest_squared_range;
    current.farthest = farther ? i : current.farthest;
    current.farthest_squared_range = farther ? squared_range : current.farthest_squared_range;
  }
  if (bundle != nullptr) *bundle = current;
}

// Appends a later part's bundles: a voxel already there keeps its place and takes the later
// point only when it is strictly nearer (farther), as one pass over both parts would.
void appendLater(const Bundles& later, Bundles* bundles) {
  for (const Bundle& theirs : later.list) {
    const auto [it, inserted] =
        bundles->of_voxel.try_emplace(theirs.key, static_cast<std::uint32_t>(bundles->list.size()));
    if (inserted) {
      bundles->list.push_back(theirs);
      continue;
    }
    Bundle& ours = bundles->list[it->second];
    if (theirs.nearest_squared_range < ours.nearest_squared_range) {
      ours.nearest = theirs.nearest;
      ours.nearest_squared_range = theirs.nearest_squared_range;
    }
    if (theirs.farthest_squared_range > ours.farthest_squared_range) {
      ours.farthest = theirs.farthest;
      ours.farthest_squared_range = theirs.farthest_squared_range;
    }
  }
  bundles->skipped += later.skipped;
}

// The bits of x at the even positions of the result (x < 2^16).
std::uint32_t spreadBits(std::uint32_t x) {
  x = (x | (x << 8)) & 0x00FF00FFu;
  x = (x | (x << 4)) & 0x0F0F0F0Fu;
  x = (x | (x << 2)) & 0x33333333u;
  x = (x | (x << 1)) & 0x55555555u;
  return x;
}

// The position of tile (u, v) along the Z-order curve.
std::uint32_t zOrderOf(std::uint32_t u, std::uint32_t v) {
  return spreadBits(u) | (spreadBits(v) << 1);
}

}  // namespace

void orderByImageTiles(int columns, std::vector<BundledRay>* rays) {
  if (columns <= 0 || rays->size() < 2) return;
  std::uint32_t last_slot = 0;
  for (const BundledRay& ray : *rays) last_slot = std::max(last_slot, ray.farthest);
  const auto tile_columns = static_cast<std::uint32_t>((columns + kRayTilePx - 1) / kRayTilePx);
  const std::uint32_t tile_rows = last_slot / static_cast<std::uint32_t>(columns) / kRayTilePx + 1;
  // The count table has a slot per Z-order position up to the last tile's: 4 MB for an image of
  // 8192 px a side. Larger images keep their order.
  if (std::max(tile_columns, tile_rows) > (1u << 10)) return;
  auto tileOf = [&](const BundledRay& ray) {
    const std::uint32_t row = ray.farthest / static_cast<std::uint32_t>(columns);
    const std::uint32_t column = ray.farthest - row * static_cast<std::uint32_t>(columns);
    return zOrderOf(column / kRayTilePx, row / kRayTilePx);
  };
  // A counting sort, stable: one pass to count each tile's rays, one to place them.
  std::vector<std::uint32_t> first_of_tile(zOrderOf(tile_columns - 1, tile_rows - 1) + 2, 0);
  for (const BundledRay& ray : *rays) ++first_of_tile[tileOf(ray) + 1];
  for (std::size_t tile = 1; tile < first_of_tile.size(); ++tile) {
    first_of_tile[tile] += first_of_tile[tile - 1];
  }
  std::vector<BundledRay> ordered(rays->size());
  for (const BundledRay& ray : *rays) ordered[first_of_tile[tileOf(ray)]++] = ray;
  *rays = std::move(ordered);
}

std::vector<BundledRay> bundleRaysByEndVoxel(const std::vector<RayTarget>& ends,
                                             bool visibility_mode, std::size_t* skipped) {
  const bool needs_depth = visibility_mode;
  // Consecutive parts of the points grouped on every thread, then joined in order: the same
  // bundles, in the same order, as one pass (and as on one thread).
  const int parts = ends.size() >= kParallelPoints ? std::max(1, omp_get_max_threads()) : 1;
  std::vector<Bundles> grouped(parts);
  const auto count = static_cast<std::uint32_t>(ends.size());
#pragma omp parallel for schedule(static, 1) num_threads(parts) if (parts > 1)
  for (int part = 0; part < parts; ++part) {
    groupByEndVoxel(ends, static_cast<std::uint32_t>(std::uint64_t{count} * part / parts),
                    static_cast<std::uint32_t>(std::uint64_t{count} * (part + 1) / parts),
                    &grouped[part]);
  }
  for (int part = 1; part < parts; ++part) appendLater(grouped[part], &grouped[0]);
  *skipped += grouped[0].skipped;
  std::vector<BundledRay> rays;
  rays.reserve(grouped[0].list.size());
  for (const Bundle& bundle : grouped[0].list) {
    rays.push_back({needs_depth ? bundle.farthest : bundle.nearest, bundle.nearest});
  }
  return rays;
}

}  // namespace occupancy_fusion
