// Hybrid block storage (VoxelMap, "Block storage"; stored_block.h): a block kept sparse, as its
// non-empty 2^3 bricks, must read exactly as the dense block it stands for, through every read
// function of the map, and cost what its bricks cost.
#include <gtest/gtest.h>

#include <octomap/OcTree.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/map/octomap_conversion.h"
#include "occupancy_fusion/map/stored_block.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {
namespace {

VoxelMapConfig configWith(BlockStorage storage, double resolution = 0.1) {
  VoxelMapConfig config;
  config.resolution = resolution;
  config.block_storage = storage;
  return config;
}

std::uint32_t bitsOf(float value) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  return bits;
}

// The brick of a voxel, worked out from its coordinates (not from BrickLayout).
std::tuple<int, int, int> brickOfVoxel(const VoxelIndex& index) {
  auto floor_half = [](int v) { return v >= 0 ? v / 2 : -((-v + 1) / 2); };
  return {floor_half(index.x()), floor_half(index.y()), floor_half(index.z())};
}

// A dense block with known voxels in `bricks` (each brick gets 1 to 8 of its voxels known, the
// others left unknown) and unknown everywhere else.
VoxelBlock blockWithBricks(const std::set<int>& bricks, std::mt19937* rng) {
  VoxelBlock block;
  std::uniform_real_distribution<float> value(-2.0f, 3.5f);
  std::bernoulli_distribution keep(0.6);
  for (int brick : bricks) {
    const int bx = (brick % 4) * 2, by = ((brick / 4) % 4) * 2, bz = (brick / 16) * 2;
    bool any = false;
    for (int corner = 0; corner < 8; ++corner) {
      if (!keep(*rng) && !(corner == 7 && !any)) continue;
      any = true;
      block.set(
          VoxelBlock::linearIndex(bx + (corner & 1), by + ((corner >> 1) & 1), bz + (corner >> 2)),
          value(*rng));
    }
  }
  block.version = 77;
  return block;
}

void expectSameBlock(const VoxelBlock& expected, const VoxelBlock& actual) {
  EXPECT_EQ(expected.known_count, actual.known_count);
  EXPECT_EQ(expected.version, actual.version);
  EXPECT_EQ(0, std::memcmp(expected.log_odds.data(), actual.log_odds.data(),
                           sizeof(expected.log_odds)));  // bit for bit, NaNs included
}

TEST(StoredBlock, CompactionAndExpansionRoundTripExactlyIncludingUnknownVoxels) {
  std::mt19937 rng(5);
  for (int count : {0, 1, 7, 31, 63}) {
    std::set<int> bricks;
    std::uniform_int_distribution<int> pick(0, 63);
    while (static_cast<int>(bricks.size()) < count) bricks.insert(pick(rng));
    const VoxelBlock original = blockWithBricks(bricks, &rng);

    StoredBlock stored = StoredBlock::newDense();
    *stored.dense() = original;
    const std::ptrdiff_t change = stored.settle(63);
    ASSERT_FALSE(stored.isDense()) << count << " bricks";
    EXPECT_EQ(stored.brickCount(), count);
    const std::size_t sparse_bytes = sizeof(SparseBlock) + 32u * static_cast<std::size_t>(count);
    EXPECT_EQ(stored.bytes(), sparse_bytes);
    EXPECT_EQ(change, static_cast<std::ptrdiff_t>(sparse_bytes) -
                          static_cast<std::ptrdiff_t>(sizeof(VoxelBlock)));
    EXPECT_EQ(stored.knownCount(), original.known_count);
    EXPECT_EQ(stored.version(), 77u);
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
      EXPECT_EQ(bitsOf(stored.at(linear)), bitsOf(original.log_odds[linear])) << linear;
    }
    VoxelBlock expanded;
    expanded.log_odds.fill(1.0f);  // whatever was there must be overwritten
    stored.copyTo(&expanded);
    expectSameBlock(original, expanded);
    VoxelBlock scratch;
    expectSameBlock(original, stored.view(&scratch));
    // And back to dense storage for a write.
    expectSameBlock(original, stored.makeDense());
    EXPECT_TRUE(stored.isDense());
  }
}

TEST(StoredBlock, StaysSparseUpToTheBrickLimitAndDenseBeyond) {
  std::mt19937 rng(9);
  std::set<int> bricks;
  for (int b = 0; b < VoxelMap::kMaxSparseBricks; ++b) bricks.insert(b);
  StoredBlock stored = StoredBlock::newDense();
  *stored.dense() = blockWithBricks(bricks, &rng);
  stored.settle(VoxelMap::kMaxSparseBricks);
  EXPECT_FALSE(stored.isDense());
  // One brick more: repacked from a written copy, it goes back to dense storage.
  bricks.insert(VoxelMap::kMaxSparseBricks);
  const VoxelBlock grown = blockWithBricks(bricks, &rng);
  EXPECT_EQ(
      stored.storeFrom(grown, VoxelMap::kMaxSparseBricks),
      static_cast<std::ptrdiff_t>(sizeof(VoxelBlock)) -
          static_cast<std::ptrdiff_t>(sizeof(SparseBlock) + 32u * VoxelMap::kMaxSparseBricks));
  EXPECT_TRUE(stored.isDense());
  expectSameBlock(grown, *stored.dense());
  EXPECT_EQ(stored.settle(VoxelMap::kMaxSparseBricks), 0);  // too many bricks to pack
  EXPECT_TRUE(stored.isDense());
}

// One random write of every kind the map has, applied to both maps.
class MixedWrites {
 public:
  explicit MixedWrites(unsigned seed) : rng_(seed) {}

  void apply(int step, VoxelMap* map) {
    std::mt19937 rng(rng_());  // the same draws for both maps
    const float lo = map->minLogOdds(), hi = map->maxLogOdds();
    switch (step % 6) {
      case 0: {  // a thin surface through some blocks: few bricks each
        std::vector<BlockIndex> blocks = someBlocks(&rng, 6, 0);
        const int layer = static_cast<int>(rng() % 8);
        map->updateBlocks(blocks, [&](const BlockIndex&, VoxelBlock& block) {
          for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; x += 3)
              block.update(VoxelBlock::linearIndex(x, y, layer), 0.85f, lo, hi);
        });
        break;
      }
      case 1: {  // free space filling whole blocks (stay dense), in the lowest layer of blocks
        std::vector<BlockIndex> blocks = someBlocks(&rng, 2, -1);
        map->updateBlocks(blocks, [&](const BlockIndex&, VoxelBlock& block) {
          for (int linear = 0; linear < VoxelBlock::kVolume; ++linear)
            block.update(linear, -0.4f, lo, hi);
        });
        break;
      }
      case 2: {  // scattered single voxels
        std::vector<VoxelUpdate> updates;
        for (int i = 0; i < 12; ++i)
          updates.push_back({someVoxel(&rng), (rng() % 2) ? 0.85f : -0.4f});
        map->applyUpdates(updates);
        break;
      }
      case 3:
        map->updateVoxel(someVoxel(&rng), 0.85f);
        break;
      case 4: {  // import-style sets, unknown included: a block can lose bricks
        for (int i = 0; i < 10; ++i) {
          const VoxelIndex index = someVoxel(&rng);
          map->setLogOdds(index, (rng() % 3 == 0) ? VoxelBlock::kUnknown : 1.5f);
        }
        break;
      }
      case 5: {
        const Eigen::Vector3d corner(static_cast<double>(rng() % 20) * 0.1 - 1.0, -1.0, -0.5);
        map->clearBox(corner, corner + Eigen::Vector3d(0.55, 2.0, 0.35));
        break;
      }
    }
  }

 private:
  // Blocks of the region (6 x 4 x 3 blocks) in layer z = -1 (lowest_z -1) or z = 0 and 1.
  static std::vector<BlockIndex> someBlocks(std::mt19937* rng, int count, int lowest_z) {
    std::vector<BlockIndex> blocks;
    std::set<std::tuple<int, int, int>> seen;
    const int layers = lowest_z < 0 ? 1 : 2;
    while (static_cast<int>(blocks.size()) < count) {
      const BlockIndex block(static_cast<int>((*rng)() % 6) - 3, static_cast<int>((*rng)() % 4) - 2,
                             lowest_z + static_cast<int>((*rng)() % layers));
      if (seen.insert({block.x(), block.y(), block.z()}).second) blocks.push_back(block);
    }
    return blocks;
  }
  static VoxelIndex someVoxel(std::mt19937* rng) {
    return {static_cast<int>((*rng)() % 48) - 24, static_cast<int>((*rng)() % 32) - 16,
            static_cast<int>((*rng)() % 24) - 8};
  }
  std::mt19937 rng_;
};

std::vector<std::pair<VoxelIndex, std::uint32_t>> visited(
    const std::function<void(const VoxelMap::VoxelFn&)>& for_each) {
  std::vector<std::pair<VoxelIndex, std::uint32_t>> out;
  for_each([&](const VoxelIndex& index, float value) { out.emplace_back(index, bitsOf(value)); });
  return out;
}

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void expectSameMaps(const VoxelMap& dense, const VoxelMap& hybrid) {
  // Point reads over the whole written region and a margin.
  for (int z = -12; z < 20; ++z)
    for (int y = -20; y < 20; ++y)
      for (int x = -28; x < 28; ++x) {
        const auto a = dense.logOdds({x, y, z});
        const auto b = hybrid.logOdds({x, y, z});
        ASSERT_EQ(a.has_value(), b.has_value()) << x << " " << y << " " << z;
        if (a) {
          ASSERT_EQ(bitsOf(*a), bitsOf(*b));
        }
        ASSERT_EQ(dense.occupancy({x, y, z}), hybrid.occupancy({x, y, z}));
      }
  // Iteration, in the same order (same table, same insertions).
  EXPECT_EQ(visited([&](const auto& fn) { dense.forEachKnownVoxel(fn); }),
            visited([&](const auto& fn) { hybrid.forEachKnownVoxel(fn); }));
  EXPECT_EQ(visited([&](const auto& fn) { dense.forEachOccupiedVoxel(fn); }),
            visited([&](const auto& fn) { hybrid.forEachOccupiedVoxel(fn); }));
  EXPECT_EQ(visited([&](const auto& fn) { dense.forEachFreeVoxel(fn); }),
            visited([&](const auto& fn) { hybrid.forEachFreeVoxel(fn); }));
  const Eigen::Vector3d box_min(-1.3, -0.7, -0.2), box_max(0.9, 1.1, 0.6);
  EXPECT_EQ(visited([&](const auto& fn) { dense.forEachKnownVoxelInBox(box_min, box_max, fn); }),
            visited([&](const auto& fn) { hybrid.forEachKnownVoxelInBox(box_min, box_max, fn); }));
  for (const Eigen::Vector3d& half : {Eigen::Vector3d(0.2, 0.2, 0.2), Eigen::Vector3d(3, 3, 3)}) {
    const VoxelCounts a = dense.countInBox(-half, half), b = hybrid.countInBox(-half, half);
    EXPECT_EQ(a.occupied, b.occupied);
    EXPECT_EQ(a.free, b.free);
    EXPECT_EQ(a.unknown, b.unknown);
  }
  EXPECT_EQ(dense.knownVoxelCount(), hybrid.knownVoxelCount());
  EXPECT_EQ(dense.blockCount(), hybrid.blockCount());
  // Blocks, as copies and as forEachBlock sees them.
  const std::vector<VoxelMap::BlockCopy> a = dense.copyBlocks(), b = hybrid.copyBlocks();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].first, b[i].first);
    expectSameBlock(a[i].second, b[i].second);
    VoxelBlock one;
    ASSERT_TRUE(hybrid.copyBlock(a[i].first, &one));
    expectSameBlock(a[i].second, one);
  }
  std::size_t at = 0;
  hybrid.forEachBlock([&](const BlockIndex& index, const VoxelBlock& block) {
    ASSERT_LT(at, a.size());
    EXPECT_EQ(index, a[at].first);
    expectSameBlock(a[at].second, block);
    ++at;
  });
  EXPECT_EQ(at, a.size());
  // Change log.
  for (std::uint64_t since :
       {std::uint64_t{0}, std::uint64_t{1}, dense.version() / 2, dense.version() - 3}) {
    const MapChanges x = dense.changesSince(since), y = hybrid.changesSince(since);
    EXPECT_EQ(x.version, y.version);
    EXPECT_EQ(x.full_rebuild, y.full_rebuild);
    EXPECT_EQ(x.changed, y.changed);
    EXPECT_EQ(x.removed, y.removed);
  }
  // OctoMap conversion and saved files.
  std::ostringstream tree_a, tree_b;
  toOcTree(dense)->writeBinary(tree_a);
  toOcTree(hybrid)->writeBinary(tree_b);
  EXPECT_EQ(tree_a.str(), tree_b.str());
  const std::string base = ::testing::TempDir() + "stored_block_map";
  writeOt(dense, base + "_dense.ot");
  writeOt(hybrid, base + "_hybrid.ot");
  EXPECT_EQ(fileBytes(base + "_dense.ot"), fileBytes(base + "_hybrid.ot"));
  writePcd(dense, base + "_dense.pcd");
  writePcd(hybrid, base + "_hybrid.pcd");
  EXPECT_EQ(fileBytes(base + "_dense.pcd"), fileBytes(base + "_hybrid.pcd"));
  for (const char* suffix : {"_dense.ot", "_hybrid.ot", "_dense.pcd", "_hybrid.pcd"}) {
    std::remove((base + suffix).c_str());
  }
}

TEST(VoxelMapStorage, HybridMapReadsExactlyAsADenseMapOfTheSameWrites) {
  VoxelMap dense(configWith(BlockStorage::kDense));
  VoxelMap hybrid(configWith(BlockStorage::kHybrid));
  MixedWrites writes_a(17), writes_b(17);
  for (int step = 0; step < 240; ++step) {
    writes_a.apply(step, &dense);
    writes_b.apply(step, &hybrid);
  }
  const VoxelMap::StorageStats stats = hybrid.storageStats();
  EXPECT_GT(stats.sparse_blocks, 10u);  // the mix holds both kinds
  EXPECT_GT(stats.dense_blocks, 3u);
  EXPECT_EQ(dense.storageStats().sparse_blocks, 0u);
  EXPECT_LT(hybrid.memoryBytes(), dense.memoryBytes());
  expectSameMaps(dense, hybrid);

  // A file written from the hybrid map loads into a hybrid map equal to the dense one's.
  const std::string path = ::testing::TempDir() + "stored_block_load.bt";
  writeBt(hybrid, path);
  const auto loaded_dense = readOctomapFile(path, configWith(BlockStorage::kDense));
  const auto loaded_hybrid = readOctomapFile(path, configWith(BlockStorage::kHybrid));
  std::remove(path.c_str());
  EXPECT_GT(loaded_hybrid->storageStats().sparse_blocks, 0u);
  expectSameMaps(*loaded_dense, *loaded_hybrid);
}

// A thin surface: a few planes of voxels, each crossing its blocks in one layer.
std::vector<VoxelUpdate> thinSurface() {
  std::vector<VoxelUpdate> updates;
  for (int x = -40; x < 40; ++x)
    for (int y = -30; y < 30; ++y) updates.push_back({{x, y, 5 + (x + 40) / 20}, 0.85f});
  for (int z = -10; z < 20; ++z)
    for (int y = -30; y < 30; y += 2) updates.push_back({{-41, y, z}, 0.85f});
  return updates;
}

TEST(VoxelMapStorage, MemoryOfAThinSurfaceFallsByItsEmptyBricks) {
  VoxelMap dense(configWith(BlockStorage::kDense));
  VoxelMap hybrid(configWith(BlockStorage::kHybrid));
  const std::vector<VoxelUpdate> updates = thinSurface();
  dense.applyUpdates(updates);
  hybrid.applyUpdates(updates);

  // Expected bytes from the bricks the surface touches, worked out from its voxels.
  std::set<std::tuple<int, int, int>> bricks, blocks;
  for (const VoxelUpdate& update : updates) {
    bricks.insert(brickOfVoxel(update.index));
    const BlockIndex block = VoxelMap::blockOf(update.index);
    blocks.insert({block.x(), block.y(), block.z()});
  }
  ASSERT_EQ(hybrid.blockCount(), blocks.size());
  // Every block qualifies as sparse here: a plane fills 16 of 64 bricks.
  const std::size_t sparse_bytes = blocks.size() * sizeof(SparseBlock) + bricks.size() * 8 * 4;
  const std::size_t dense_bytes = blocks.size() * 2064;  // 512 floats, count and version
  ASSERT_EQ(sizeof(VoxelBlock), 2064u);
  const VoxelMap::StorageStats stats = hybrid.storageStats();
  EXPECT_EQ(stats.sparse_blocks, blocks.size());
  EXPECT_EQ(stats.sparse_bricks, bricks.size());
  EXPECT_EQ(stats.block_bytes, sparse_bytes);
  EXPECT_EQ(dense.storageStats().block_bytes, dense_bytes);
  // Same table, same change log: the whole difference is the blocks'.
  EXPECT_EQ(dense.memoryBytes() - hybrid.memoryBytes(), dense_bytes - sparse_bytes);
  EXPECT_EQ(hybrid.memoryBytes(), stats.block_bytes + stats.table_bytes + stats.change_log_bytes);
  // About a quarter here (16 of 64 bricks per plane block).
  EXPECT_LT(static_cast<double>(sparse_bytes) / dense_bytes, 0.3);

  // Filling the same blocks with free space makes them dense again, at the dense cost.
  std::vector<BlockIndex> block_list;
  for (const auto& [x, y, z] : blocks) block_list.emplace_back(x, y, z);
  hybrid.updateBlocks(block_list, [&](const BlockIndex&, VoxelBlock& block) {
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear)
      block.update(linear, -0.4f, hybrid.minLogOdds(), hybrid.maxLogOdds());
  });
  EXPECT_EQ(hybrid.storageStats().dense_blocks, blocks.size());
  EXPECT_EQ(hybrid.storageStats().block_bytes, dense_bytes);
}

TEST(VoxelMapStorage, MemoryBoundEvictsSparseBlocksFarthestFromTheFocus) {
  // 200 blocks in a row along +x, each with one voxel (one brick: a sparse block of 56 bytes),
  // under a bound of 150 of them plus the table (512 slots of 24 bytes for up to 256 blocks).
  const std::size_t sparse_block = sizeof(SparseBlock) + 32;
  VoxelMapConfig config = configWith(BlockStorage::kHybrid);
  config.max_memory_bytes = 150 * sparse_block + 512 * 24;
  VoxelMap map(config);
  map.setFocus({0.0, 0.0, 0.0});
  for (int i = 0; i < 200; ++i) {
    map.updateVoxel({i * VoxelBlock::kSide, 0, 0}, 1.0f);
    const VoxelMap::StorageStats stats = map.storageStats();
    ASSERT_LE(stats.block_bytes + stats.table_bytes, config.max_memory_bytes) << i;
    ASSERT_EQ(stats.dense_blocks, 0u);
  }
  EXPECT_GT(map.evictedBlockCount(), 0u);
  EXPECT_EQ(map.blockCount() + map.evictedBlockCount(), 200u);
  EXPECT_GT(map.blockCount(), 100u);  // sparse blocks are counted at their own size
  EXPECT_EQ(map.storageStats().block_bytes, map.blockCount() * sparse_block);
  // Each eviction dropped the farthest blocks (down to 90 % of the bound: 113 of them), so the
  // nearest ones all survive.
  int nearest_kept = 0;
  while (map.occupancy({nearest_kept * VoxelBlock::kSide, 0, 0}) == Occupancy::kOccupied) {
    ++nearest_kept;
  }
  EXPECT_GE(nearest_kept, 110);
  // A dense block written near the focus is counted at the dense size and evicts more.
  const std::size_t before = map.blockCount();
  map.updateBlocks({BlockIndex(0, 1, 0), BlockIndex(0, 2, 0)},
                   [&](const BlockIndex&, VoxelBlock& block) {
                     for (int linear = 0; linear < VoxelBlock::kVolume; ++linear)
                       block.update(linear, -0.4f, map.minLogOdds(), map.maxLogOdds());
                   });
  EXPECT_EQ(map.storageStats().dense_blocks, 2u);
  // Two dense blocks (4128 bytes) displace about 74 sparse ones (56 bytes each) and more.
  EXPECT_LE(map.blockCount(), before + 2 - 74);
  EXPECT_EQ(map.occupancy({0, VoxelBlock::kSide, 0}), Occupancy::kFree);
  EXPECT_EQ(map.occupancy({0, 0, 0}), Occupancy::kOccupied);
}

}  // namespace
}  // namespace occupancy_fusion
