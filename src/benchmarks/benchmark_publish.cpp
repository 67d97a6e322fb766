// benchmark publish: what the MapServer nodelet pays per publishing cycle after a change of fixed
// size, for maps of growing size, against rebuilding its outputs from the whole map (what
// octomap_server does on every publish).
//
// The map is synthetic: fully observed blocks of 8^3 voxels stacked 4 blocks high over a square
// footprint that grows with the map, about 10 % of the voxels occupied (a hash of the voxel index
// decides, so every run builds the same map). A change rewrites B blocks chosen at random.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include "occupancy_fusion/benchmarks/benchmark_harness.h"
#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/ros/conversions.h"
#include "occupancy_fusion/ros/occupied_voxel_cache.h"
#include "occupancy_fusion/sim/deterministic_random.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

using bench::Clock;
using bench::median;
using bench::millisecondsSince;

// "1e5,1e6" -> {1e5, 1e6}; UsageError naming the option on anything else.
std::vector<double> positiveList(const CommandLine& args, const std::string& option,
                                 const std::string& fallback) {
  return bench::parseNumberList<double>(option, args.value(option, fallback), "numbers >= 1",
                                        [](double value) { return value >= 1.0; });
}

constexpr int kStackBlocks = 4;  // blocks per column of the synthetic map (1.6 m at 5 cm)

// Blocks of a square footprint, kStackBlocks high, holding at least `known_voxels` voxels.
std::vector<BlockIndex> syntheticBlocks(double known_voxels) {
  const double columns = std::ceil(known_voxels / (VoxelBlock::kVolume * kStackBlocks));
  const int side = static_cast<int>(std::ceil(std::sqrt(columns)));
  std::vector<BlockIndex> blocks;
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      for (int z = 0; z < kStackBlocks; ++z) blocks.emplace_back(x - side / 2, y - side / 2, z);
  return blocks;
}

// Every voxel known; about 10 % occupied at the upper clamping bound, the rest free at the lower.
// `seed` changes the pattern, so rewriting a block with a new seed changes its content.
void fillBlock(const VoxelMap& map, std::uint64_t seed, const BlockIndex& index,
               VoxelBlock& block) {
  for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
    const VoxelIndex voxel = VoxelMap::voxelIndex(index, linear);
    const std::uint64_t hash = sim::hashKey({seed, static_cast<std::uint64_t>(voxel.x()),
                                             static_cast<std::uint64_t>(voxel.y()),
                                             static_cast<std::uint64_t>(voxel.z())});
    block.set(linear, hash % 10 == 0 ? map.maxLogOdds() : map.minLogOdds());
  }
}

// `count` distinct blocks of `blocks`, picked by a seeded partial shuffle.
std::vector<BlockIndex> pickBlocks(std::vector<BlockIndex> blocks, std::size_t count,
                                   std::uint64_t seed) {
  count = std::min(count, blocks.size());
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t j = i + sim::hashKey({seed, i}) % (blocks.size() - i);
    std::swap(blocks[i], blocks[j]);
  }
  blocks.resize(count);
  return blocks;
}

// What publishCloud does with the cache: one PointCloud2 of every occupied centre.
std::size_t fillCloud(const OccupiedVoxelCache& cache) {
  sensor_msgs::PointCloud2 cloud;
  resizeXyzCloud(cache.occupiedCount(), &cloud);
  sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  cache.forEachCentre([&](const Eigen::Vector3f& centre) {
    *x = centre.x();
    *y = centre.y();
    *z = centre.z();
    ++x, ++y, ++z;
  });
  return cloud.data.size();
}

struct CaseTimes {
  std::vector<double> cache, grid, compose, grid_message, cloud_message, full_cache, full_grid;
};

void runCase(double known_voxels, std::size_t changed_blocks, int repetitions, double resolution) {
  VoxelMapConfig config;
  config.resolution = resolution;
  VoxelMap map(config);
  const std::vector<BlockIndex> blocks = syntheticBlocks(known_voxels);
  changed_blocks = std::min(changed_blocks, blocks.size());  // a small map changes entirely
  map.updateBlocks(
      blocks, [&](const BlockIndex& index, VoxelBlock& block) { fillBlock(map, 0, index, block); });
  OccupiedVoxelCache cache;
  FusedGridView view;
  cache.refresh(map);  // the first, full refresh is not timed
  view.update(map, nullptr);

  CaseTimes t;
  OccupancyRaster raster;
  std::size_t cloud_bytes = 0;
  for (int r = 0; r < repetitions; ++r) {
    const std::uint64_t seed = static_cast<std::uint64_t>(r) + 1;
    map.updateBlocks(
        pickBlocks(blocks, changed_blocks, seed),
        [&](const BlockIndex& index, VoxelBlock& block) { fillBlock(map, seed, index, block); });
    auto start = Clock::now();
    const OccupiedVoxelCache::RefreshStats stats = cache.refresh(map);
    t.cache.push_back(millisecondsSince(start));
    start = Clock::now();
    raster = view.update(map, nullptr);
    t.grid.push_back(millisecondsSince(start));
    if (stats.full_rebuild || view.lastUpdateStats().map_rebuilt) {
      throw std::logic_error("publish: an incremental refresh rebuilt from scratch");
    }
    // No change since: what is left is walking the column tiles and assembling the raster.
    start = Clock::now();
    view.update(map, nullptr);
    t.compose.push_back(millisecondsSince(start));
    start = Clock::now();
    nav_msgs::OccupancyGrid grid;
    toOccupancyGridMessage(raster, "map", ros::Time(), &grid);
    t.grid_message.push_back(millisecondsSince(start));
    start = Clock::now();
    cloud_bytes = fillCloud(cache);
    t.cloud_message.push_back(millisecondsSince(start));

    // octomap_server's way: walk the whole map for the centres and for the projection.
    start = Clock::now();
    OccupiedVoxelCache fresh;
    fresh.refresh(map);
    t.full_cache.push_back(millisecondsSince(start));
    start = Clock::now();
    const OccupancyRaster reference = projectToRaster(map, nullptr, view.config());
    t.full_grid.push_back(millisecondsSince(start));
    if (reference.data != raster.data || fresh.occupiedCount() != cache.occupiedCount()) {
      throw std::logic_error("publish: incremental and full results differ");
    }
  }
  const double incremental = median(t.cache) + median(t.grid);
  const double full = median(t.full_cache) + median(t.full_grid);
  std::printf(
      "publish known_voxels=%zu changed_blocks=%zu incremental_ms=%.3f full_rebuild_ms=%.3f "
      "cache_ms=%.3f grid_ms=%.3f grid_compose_ms=%.3f full_cache_ms=%.3f full_grid_ms=%.3f "
      "grid_message_ms=%.3f cloud_message_ms=%.3f map_blocks=%zu occupied_voxels=%zu "
      "raster_cells=%zu cloud_bytes=%zu\n",
      map.knownVoxelCount(), changed_blocks, incremental, full, median(t.cache), median(t.grid),
      median(t.compose), median(t.full_cache), median(t.full_grid), median(t.grid_message),
      median(t.cloud_message), map.blockCount(), cache.occupiedCount(), raster.data.size(),
      cloud_bytes);
  std::fflush(stdout);
}

}  // namespace

int runPublish(const CommandLine& args) {
  const std::vector<double> sizes = positiveList(args, "known_voxels", "1e5,1e6,1e7");
  const std::vector<double> changes = positiveList(args, "changed_blocks", "64");
  const int repetitions = args.intValue("repetitions", 5);
  if (repetitions < 1) throw UsageError("--repetitions must be at least 1");
  const double resolution = args.doubleValue("resolution", 0.05);
  if (!(resolution > 0.0)) throw UsageError("--resolution must be positive");
  for (double known_voxels : sizes) {
    for (double changed : changes) {
      runCase(known_voxels, static_cast<std::size_t>(changed), repetitions, resolution);
    }
  }
  return 0;
}

}  // namespace occupancy_fusion
