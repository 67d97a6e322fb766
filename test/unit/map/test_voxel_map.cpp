#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>
#include <tuple>
#include <vector>

#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {
namespace {

VoxelMapConfig defaultConfig(double resolution = 0.1) {
  VoxelMapConfig config;
  config.resolution = resolution;
  return config;
}

TEST(OccupancyModel, DefaultsAreOctoMaps) {
  const OccupancyModel model;
  EXPECT_NEAR(model.hitLogOdds(), std::log(0.7 / 0.3), 1e-6);
  EXPECT_NEAR(model.missLogOdds(), std::log(0.4 / 0.6), 1e-6);
  EXPECT_NEAR(model.minLogOdds(), -1.99993, 1e-4);  // logit(0.1192)
  EXPECT_NEAR(model.maxLogOdds(), 3.51103, 1e-4);   // logit(0.971)
  EXPECT_FLOAT_EQ(model.thresholdLogOdds(), 0.0f);
}

TEST(OccupancyModel, RejectsBadProbabilitiesNamingTheField) {
  auto message_of = [](const OccupancyModel& model) {
    try {
      model.validate();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  OccupancyModel model;
  model.prob_hit = 1.2;
  EXPECT_NE(message_of(model).find("sensor_model/hit"), std::string::npos);
  model = OccupancyModel();
  model.prob_miss = 0.6;
  EXPECT_NE(message_of(model).find("sensor_model/miss"), std::string::npos);
  model = OccupancyModel();
  model.clamp_min = 0.99;
  EXPECT_NE(message_of(model).find("sensor_model/min"), std::string::npos);
  model = OccupancyModel();
  model.occupancy_threshold = std::nan("");
  EXPECT_NE(message_of(model).find("occupancy_threshold"), std::string::npos);
  EXPECT_EQ(message_of(OccupancyModel()), "");
}

TEST(VoxelMapConfig, RejectsNonPositiveResolution) {
  VoxelMapConfig config;
  config.resolution = -0.1;
  EXPECT_THROW(VoxelMap map(config), std::invalid_argument);
  config.resolution = 0.0;
  EXPECT_THROW(VoxelMap map(config), std::invalid_argument);
  config.resolution = std::numeric_limits<double>::infinity();
  EXPECT_THROW(VoxelMap map(config), std::invalid_argument);
}

TEST(VoxelMap, IndexingFloorsAndCentresAreHalfwayIncludingNegatives) {
  VoxelMap map(defaultConfig(0.1));
  EXPECT_EQ(map.indexOf({0.05, 0.0, 0.0999}), VoxelIndex(0, 0, 0));
  EXPECT_EQ(map.indexOf({-0.01, -0.1, -0.1001}), VoxelIndex(-1, -1, -2));
  EXPECT_TRUE(map.centerOf({-1, 2, 0}).isApprox(Eigen::Vector3d(-0.05, 0.25, 0.05)));
  EXPECT_EQ(VoxelMap::blockOf({-1, 7, 8}), BlockIndex(-1, 0, 1));
  EXPECT_EQ(VoxelMap::blockOf({-8, -9, 15}), BlockIndex(-1, -2, 1));
  // linear index and back
  for (const VoxelIndex& index : {VoxelIndex(-1, 7, 8), VoxelIndex(-17, 3, 100)}) {
    EXPECT_EQ(VoxelMap::voxelIndex(VoxelMap::blockOf(index), VoxelMap::linearIndexInBlock(index)),
              index);
  }
  EXPECT_FALSE(map.isInRange({std::nan(""), 0, 0}));
  EXPECT_FALSE(map.isInRange({1e9, 0, 0}));
  EXPECT_TRUE(map.isInRange({-1000, 20, 3}));
}

// The keys of many points at once equal packKey of each floored point, also at integers, just
// below and above them, at halves (which round to even on the way), for negatives and at the
// key range's ends; non-finite and huge coordinates give some key without a fault.
TEST(SpatialKey, PackFlooredKeysEqualsFlooringAndPackingEachPoint) {
  std::vector<double> values = {0.0,       -0.0,       0.5,         1.5,         2.5, -0.5,
                                -1.5,      -2.5,       1e-300,      -1e-300,     7.0, -7.0,
                                1048575.0, -1048576.0, 0.999999999, -0.999999999};
  for (const double integer : {3.0, -3.0, 1000.0, -1000.0, 1048575.0, -1048575.0}) {
    values.push_back(std::nextafter(integer, -1e9));
    values.push_back(std::nextafter(integer, 1e9));
  }
  std::mt19937 random(5);
  std::uniform_real_distribution<double> uniform(-1048576.0, 1048575.0);
  while (values.size() < 4000) values.push_back(uniform(random));
  const std::size_t count = values.size();  // even
  std::vector<double> x(count), y(count), z(count);
  for (std::size_t k = 0; k < count; ++k) {
    x[k] = values[k];
    y[k] = values[(k * 7 + 3) % count];
    z[k] = values[(k * 13 + 5) % count];
  }
  std::vector<std::uint64_t> keys(count);
  packFlooredKeys(x.data(), y.data(), z.data(), static_cast<int>(count), keys.data());
  for (std::size_t k = 0; k < count; ++k) {
    const VoxelIndex floored(static_cast<int>(std::floor(x[k])), static_cast<int>(std::floor(y[k])),
                             static_cast<int>(std::floor(z[k])));
    ASSERT_EQ(keys[k], packKey(floored)) << x[k] << " " << y[k] << " " << z[k];
  }
  const double inf = std::numeric_limits<double>::infinity();
  const double bad_x[2] = {std::nan(""), inf}, bad_y[2] = {-inf, 1e300}, bad_z[2] = {1e17, -1e60};
  std::uint64_t bad_keys[2];
  packFlooredKeys(bad_x, bad_y, bad_z, 2, bad_keys);  // no fault; the keys mean nothing
}

TEST(VoxelMap, UnknownIsNotFreeAndUpdatesAccumulateWithClamping) {
  VoxelMap map(defaultConfig());
  const VoxelIndex index(3, -4, 5);
  EXPECT_FALSE(map.logOdds(index).has_value());
  EXPECT_EQ(map.occupancy(index), Occupancy::kUnknown);

  const float hit = map.model().hitLogOdds();
  const float miss = map.model().missLogOdds();
  map.updateVoxel(index, miss);
  EXPECT_FLOAT_EQ(*map.logOdds(index), miss);  // first update starts at the prior 0
  EXPECT_EQ(map.occupancy(index), Occupancy::kFree);
  map.updateVoxel(index, hit);
  map.updateVoxel(index, hit);
  EXPECT_NEAR(*map.logOdds(index), miss + 2 * hit, 1e-6);
  EXPECT_EQ(map.occupancy(index), Occupancy::kOccupied);
  for (int i = 0; i < 20; ++i) map.updateVoxel(index, hit);
  EXPECT_FLOAT_EQ(*map.logOdds(index), map.maxLogOdds());
  for (int i = 0; i < 40; ++i) map.updateVoxel(index, miss);
  EXPECT_FLOAT_EQ(*map.logOdds(index), map.minLogOdds());
  // the neighbour in the same block is still unknown
  EXPECT_EQ(map.occupancy(index + VoxelIndex(1, 0, 0)), Occupancy::kUnknown);
  EXPECT_EQ(map.knownVoxelCount(), 1u);
}

// The depth mapper's skip of no-op updates and its clearing read which voxels sit at the lower
// clamping bound and which are occupied, dense and sparse (hybrid) blocks alike; absent blocks
// give empty masks.
TEST(VoxelMap, VoxelStatesAreMaskedPerBlock) {
  for (BlockStorage storage : {BlockStorage::kDense, BlockStorage::kHybrid}) {
    VoxelMapConfig config = defaultConfig();
    config.block_storage = storage;
    VoxelMap map(config);
    const float miss = map.model().missLogOdds();
    const VoxelIndex clamped(1, 2, 3), nearly(2, 2, 3), occupied(3, 2, 3), elsewhere(9, 0, 0);
    for (int i = 0; i < 40; ++i) map.updateVoxel(clamped, miss);
    map.updateVoxel(nearly, miss);
    map.updateVoxel(occupied, map.model().hitLogOdds());
    for (int i = 0; i < 40; ++i) map.updateVoxel(elsewhere, miss);
    const std::vector<VoxelMap::VoxelStates> states =
        map.voxelStates({VoxelMap::blockOf(clamped), BlockIndex(5, 5, 5)});
    ASSERT_EQ(states.size(), 2u);
    EXPECT_EQ(states[0].at_lower_bound.count(), 1u);
    EXPECT_TRUE(states[0].at_lower_bound.test(VoxelMap::linearIndexInBlock(clamped)));
    EXPECT_EQ(states[0].occupied.count(), 1u);
    EXPECT_TRUE(states[0].occupied.test(VoxelMap::linearIndexInBlock(occupied)));
    EXPECT_TRUE(states[1].at_lower_bound.none() && states[1].occupied.none());
  }
}

TEST(VoxelMap, BatchUpdatesEqualSingleUpdates) {
  VoxelMap batch(defaultConfig());
  VoxelMap single(defaultConfig());
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coordinate(-20, 20);
  std::uniform_real_distribution<float> delta(-1.0f, 1.0f);
  std::vector<VoxelUpdate> updates;
  for (int i = 0; i < 5000; ++i) {
    updates.push_back({{coordinate(rng), coordinate(rng), coordinate(rng)}, delta(rng)});
  }
  batch.applyUpdates(updates);
  for (const VoxelUpdate& update : updates) single.updateVoxel(update.index, update.delta);
  std::size_t compared = 0;
  batch.forEachKnownVoxel([&](const VoxelIndex& index, float value) {
    ASSERT_TRUE(single.logOdds(index).has_value());
    EXPECT_FLOAT_EQ(*single.logOdds(index), value);
    ++compared;
  });
  EXPECT_EQ(compared, single.knownVoxelCount());
  EXPECT_GT(compared, 3000u);
}

TEST(VoxelMap, IterationSplitsOccupiedAndFree) {
  VoxelMap map(defaultConfig());
  std::set<std::tuple<int, int, int>> occupied, free;
  for (int i = 0; i < 30; ++i) {
    const VoxelIndex index(i * 3 - 40, i % 5, -i);
    const bool is_occupied = i % 3 == 0;
    map.updateVoxel(index, is_occupied ? 0.85f : -0.4f);
    (is_occupied ? occupied : free).insert({index.x(), index.y(), index.z()});
  }
  std::set<std::tuple<int, int, int>> seen_occupied, seen_free;
  map.forEachOccupiedVoxel([&](const VoxelIndex& i, float value) {
    EXPECT_GT(value, 0.0f);
    seen_occupied.insert({i.x(), i.y(), i.z()});
  });
  map.forEachFreeVoxel([&](const VoxelIndex& i, float value) {
    EXPECT_LE(value, 0.0f);
    seen_free.insert({i.x(), i.y(), i.z()});
  });
  EXPECT_EQ(seen_occupied, occupied);
  EXPECT_EQ(seen_free, free);
}

TEST(VoxelMap, CopyBlocksIsASnapshotUnaffectedByLaterWrites) {
  VoxelMap map(defaultConfig());
  std::map<std::tuple<int, int, int>, float> written;
  for (int i = 0; i < 40; ++i) {
    const VoxelIndex index(i * 5 - 90, (i * 7) % 23 - 11, 3 - i);
    const float delta = i % 2 ? 0.85f : -0.4f;
    map.updateVoxel(index, delta);
    written[{index.x(), index.y(), index.z()}] = delta;
  }
  const std::vector<VoxelMap::BlockCopy> copies = map.copyBlocks();
  map.updateVoxel(VoxelIndex(-90, -11, 3), 0.85f);  // after the copy: not in it
  map.updateVoxel(VoxelIndex(500, 500, 500), 0.85f);
  EXPECT_EQ(copies.size() + 1, map.blockCount());
  std::map<std::tuple<int, int, int>, float> copied;
  for (const auto& [block_index, block] : copies) {
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
      if (!VoxelBlock::isKnown(block.log_odds[linear])) continue;
      const VoxelIndex index = VoxelMap::voxelIndex(block_index, linear);
      copied[{index.x(), index.y(), index.z()}] = block.log_odds[linear];
    }
  }
  EXPECT_EQ(copied, written);
}

TEST(VoxelMap, BoxQueryCountsAndClearBox) {
  VoxelMap map(defaultConfig(0.1));
  // A 10 x 10 x 10 cube of occupied voxels at indices 0..9 (centres 0.05 .. 0.95).
  std::vector<VoxelUpdate> updates;
  for (int z = 0; z < 10; ++z)
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 10; ++x) updates.push_back({{x, y, z}, 2.0f});
  map.applyUpdates(updates);
  // Box [0.2, 0.5] holds centres 0.25, 0.35, 0.45 per axis: 27 voxels.
  const VoxelCounts inner = map.countInBox({0.2, 0.2, 0.2}, {0.5, 0.5, 0.5});
  EXPECT_EQ(inner.occupied, 27u);
  EXPECT_EQ(inner.free, 0u);
  EXPECT_EQ(inner.unknown, 0u);
  // A box reaching outside the cube: centres -0.05 .. 0.15 (3 per axis), 8 known.
  const VoxelCounts edge = map.countInBox({-0.1, -0.1, -0.1}, {0.2, 0.2, 0.2});
  EXPECT_EQ(edge.occupied, 8u);
  EXPECT_EQ(edge.unknown, 27u - 8u);

  EXPECT_EQ(map.clearBox({0.2, 0.2, 0.2}, {0.5, 0.5, 0.5}), 27u);
  EXPECT_EQ(map.occupancy({3, 3, 3}), Occupancy::kFree);
  EXPECT_FLOAT_EQ(*map.logOdds({3, 3, 3}), map.minLogOdds());
  EXPECT_EQ(map.occupancy({1, 3, 3}), Occupancy::kOccupied);
  // clear_bbx never creates knowledge
  EXPECT_EQ(map.clearBox({5, 5, 5}, {6, 6, 6}), 0u);
  EXPECT_EQ(map.knownVoxelCount(), 1000u);

  map.reset();
  EXPECT_EQ(map.knownVoxelCount(), 0u);
  EXPECT_EQ(map.blockCount(), 0u);
  EXPECT_EQ(map.occupancy({3, 3, 3}), Occupancy::kUnknown);
}

TEST(VoxelMap, UpdateBlocksRunsOncePerBlockAndAllocatesThem) {
  VoxelMap map(defaultConfig());
  std::vector<BlockIndex> blocks;
  for (int i = -20; i < 20; ++i) blocks.push_back({i, -i, i % 3});
  std::atomic<int> calls{0};
  map.updateBlocks(blocks, [&](const BlockIndex& block, VoxelBlock& data) {
    ++calls;
    data.update(VoxelBlock::linearIndex(1, 2, 3), 1.0f, map.minLogOdds(), map.maxLogOdds());
    (void)block;
  });
  EXPECT_EQ(calls.load(), 40);
  EXPECT_EQ(map.blockCount(), 40u);
  for (const BlockIndex& block : blocks) {
    const VoxelIndex index = block * VoxelBlock::kSide + VoxelIndex(1, 2, 3);
    EXPECT_FLOAT_EQ(*map.logOdds(index), 1.0f);
  }
}

TEST(VoxelMap, MemoryAccountingGrowsWithBlocks) {
  VoxelMapConfig config = defaultConfig();
  config.block_storage = BlockStorage::kDense;  // sparse blocks: test_voxel_map_storage.cpp
  VoxelMap map(config);
  map.updateVoxel({0, 0, 0}, 1.0f);
  const std::size_t one_block = map.memoryBytes();
  EXPECT_GE(one_block, sizeof(VoxelBlock));
  for (int i = 1; i < 100; ++i) map.updateVoxel({i * VoxelBlock::kSide, 0, 0}, 1.0f);
  EXPECT_EQ(map.blockCount(), 100u);
  EXPECT_GE(map.memoryBytes(), 100 * sizeof(VoxelBlock));
  EXPECT_LT(map.memoryBytes(), 100 * sizeof(VoxelBlock) + (1u << 16));
}

TEST(VoxelMap, MemoryBoundEvictsBlocksFarthestFromTheFocus) {
  VoxelMapConfig config = defaultConfig(0.1);
  config.block_storage = BlockStorage::kDense;  // in units of dense blocks
  config.max_memory_bytes = 60 * sizeof(VoxelBlock);
  VoxelMap map(config);
  map.setFocus({0.0, 0.0, 0.0});
  // 100 blocks in a row along +x: block i at distance ~ i blocks from the focus.
  for (int i = 0; i < 100; ++i) map.updateVoxel({i * VoxelBlock::kSide, 0, 0}, 1.0f);
  EXPECT_GT(map.evictedBlockCount(), 0u);
  EXPECT_LT(map.blockCount(), 60u);
  EXPECT_EQ(map.blockCount() + map.evictedBlockCount(), 100u);
  // Each eviction dropped the farthest blocks, so the nearest ones all survive and everything
  // that was dropped lies beyond them.
  int nearest_kept = 0;
  while (map.occupancy({nearest_kept * VoxelBlock::kSide, 0, 0}) == Occupancy::kOccupied) {
    ++nearest_kept;
  }
  EXPECT_GE(nearest_kept, 45);
  EXPECT_EQ(map.occupancy({60 * VoxelBlock::kSide, 0, 0}), Occupancy::kUnknown);
  // The map keeps working after eviction.
  map.setFocus({80.0 * VoxelBlock::kSide * 0.1, 0.0, 0.0});
  map.updateVoxel({81 * VoxelBlock::kSide, 0, 0}, 1.0f);
  EXPECT_EQ(map.occupancy({81 * VoxelBlock::kSide, 0, 0}), Occupancy::kOccupied);
}

TEST(VoxelMap, ChangeLogReportsWrittenAndRemovedBlocks) {
  VoxelMap map(defaultConfig());
  MapChanges first = map.changesSince(0);
  EXPECT_TRUE(first.full_rebuild);
  map.updateVoxel({0, 0, 0}, 1.0f);
  map.updateVoxel({100, 0, 0}, 1.0f);
  MapChanges changes = map.changesSince(first.version);
  EXPECT_FALSE(changes.full_rebuild);
  ASSERT_EQ(changes.changed.size(), 2u);
  EXPECT_EQ(changes.changed[0], BlockIndex(0, 0, 0));
  EXPECT_EQ(changes.changed[1], BlockIndex(12, 0, 0));
  // Nothing new since.
  MapChanges none = map.changesSince(changes.version);
  EXPECT_TRUE(none.changed.empty());
  EXPECT_TRUE(none.removed.empty());
  // One write touching many voxels of one block logs it once.
  std::vector<VoxelUpdate> updates;
  for (int x = 0; x < 8; ++x) updates.push_back({{x, 1, 1}, 0.5f});
  map.applyUpdates(updates);
  MapChanges batch = map.changesSince(none.version);
  EXPECT_EQ(batch.changed.size(), 1u);
  // A reset forces consumers to rebuild.
  map.reset();
  EXPECT_TRUE(map.changesSince(batch.version).full_rebuild);
}

TEST(VoxelMap, EvictionIsReportedAsRemoval) {
  VoxelMapConfig config = defaultConfig(0.1);
  config.block_storage = BlockStorage::kDense;  // in units of dense blocks
  config.max_memory_bytes = 20 * sizeof(VoxelBlock);
  VoxelMap map(config);
  const std::uint64_t start = map.changesSince(0).version;
  for (int i = 0; i < 40; ++i) map.updateVoxel({i * VoxelBlock::kSide, 0, 0}, 1.0f);
  const MapChanges changes = map.changesSince(start);
  EXPECT_EQ(changes.removed.size(), map.evictedBlockCount());
  EXPECT_GT(changes.removed.size(), 0u);
}

TEST(VoxelMap, ConcurrentWritersAndReadersKeepEveryUpdate) {
  VoxelMap map(defaultConfig());
  constexpr int kWriters = 4;
  constexpr int kUpdatesPerWriter = 2000;
  std::atomic<bool> done{false};
  std::thread reader([&] {
    while (!done) {
      std::size_t seen = 0;
      map.forEachKnownVoxel([&](const VoxelIndex&, float) { ++seen; });
      EXPECT_LE(seen, static_cast<std::size_t>(kWriters));
    }
  });
  std::vector<std::thread> writers;
  for (int w = 0; w < kWriters; ++w) {
    writers.emplace_back([&map, w] {
      for (int i = 0; i < kUpdatesPerWriter; ++i) map.updateVoxel({w, 0, 0}, 0.001f);
    });
  }
  for (auto& writer : writers) writer.join();
  done = true;
  reader.join();
  for (int w = 0; w < kWriters; ++w) EXPECT_NEAR(*map.logOdds({w, 0, 0}), 2.0f, 1e-3);
}

}  // namespace
}  // namespace occupancy_fusion
