// A map pushed far past its memory bound by a moving sensor (docs/architecture.md, "Memory bound
// and eviction"): after every write the storage is within the bound, an evicting write drops the
// blocks farthest from the focus down to 90 % of the bound, incremental consumers (the change log,
// the fused 2D view the MapServer publishes) drop the evicted blocks, and the cost of a frame
// stays flat. Only the public API is used, in units of VoxelBlock, so the test holds for any
// VoxelBlock::kSide; the blocks are stored dense (eviction of sparse blocks:
// test_voxel_map_storage.cpp).
#include <gtest/gtest.h>

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <tuple>
#include <vector>

#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {
namespace {

using BlockSet = std::set<std::tuple<int, int, int>>;

std::tuple<int, int, int> asTuple(const BlockIndex& block) {
  return {block.x(), block.y(), block.z()};
}

BlockSet allocatedBlocks(const VoxelMap& map) {
  BlockSet blocks;
  map.forEachBlock(
      [&](const BlockIndex& block, const VoxelBlock&) { blocks.insert(asTuple(block)); });
  return blocks;
}

// Distance from the focus to a block's centre, in block edges (the measure eviction sorts by).
double blockDistance(const BlockIndex& block, const Eigen::Vector3d& focus_in_blocks) {
  return ((block.cast<double>().array() + 0.5).matrix() - focus_in_blocks).norm();
}

double processCpuSeconds() {
  timespec time{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &time);
  return static_cast<double>(time.tv_sec) + 1e-9 * static_cast<double>(time.tv_nsec);
}

// One frame of a sensor at `sensor_block` (in block units): a hit on a row of voxels in every block
// of a 7 x 7 x 3 neighbourhood, as a scan of the surroundings would write.
std::vector<VoxelUpdate> frameUpdates(const Eigen::Vector3i& sensor_block,
                                      std::vector<BlockIndex>* frame_blocks) {
  constexpr int kRadius = 3;
  std::vector<VoxelUpdate> updates;
  frame_blocks->clear();
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -kRadius; dy <= kRadius; ++dy) {
      for (int dx = -kRadius; dx <= kRadius; ++dx) {
        const BlockIndex block = sensor_block + Eigen::Vector3i(dx, dy, dz);
        frame_blocks->push_back(block);
        for (int x = 0; x < VoxelBlock::kSide; ++x) {
          updates.push_back({VoxelMap::voxelIndex(block, VoxelBlock::linearIndex(x, 1, 2)), 0.85f});
        }
      }
    }
  }
  return updates;
}

TEST(VoxelMapMemoryBound, MovingSensorEvictsFarthestBlocksAndStaysFlat) {
  constexpr std::size_t kBoundBlocks = 300;  // a 7 x 7 x 3 frame (147 blocks) fits in 90 %
  constexpr int kFrames = 400;
  constexpr int kCheckGridEvery = 5;
  VoxelMapConfig config;
  config.resolution = 0.1;
  config.block_storage = BlockStorage::kDense;
  config.max_memory_bytes = kBoundBlocks * sizeof(VoxelBlock);
  VoxelMap map(config);
  const double block_edge = config.resolution * VoxelBlock::kSide;

  // Consumers as the MapServer has them: a block set kept from the change log (the occupied-voxel
  // cache works the same way) and the incremental fused view behind projected_map.
  BlockSet consumer_blocks;
  std::uint64_t consumer_version = map.changesSince(0).version;
  FusedGridView view;

  std::vector<double> frame_cpu_seconds;
  std::size_t evicting_frames = 0;
  std::size_t removals_reported = 0;
  std::vector<BlockIndex> frame_blocks;
  for (int frame = 0; frame < kFrames; ++frame) {
    // The sensor moves half a block edge per frame along +x: 200 block edges in all, about 4000
    // blocks written, more than 13 times the bound.
    const Eigen::Vector3d sensor(0.5 * frame * block_edge + 0.5 * block_edge, 0.5 * block_edge,
                                 0.5 * block_edge);
    const Eigen::Vector3i sensor_block = (sensor / block_edge).array().floor().cast<int>();
    const std::vector<VoxelUpdate> updates = frameUpdates(sensor_block, &frame_blocks);
    const std::size_t evicted_before = map.evictedBlockCount();

    const double start = processCpuSeconds();
    map.setFocus(sensor);
    map.applyUpdates(updates);
    frame_cpu_seconds.push_back(processCpuSeconds() - start);

    // Within the bound after every write (blocks alone are a lower bound of the storage).
    ASSERT_LE(map.blockCount() * sizeof(VoxelBlock), config.max_memory_bytes) << "frame " << frame;
    const BlockSet blocks = allocatedBlocks(map);
    // The frame's own blocks are the nearest to the focus: none was evicted.
    for (const BlockIndex& block : frame_blocks) {
      ASSERT_EQ(blocks.count(asTuple(block)), 1u) << "frame " << frame;
    }

    const MapChanges changes = map.changesSince(consumer_version);
    ASSERT_FALSE(changes.full_rebuild) << "frame " << frame;
    consumer_version = changes.version;
    for (const BlockIndex& block : changes.changed) consumer_blocks.insert(asTuple(block));
    for (const BlockIndex& block : changes.removed) consumer_blocks.erase(asTuple(block));
    removals_reported += changes.removed.size();
    // The change log tells consumers exactly which blocks exist.
    ASSERT_EQ(consumer_blocks, blocks) << "frame " << frame;

    const std::size_t evicted_now = map.evictedBlockCount() - evicted_before;
    ASSERT_EQ(changes.removed.size(), evicted_now) << "frame " << frame;
    if (evicted_now > 0) {
      ++evicting_frames;
      // Down to 90 % of the bound, but not much further: eviction stops once below 90 %, and
      // the hash table is a small part of the storage.
      EXPECT_LE(map.blockCount() * sizeof(VoxelBlock), config.max_memory_bytes / 10 * 9);
      EXPECT_GE(map.blockCount(), kBoundBlocks * 7 / 10) << "frame " << frame;
      // Farthest first: every kept block is at most as far from the focus as every evicted one.
      const Eigen::Vector3d focus_in_blocks = sensor / block_edge;
      double farthest_kept = 0.0;
      for (const auto& [x, y, z] : blocks) {
        farthest_kept = std::max(farthest_kept, blockDistance({x, y, z}, focus_in_blocks));
      }
      double nearest_evicted = 1e300;
      for (const BlockIndex& block : changes.removed) {
        nearest_evicted = std::min(nearest_evicted, blockDistance(block, focus_in_blocks));
      }
      EXPECT_LE(farthest_kept, nearest_evicted + 1e-9) << "frame " << frame;
    }

    // projected_map: the incremental view drops the evicted columns, as a full projection does.
    if (frame % kCheckGridEvery == 0 || frame == kFrames - 1) {
      const OccupancyRaster incremental = view.update(map, nullptr);
      const OccupancyRaster reference = projectToRaster(map, nullptr, FusedGridConfig());
      ASSERT_EQ(incremental.width, reference.width) << "frame " << frame;
      ASSERT_EQ(incremental.height, reference.height) << "frame " << frame;
      EXPECT_DOUBLE_EQ(incremental.origin_x, reference.origin_x) << "frame " << frame;
      EXPECT_DOUBLE_EQ(incremental.origin_y, reference.origin_y) << "frame " << frame;
      ASSERT_EQ(incremental.data, reference.data) << "frame " << frame;
    }
  }
  // The bound was exceeded many times over and eviction ran again and again.
  EXPECT_GT(map.evictedBlockCount(), 10 * kBoundBlocks);
  EXPECT_GT(evicting_frames, 50u);
  EXPECT_EQ(removals_reported, map.evictedBlockCount());
  // Nothing behind the sensor's last bound-sized neighbourhood is left: the start of the path
  // was evicted.
  EXPECT_EQ(map.occupancy(VoxelMap::voxelIndex({-3, 0, 0}, VoxelBlock::linearIndex(0, 1, 2))),
            Occupancy::kUnknown);

  // Responsive: the CPU time of a frame does not grow with the distance travelled. Compare the
  // 40 frames after the bound was first reached with the last 40 (process CPU time, robust to
  // other load; generous factor and a floor for timer noise).
  const int first_full = static_cast<int>(kBoundBlocks / 20);  // ~10 new blocks per frame
  double early = 0.0, late = 0.0;
  for (int i = 0; i < 40; ++i) {
    early += frame_cpu_seconds[first_full + i];
    late += frame_cpu_seconds[kFrames - 40 + i];
  }
  RecordProperty("early_frame_cpu_us", static_cast<int>(early / 40 * 1e6));
  RecordProperty("late_frame_cpu_us", static_cast<int>(late / 40 * 1e6));
  EXPECT_LE(late / 40, 3.0 * early / 40 + 50e-6)
      << "early " << early / 40 * 1e6 << " us, late " << late / 40 * 1e6 << " us per frame";
}

}  // namespace
}  // namespace occupancy_fusion
