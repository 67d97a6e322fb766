// VoxelMap with a memory bound and a spill store (docs/architecture.md, "Spill store"): the same
// writes as an unbounded map give the same reads (voxels, iteration, counts, saved .bt/.ot), while
// most blocks live on disk; readers in parallel with a spilling writer read right; a store that
// fills up falls back to dropping blocks, observably; a bad store is refused naming its folder.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "../../common/test_folder.h"
#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {
namespace {

using VoxelMapSpill = TestFolder;
using Key = std::tuple<int, int, int>;
using VoxelValues = std::map<Key, float>;

constexpr int kRegionBlocks = 24;  // the random writes fall in 24 x 24 x 2 blocks
constexpr std::size_t kBoundBlocks = 40;

Key asKey(const Eigen::Vector3i& index) { return {index.x(), index.y(), index.z()}; }

VoxelValues knownVoxels(const VoxelMap& map) {
  VoxelValues values;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float value) {
    EXPECT_TRUE(values.emplace(asKey(index), value).second) << "visited twice";
  });
  return values;
}

std::map<Key, VoxelBlock> allBlocks(const VoxelMap& map) {
  std::map<Key, VoxelBlock> blocks;
  map.forEachBlock([&](const BlockIndex& index, const VoxelBlock& block) {
    EXPECT_TRUE(blocks.emplace(asKey(index), block).second) << "visited twice";
  });
  return blocks;
}

bool sameVoxels(const VoxelBlock& a, const VoxelBlock& b) {
  for (int i = 0; i < VoxelBlock::kVolume; ++i) {
    const bool known = VoxelBlock::isKnown(a.log_odds[i]);
    if (known != VoxelBlock::isKnown(b.log_odds[i])) return false;
    if (known && a.log_odds[i] != b.log_odds[i]) return false;
  }
  return a.known_count == b.known_count;
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

VoxelMapConfig boundedConfig(BlockStorage storage, const std::string& spill_folder) {
  VoxelMapConfig config;
  config.resolution = 0.1;
  config.block_storage = storage;
  config.max_memory_bytes = kBoundBlocks * sizeof(VoxelBlock);
  config.spill_folder = spill_folder;
  return config;
}

// One frame of writes around `focus_block`, the same for every map it is applied to: point
// updates, sometimes unclamped sets, sometimes a block callback (as the integrators write).
class RandomFrames {
 public:
  explicit RandomFrames(unsigned seed) : rng_(seed) {}

  Eigen::Vector3d nextFocus(double block_edge) {
    // A random walk over the region, so that blocks leave memory and are written again later.
    std::uniform_int_distribution<int> step(-2, 2);
    focus_block_.x() = std::clamp(focus_block_.x() + step(rng_), 1, kRegionBlocks - 2);
    focus_block_.y() = std::clamp(focus_block_.y() + step(rng_), 1, kRegionBlocks - 2);
    return (focus_block_.cast<double>().array() + 0.5) * block_edge;
  }

  void write(VoxelMap* bounded, VoxelMap* unbounded) {
    std::uniform_int_distribution<int> offset(-VoxelBlock::kSide, 2 * VoxelBlock::kSide - 1);
    std::uniform_int_distribution<int> z(0, 2 * VoxelBlock::kSide - 1);
    std::uniform_real_distribution<float> delta(-1.2f, 1.6f);
    std::uniform_int_distribution<int> kind(0, 9);
    const VoxelIndex base = focus_block_ * VoxelBlock::kSide;
    std::vector<VoxelUpdate> updates;
    for (int i = 0; i < 300; ++i) {
      updates.push_back(
          {base + VoxelIndex(offset(rng_), offset(rng_), z(rng_) - base.z()), delta(rng_)});
    }
    for (VoxelMap* map : {bounded, unbounded}) map->applyUpdates(updates);
    const int what = kind(rng_);
    if (what == 0) {
      const VoxelIndex index = base + VoxelIndex(offset(rng_), offset(rng_), -base.z());
      const float value = 5.0f * delta(rng_);  // beyond the clamping bounds
      for (VoxelMap* map : {bounded, unbounded}) map->setLogOdds(index, value);
    } else if (what < 4) {
      std::vector<BlockIndex> blocks;
      for (int dy = -1; dy <= 1; ++dy) blocks.push_back(focus_block_ + BlockIndex(what - 2, dy, 1));
      const float step = delta(rng_);
      auto fn = [step](const BlockIndex& block, VoxelBlock& voxels) {
        // A plane of voxels that depends on the block only: the same in both maps.
        const int y = (block.x() * 3 + block.y()) & (VoxelBlock::kSide - 1);
        for (int z = 0; z < VoxelBlock::kSide; ++z)
          for (int x = 0; x < VoxelBlock::kSide; ++x)
            voxels.update(VoxelBlock::linearIndex(x, y, z), step, -2.0f, 3.5f);
      };
      for (VoxelMap* map : {bounded, unbounded}) map->updateBlocks(blocks, fn);
    }
  }

 private:
  std::mt19937 rng_;
  BlockIndex focus_block_{kRegionBlocks / 2, kRegionBlocks / 2, 0};
};

// Every read of `map` equals the same read of `reference`.
void expectSameReads(const VoxelMap& map, const VoxelMap& reference, const std::string& folder) {
  const VoxelValues known = knownVoxels(reference);
  ASSERT_GT(known.size(), 10000u);
  EXPECT_EQ(knownVoxels(map), known);
  EXPECT_EQ(map.knownVoxelCount(), reference.knownVoxelCount());
  EXPECT_EQ(map.blockCount(), reference.blockCount());

  // Point queries: every known voxel, and voxels at random, known or not.
  for (const auto& [key, value] : known) {
    const auto [x, y, z] = key;
    const std::optional<float> read = map.logOdds({x, y, z});
    ASSERT_TRUE(read.has_value()) << x << " " << y << " " << z;
    ASSERT_EQ(*read, value) << x << " " << y << " " << z;
  }
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> coordinate(-8, kRegionBlocks * VoxelBlock::kSide + 8);
  for (int i = 0; i < 3000; ++i) {
    const VoxelIndex index(coordinate(rng), coordinate(rng), coordinate(rng) % 20 - 2);
    ASSERT_EQ(map.logOdds(index), reference.logOdds(index)) << index.transpose();
    ASSERT_EQ(map.occupancy(index), reference.occupancy(index)) << index.transpose();
  }

  std::size_t occupied = 0, free = 0, reference_occupied = 0, reference_free = 0;
  map.forEachOccupiedVoxel([&](const VoxelIndex&, float) { ++occupied; });
  map.forEachFreeVoxel([&](const VoxelIndex&, float) { ++free; });
  reference.forEachOccupiedVoxel([&](const VoxelIndex&, float) { ++reference_occupied; });
  reference.forEachFreeVoxel([&](const VoxelIndex&, float) { ++reference_free; });
  EXPECT_EQ(occupied, reference_occupied);
  EXPECT_EQ(free, reference_free);
  EXPECT_GT(occupied, 0u);
  EXPECT_GT(free, 0u);

  // Blocks: forEachBlock, copyBlock and copyBlocks.
  const std::map<Key, VoxelBlock> blocks = allBlocks(reference);
  const std::map<Key, VoxelBlock> read_blocks = allBlocks(map);
  ASSERT_EQ(read_blocks.size(), blocks.size());
  std::map<Key, VoxelBlock> copied;
  for (const auto& [index, block] : map.copyBlocks()) copied.emplace(asKey(index), block);
  ASSERT_EQ(copied.size(), blocks.size());
  for (const auto& [key, block] : blocks) {
    const auto [x, y, z] = key;
    EXPECT_TRUE(sameVoxels(read_blocks.at(key), block)) << x << " " << y << " " << z;
    EXPECT_TRUE(sameVoxels(copied.at(key), block)) << x << " " << y << " " << z;
    VoxelBlock one;
    ASSERT_TRUE(map.copyBlock({x, y, z}, &one));
    EXPECT_TRUE(sameVoxels(one, block)) << x << " " << y << " " << z;
  }

  // Boxes, small (blocks looked up) around a known voxel, and larger than the map (blocks walked).
  const double edge = reference.resolution() * VoxelBlock::kSide;
  const auto [x, y, z] = std::next(known.begin(), known.size() / 2)->first;
  const Eigen::Vector3d middle = reference.centerOf({x, y, z});
  const Eigen::Vector3d half_box(1.3 * edge, 0.9 * edge, 0.6 * edge);
  const std::pair<Eigen::Vector3d, Eigen::Vector3d> boxes[] = {
      {middle - half_box, middle + half_box}, {{-100.0, -100.0, -100.0}, {100.0, 100.0, 100.0}}};
  for (const auto& [lo, hi] : boxes) {
    VoxelValues in_box, reference_in_box;
    map.forEachKnownVoxelInBox(lo, hi, [&](const VoxelIndex& i, float v) { in_box[asKey(i)] = v; });
    reference.forEachKnownVoxelInBox(
        lo, hi, [&](const VoxelIndex& i, float v) { reference_in_box[asKey(i)] = v; });
    EXPECT_EQ(in_box, reference_in_box);
    EXPECT_FALSE(in_box.empty());
    const VoxelCounts counts = map.countInBox(lo, hi);
    const VoxelCounts reference_counts = reference.countInBox(lo, hi);
    EXPECT_EQ(counts.occupied, reference_counts.occupied);
    EXPECT_EQ(counts.free, reference_counts.free);
    EXPECT_EQ(counts.unknown, reference_counts.unknown);
  }

  // Saved files, byte for byte.
  writeBt(map, folder + "/bounded.bt");
  writeBt(reference, folder + "/unbounded.bt");
  writeOt(map, folder + "/bounded.ot");
  writeOt(reference, folder + "/unbounded.ot");
  const std::string bt = readAll(folder + "/bounded.bt");
  EXPECT_GT(bt.size(), 1000u);
  EXPECT_TRUE(bt == readAll(folder + "/unbounded.bt"));
  const std::string ot = readAll(folder + "/bounded.ot");
  EXPECT_GT(ot.size(), 1000u);
  EXPECT_TRUE(ot == readAll(folder + "/unbounded.ot"));
}

void randomWritesReadAsUnbounded(BlockStorage storage, const std::string& folder) {
  VoxelMapConfig unbounded_config = boundedConfig(storage, "");
  unbounded_config.max_memory_bytes = 0;
  VoxelMap unbounded(unbounded_config);
  VoxelMap bounded(boundedConfig(storage, folder + "/spill"));
  const double edge = bounded.resolution() * VoxelBlock::kSide;
  RandomFrames frames(storage == BlockStorage::kDense ? 1 : 2);
  FusedGridView view;  // kept up to date from the change log, as the MapServer's
  for (int frame = 0; frame < 400; ++frame) {
    const Eigen::Vector3d focus = frames.nextFocus(edge);
    for (VoxelMap* map : {&bounded, &unbounded}) map->setFocus(focus);
    frames.write(&bounded, &unbounded);
    if (frame == 250) {
      // clear_bbx over blocks in memory and spilled ones.
      const Eigen::Vector3d lo(2.0 * edge, 2.0 * edge, 0.0), hi(20.5 * edge, 9.5 * edge, edge);
      ASSERT_EQ(bounded.clearBox(lo, hi), unbounded.clearBox(lo, hi));
    }
    // Within the bound after every write; what is not in memory is in the store.
    const VoxelMap::StorageStats stats = bounded.storageStats();
    ASSERT_LE(stats.block_bytes + stats.table_bytes, bounded.config().max_memory_bytes);
    ASSERT_EQ(stats.dense_blocks + stats.sparse_blocks + stats.spilled_blocks,
              unbounded.blockCount());
    if (frame % 50 == 0) {
      const OccupancyRaster incremental = view.update(bounded, nullptr);
      const OccupancyRaster reference = projectToRaster(unbounded, nullptr, FusedGridConfig());
      ASSERT_EQ(incremental.width, reference.width) << "frame " << frame;
      ASSERT_EQ(incremental.data, reference.data) << "frame " << frame;
    }
  }
  const SpillStatus status = bounded.spillStatus();
  EXPECT_TRUE(status.enabled);
  EXPECT_EQ(status.failures, 0u) << status.last_error;
  EXPECT_EQ(bounded.evictedBlockCount(), 0u);
  // Most of the map is on disk, and blocks went back and forth many times.
  EXPECT_GT(status.spilled_blocks, unbounded.blockCount() * 3 / 4);
  EXPECT_GT(status.blocks_paged_in, 500u);
  EXPECT_GT(status.blocks_written, status.blocks_paged_in);
  EXPECT_GT(unbounded.blockCount(), 10 * kBoundBlocks);
  // Spilling is no change: no block was ever reported removed to consumers that followed along.
  const MapChanges changes = bounded.changesSince(2);
  ASSERT_FALSE(changes.full_rebuild);
  EXPECT_TRUE(changes.removed.empty());

  expectSameReads(bounded, unbounded, folder);
}

TEST_F(VoxelMapSpill, DenseRandomWritesReadAsInAnUnboundedMap) {
  randomWritesReadAsUnbounded(BlockStorage::kDense, folder_.string());
}

TEST_F(VoxelMapSpill, HybridRandomWritesReadAsInAnUnboundedMap) {
  randomWritesReadAsUnbounded(BlockStorage::kHybrid, folder_.string());
}

// Readers in parallel with a writer that spills and pages in: every read of a block the writer
// does not touch gives the value written before, wherever the block is at that moment.
TEST_F(VoxelMapSpill, ReadersInParallelWithASpillingWriterReadRight) {
  VoxelMap map(boundedConfig(BlockStorage::kDense, path("spill")));
  const double edge = map.resolution() * VoxelBlock::kSide;
  // Row y = 0 of blocks, one known voxel each, written once: its value encodes its block.
  constexpr int kFixedBlocks = 200;
  auto fixed_voxel = [](int x) { return VoxelMap::voxelIndex({x, 0, 0}, 5); };
  for (int x = 0; x < kFixedBlocks; ++x) {
    map.setFocus(Eigen::Vector3d((x + 0.5) * edge, 0.0, 0.0));
    map.setLogOdds(fixed_voxel(x), 0.01f * static_cast<float>(x));
  }
  ASSERT_GT(map.spillStatus().spilled_blocks, kFixedBlocks / 2);

  std::atomic<bool> writing{true};
  std::atomic<std::size_t> reads{0}, wrong{0};
  auto reader = [&](unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> block(0, kFixedBlocks - 1);
    while (writing) {
      const int x = block(rng);
      const std::optional<float> value = map.logOdds(fixed_voxel(x));
      if (!value || *value != 0.01f * static_cast<float>(x)) ++wrong;
      VoxelBlock copy;
      if (!map.copyBlock({x, 0, 0}, &copy) || copy.known_count != 1) ++wrong;
      reads += 2;
      // The map's shared_mutex lets readers in ahead of a waiting writer: leave it gaps.
      std::this_thread::sleep_for(std::chrono::microseconds(50));
    }
  };
  std::vector<std::thread> readers;
  for (unsigned i = 0; i < 3; ++i) readers.emplace_back(reader, i);
  // The writer walks rows y = 2 .. 4 back and forth: its blocks go to the store and come back,
  // and so do the fixed ones, as the focus moves.
  std::mt19937 rng(4);
  std::uniform_int_distribution<int> voxel(0, VoxelBlock::kVolume - 1);
  for (int frame = 0; frame < 2000; ++frame) {
    const int x = frame % 400 < 200 ? frame % 200 : 199 - frame % 200;
    map.setFocus(Eigen::Vector3d((x + 0.5) * edge, 3.5 * edge, 0.0));
    std::vector<VoxelUpdate> updates;
    for (int y = 2; y <= 4; ++y) {
      updates.push_back({VoxelMap::voxelIndex({x, y, 0}, voxel(rng)), 0.4f});
    }
    map.applyUpdates(updates);
  }
  writing = false;
  for (std::thread& thread : readers) thread.join();
  EXPECT_GT(reads.load(), 100u);
  EXPECT_EQ(wrong.load(), 0u);
  EXPECT_GT(map.spillStatus().blocks_paged_in, 100u);
  EXPECT_EQ(map.spillStatus().failures, 0u);
  std::size_t fixed_known = 0;
  map.forEachKnownVoxelInBox(Eigen::Vector3d(0, 0, 0),
                             Eigen::Vector3d(kFixedBlocks * edge, 0.5 * edge, 0.5 * edge),
                             [&](const VoxelIndex&, float) { ++fixed_known; });
  EXPECT_EQ(fixed_known, static_cast<std::size_t>(kFixedBlocks));
}

// Two writers on the same blocks, each bringing spilled blocks back and spilling others: a
// block read from the store before its writer's exclusive lock may have been paged in, written
// and spilled again by the other writer meanwhile; that copy must not be taken (a write would be
// lost). Every write adds 0.25 (exact in float, no clamping), so the result does not depend on
// the order.
TEST_F(VoxelMapSpill, WritersReadingAheadOfTheLockLoseNoWrite) {
  VoxelMap map(boundedConfig(BlockStorage::kDense, path("store")));
  constexpr int kSide = 12;  // 144 blocks, the bound holds 40
  constexpr int kCalls = 400;
  std::vector<std::atomic<int>> writes(kSide * kSide);
  auto writer = [&](unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> coordinate(0, kSide - 1);
    for (int call = 0; call < kCalls; ++call) {
      std::vector<BlockIndex> blocks;
      for (int i = 0; i < 6; ++i) {
        const BlockIndex block(coordinate(rng), coordinate(rng), 0);
        if (std::find(blocks.begin(), blocks.end(), block) == blocks.end()) blocks.push_back(block);
      }
      // The focus follows this writer's blocks: the other writer's recent blocks leave memory.
      map.setFocus(((blocks.front().cast<double>().array() + 0.5) * 0.8).matrix());
      map.updateBlocks(blocks, [](const BlockIndex&, VoxelBlock& voxels) {
        voxels.update(0, 0.25f, -100.0f, 100.0f);
      });
      for (const BlockIndex& block : blocks) ++writes[block.y() * kSide + block.x()];
    }
  };
  std::thread first(writer, 1u), second(writer, 2u);
  first.join();
  second.join();
  const SpillStatus status = map.spillStatus();
  ASSERT_TRUE(status.enabled) << status.last_error;
  EXPECT_EQ(status.failures, 0u) << status.last_error;
  EXPECT_GT(status.blocks_read_ahead, 100u);
  EXPECT_GT(map.spillStatus().spilled_blocks, 50u);
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      const int n = writes[y * kSide + x];
      if (n == 0) continue;
      const std::optional<float> value = map.logOdds(BlockIndex(x, y, 0) * VoxelBlock::kSide);
      ASSERT_TRUE(value.has_value()) << x << " " << y;
      EXPECT_EQ(*value, 0.25f * n) << "block " << x << " " << y;
    }
  }
  std::printf("read ahead %zu, read again under the lock %zu\n", status.blocks_read_ahead,
              status.blocks_read_under_lock);
}

// A store that fills up: the blocks that no longer fit are dropped as without a store, the map
// stays within its bound, nothing throws, and the status says what happened and where.
TEST_F(VoxelMapSpill, FullStoreFallsBackToDroppingBlocksObservably) {
  VoxelMapConfig config = boundedConfig(BlockStorage::kDense, path("spill"));
  // About 120 full blocks: a full block (2 KiB and its brick mask) is a little too large for an
  // LMDB leaf page of 4 KiB, and takes an overflow page of its own.
  config.spill_max_bytes = 512 << 10;
  VoxelMap map(config);
  VoxelMapConfig unbounded_config = config;
  unbounded_config.max_memory_bytes = 0;
  VoxelMap unbounded(unbounded_config);
  const double edge = map.resolution() * VoxelBlock::kSide;
  // Each block is written once, full: along +x, a column of 4 blocks per frame.
  for (int x = 0; x < 120; ++x) {
    std::vector<BlockIndex> blocks;
    for (int y = 0; y < 4; ++y) blocks.push_back({x, y, 0});
    auto fill = [](const BlockIndex& block, VoxelBlock& voxels) {
      for (int i = 0; i < VoxelBlock::kVolume; ++i) {
        voxels.update(i, 0.1f * static_cast<float>((block.x() + block.y() + i) % 30 - 10), -2.0f,
                      3.5f);
      }
    };
    for (VoxelMap* m : {&map, &unbounded}) {
      m->setFocus(Eigen::Vector3d((x + 0.5) * edge, 2.0 * edge, 0.5 * edge));
      ASSERT_NO_THROW(m->updateBlocks(blocks, fill));
    }
    const VoxelMap::StorageStats stats = map.storageStats();
    ASSERT_LE(stats.block_bytes + stats.table_bytes, config.max_memory_bytes);
  }
  const SpillStatus status = map.spillStatus();
  EXPECT_GT(status.failures, 0u);
  EXPECT_NE(status.last_error.find(path("spill")), std::string::npos) << status.last_error;
  EXPECT_NE(status.last_error.find("full"), std::string::npos) << status.last_error;
  EXPECT_GT(status.spilled_blocks, 50u);
  EXPECT_GT(map.evictedBlockCount(), 100u);
  // Every block is spilled, in memory or dropped; those kept read as written.
  EXPECT_EQ(map.blockCount() + map.evictedBlockCount(), unbounded.blockCount());
  const std::map<Key, VoxelBlock> kept = allBlocks(map);
  const std::map<Key, VoxelBlock> written = allBlocks(unbounded);
  EXPECT_EQ(kept.size(), map.blockCount());
  for (const auto& [key, block] : kept) EXPECT_TRUE(sameVoxels(block, written.at(key)));
  // Dropped blocks are reported removed, as evicted blocks always were.
  EXPECT_EQ(map.changesSince(2).removed.size(), map.evictedBlockCount());
}

// reset() forgets the spilled blocks too: a later write starts from unknown, not from them.
TEST_F(VoxelMapSpill, ResetForgetsSpilledBlocks) {
  VoxelMap map(boundedConfig(BlockStorage::kDense, path("spill")));
  const double edge = map.resolution() * VoxelBlock::kSide;
  for (int x = 0; x < 100; ++x) {
    map.setFocus(Eigen::Vector3d((x + 0.5) * edge, 0.0, 0.0));
    map.updateVoxel(VoxelMap::voxelIndex({x, 0, 0}, 0), 1.0f);
  }
  ASSERT_GT(map.spillStatus().spilled_blocks, 50u);
  map.reset();
  EXPECT_EQ(map.blockCount(), 0u);
  EXPECT_EQ(map.knownVoxelCount(), 0u);
  EXPECT_EQ(map.spillStatus().spilled_blocks, 0u);
  EXPECT_FALSE(map.logOdds(VoxelMap::voxelIndex({0, 0, 0}, 0)).has_value());
  map.updateVoxel(VoxelMap::voxelIndex({0, 0, 0}, 0), 0.5f);
  EXPECT_EQ(map.logOdds(VoxelMap::voxelIndex({0, 0, 0}, 0)), 0.5f);
  std::size_t blocks = 0;
  map.forEachBlock([&](const BlockIndex&, const VoxelBlock&) { ++blocks; });
  EXPECT_EQ(blocks, 1u);
}

TEST_F(VoxelMapSpill, BadStoresAreRefusedNamingTheFolderAndTheMapEvictsInstead) {
  const std::string folder = path("spill");
  // The store refused: the map says why, naming the folder, and goes on with the bound's
  // eviction (blocks beyond it dropped, counted).
  auto expectRefused = [](const VoxelMapConfig& config, const std::string& words) {
    VoxelMap map(config);
    const SpillStatus status = map.spillStatus();
    EXPECT_FALSE(status.enabled);
    EXPECT_EQ(status.folder, config.spill_folder);
    EXPECT_EQ(status.failures, 1u);
    EXPECT_NE(status.last_error.find(config.spill_folder), std::string::npos) << status.last_error;
    EXPECT_NE(status.last_error.find(words), std::string::npos) << status.last_error;
    for (int x = 0; x < 200; ++x) {
      map.setFocus(Eigen::Vector3d(x * 0.8, 0.0, 0.0));
      map.updateVoxel(map.indexOf(Eigen::Vector3d(x * 0.8, 0.0, 0.0)), 1.0f);
    }
    EXPECT_GT(map.evictedBlockCount(), 0u);
    EXPECT_EQ(map.spillStatus().spilled_blocks, 0u);
  };
  { VoxelMap map(boundedConfig(BlockStorage::kDense, folder)); }  // resolution 0.1
  VoxelMapConfig other_resolution = boundedConfig(BlockStorage::kDense, folder);
  other_resolution.resolution = 0.05;
  expectRefused(other_resolution, "resolution 0.1 m");

  std::ofstream(path("file")) << "not a folder";
  expectRefused(boundedConfig(BlockStorage::kDense, path("file") + "/spill"), "cannot create");

  const std::string damaged = path("damaged");
  std::filesystem::create_directories(damaged);
  std::ofstream(damaged + "/data.mdb") << std::string(20000, 'x');
  expectRefused(boundedConfig(BlockStorage::kDense, damaged), "damaged");

  // Without a memory bound nothing is spilled, and no store is made.
  VoxelMapConfig unbounded = boundedConfig(BlockStorage::kDense, path("unused"));
  unbounded.max_memory_bytes = 0;
  VoxelMap map(unbounded);
  EXPECT_FALSE(map.spillStatus().enabled);
  EXPECT_FALSE(std::filesystem::exists(path("unused")));
}

}  // namespace
}  // namespace occupancy_fusion
