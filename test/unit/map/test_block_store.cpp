// The spill store (map/block_store.h) on its own: blocks come back as written, also after the
// store is reopened, and every bad store gives a std::runtime_error naming its folder.
#include <gtest/gtest.h>

#include <lmdb.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "../../common/test_folder.h"
#include "occupancy_fusion/map/block_store.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/stored_block.h"

namespace occupancy_fusion {
namespace {

using BlockStoreTest = TestFolder;

// Voxel for voxel (NaN where unknown in both), and the same known count.
::testing::AssertionResult sameVoxels(const VoxelBlock& a, const VoxelBlock& b) {
  for (int i = 0; i < VoxelBlock::kVolume; ++i) {
    const bool a_known = VoxelBlock::isKnown(a.log_odds[i]);
    if (a_known != VoxelBlock::isKnown(b.log_odds[i]) ||
        (a_known && a.log_odds[i] != b.log_odds[i])) {
      return ::testing::AssertionFailure()
             << "voxel " << i << ": " << a.log_odds[i] << " vs " << b.log_odds[i];
    }
  }
  if (a.known_count != b.known_count) {
    return ::testing::AssertionFailure() << "known " << a.known_count << " vs " << b.known_count;
  }
  return ::testing::AssertionSuccess();
}

// `known` random voxels set to random log-odds.
VoxelBlock randomBlock(std::mt19937* rng, int known) {
  std::uniform_int_distribution<int> voxel(0, VoxelBlock::kVolume - 1);
  std::uniform_real_distribution<float> value(-2.0f, 3.5f);
  VoxelBlock block;
  while (block.known_count < known) block.set(voxel(*rng), value(*rng));
  return block;
}

// Blocks at scattered indices, from empty to full, sparse ones in between.
std::map<std::uint64_t, VoxelBlock> randomBlocks(unsigned seed, int count) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> coordinate(-1000, 1000);
  const int known_counts[] = {0, 1, 7, 60, 300, VoxelBlock::kVolume};
  std::map<std::uint64_t, VoxelBlock> blocks;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3i index(coordinate(rng), coordinate(rng), coordinate(rng));
    blocks[packKey(index)] = randomBlock(&rng, known_counts[i % 6]);
  }
  return blocks;
}

void putAll(BlockStore* store, const std::map<std::uint64_t, VoxelBlock>& blocks) {
  std::vector<std::uint64_t> keys;
  std::vector<const VoxelBlock*> values;
  for (const auto& [key, block] : blocks) {
    keys.push_back(key);
    values.push_back(&block);
  }
  store->put(keys, [&](std::size_t i) -> const VoxelBlock& { return *values[i]; });
}

BlockStoreConfig storeConfig(const std::string& folder, double resolution = 0.05) {
  BlockStoreConfig config;
  config.folder = folder;
  config.resolution = resolution;
  return config;
}

// The error `make` throws: a std::runtime_error naming `folder`.
template <class Make>
std::string errorOf(const Make& make, const std::string& folder) {
  try {
    make();
  } catch (const std::runtime_error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(folder), std::string::npos) << message;
    return message;
  }
  ADD_FAILURE() << "no error for " << folder;
  return "";
}

TEST(BrickEncoding, HoldsOnlyTheNonEmptyBricksAndDecodesToTheSameBlock) {
  VoxelBlock block;
  block.set(VoxelBlock::linearIndex(0, 0, 0), 1.5f);
  block.set(VoxelBlock::linearIndex(1, 1, 1), -0.25f);  // the same brick
  block.set(VoxelBlock::linearIndex(7, 0, 0), 2.0f);
  block.set(VoxelBlock::linearIndex(4, 6, 3), 0.0f);
  std::vector<unsigned char> bytes;
  BrickEncoding::encode(block, &bytes);
  EXPECT_EQ(bytes.size(), 8u + 3u * 8u * sizeof(float));  // mask + 3 bricks of 8 floats

  VoxelBlock decoded;
  decoded.version = 77;
  ASSERT_TRUE(BrickEncoding::decode(bytes.data(), bytes.size(), &decoded));
  EXPECT_TRUE(sameVoxels(decoded, block));
  EXPECT_EQ(decoded.known_count, 4);
  EXPECT_EQ(decoded.version, 0u);

  EXPECT_FALSE(BrickEncoding::decode(bytes.data(), bytes.size() - 1, &decoded));
  EXPECT_FALSE(BrickEncoding::decode(bytes.data(), 5, &decoded));

  VoxelBlock full = block;
  for (int i = 0; i < VoxelBlock::kVolume; ++i) full.set(i, 0.5f);
  BrickEncoding::encode(full, &bytes);
  EXPECT_EQ(bytes.size(), 8u + VoxelBlock::kVolume * sizeof(float));
}

TEST_F(BlockStoreTest, GivesTheBlocksBackAlsoAfterReopening) {
  const std::string folder = path("store");
  const std::map<std::uint64_t, VoxelBlock> blocks = randomBlocks(11, 120);
  {
    BlockStore store(storeConfig(folder));
    EXPECT_EQ(store.size(), 0u);
    putAll(&store, blocks);
    EXPECT_EQ(store.size(), blocks.size());
  }
  BlockStore reopened(storeConfig(folder));
  EXPECT_EQ(reopened.size(), blocks.size());
  for (const auto& [key, block] : blocks) {
    VoxelBlock read;
    ASSERT_TRUE(reopened.get(key, &read)) << key;
    EXPECT_TRUE(sameVoxels(read, block)) << key;
  }
  VoxelBlock absent;
  EXPECT_FALSE(reopened.get(packKey(Eigen::Vector3i(5000, 0, 0)), &absent));

  // forEach: every block once, in increasing key order (std::map's order).
  auto expected = blocks.begin();
  std::size_t visited = 0;
  reopened.forEach([&](std::uint64_t key, const VoxelBlock& block) {
    ASSERT_NE(expected, blocks.end());
    EXPECT_EQ(key, expected->first);
    EXPECT_TRUE(sameVoxels(block, expected->second)) << key;
    ++expected;
    ++visited;
  });
  EXPECT_EQ(visited, blocks.size());

  // A block written again replaces the old one; clear() empties the store.
  std::mt19937 rng(3);
  const VoxelBlock replacement = randomBlock(&rng, 200);
  reopened.put(blocks.begin()->first, replacement);
  VoxelBlock read;
  ASSERT_TRUE(reopened.get(blocks.begin()->first, &read));
  EXPECT_TRUE(sameVoxels(read, replacement));
  EXPECT_EQ(reopened.size(), blocks.size());
  reopened.clear();
  EXPECT_EQ(reopened.size(), 0u);
  EXPECT_FALSE(reopened.get(blocks.begin()->first, &read));
}

TEST_F(BlockStoreTest, GrowsWhenFullUpToItsLimit) {
  BlockStoreConfig config = storeConfig(path("store"));
  config.initial_bytes = 64 << 10;
  config.max_bytes = 1 << 20;
  BlockStore store(config);
  EXPECT_EQ(store.sizeLimit(), config.initial_bytes);
  // 100 full blocks, 400 KiB on disk (one 4 KiB page each): more than the initial size, less than
  // the limit.
  std::mt19937 rng(5);
  std::map<std::uint64_t, VoxelBlock> blocks;
  for (int i = 0; i < 100; ++i) blocks[packKey(Eigen::Vector3i(i, 0, 0))] = randomBlock(&rng, 512);
  putAll(&store, blocks);
  EXPECT_GT(store.sizeLimit(), config.initial_bytes);
  EXPECT_LE(store.sizeLimit(), config.max_bytes);
  EXPECT_EQ(store.size(), 100u);

  // 1000 more do not fit in 1 MiB: an error naming the folder, and nothing of them written.
  std::map<std::uint64_t, VoxelBlock> more;
  for (int i = 0; i < 1000; ++i) more[packKey(Eigen::Vector3i(i, 1, 0))] = randomBlock(&rng, 512);
  const std::string message = errorOf([&] { putAll(&store, more); }, config.folder);
  EXPECT_NE(message.find("full"), std::string::npos) << message;
  EXPECT_EQ(store.sizeLimit(), config.max_bytes);
  EXPECT_EQ(store.size(), 100u);
  VoxelBlock read;
  EXPECT_FALSE(store.get(more.begin()->first, &read));
  ASSERT_TRUE(store.get(blocks.begin()->first, &read));
  EXPECT_TRUE(sameVoxels(read, blocks.begin()->second));
}

TEST_F(BlockStoreTest, StoreOfAnotherResolutionIsRefusedNamingTheFolder) {
  const std::string folder = path("store");
  { BlockStore store(storeConfig(folder, 0.05)); }
  const std::string message = errorOf([&] { BlockStore store(storeConfig(folder, 0.1)); }, folder);
  EXPECT_NE(message.find("written with resolution 0.05 m, the map's is 0.1 m"), std::string::npos)
      << message;
  EXPECT_NO_THROW(BlockStore store(storeConfig(folder, 0.05)));
}

// Replaces the value of the store's first block with `bytes`, through LMDB itself.
void damageFirstBlock(const std::string& folder, const std::string& bytes) {
  MDB_env* env = nullptr;
  ASSERT_EQ(mdb_env_create(&env), MDB_SUCCESS);
  ASSERT_EQ(mdb_env_set_maxdbs(env, 2), MDB_SUCCESS);
  ASSERT_EQ(mdb_env_open(env, folder.c_str(), 0, 0664), MDB_SUCCESS);
  MDB_txn* txn = nullptr;
  ASSERT_EQ(mdb_txn_begin(env, nullptr, 0, &txn), MDB_SUCCESS);
  MDB_dbi blocks;
  ASSERT_EQ(mdb_dbi_open(txn, "blocks", 0, &blocks), MDB_SUCCESS);
  MDB_cursor* cursor = nullptr;
  ASSERT_EQ(mdb_cursor_open(txn, blocks, &cursor), MDB_SUCCESS);
  MDB_val key, value;
  ASSERT_EQ(mdb_cursor_get(cursor, &key, &value, MDB_FIRST), MDB_SUCCESS);
  MDB_val damaged{bytes.size(), const_cast<char*>(bytes.data())};
  ASSERT_EQ(mdb_cursor_put(cursor, &key, &damaged, MDB_CURRENT), MDB_SUCCESS);
  mdb_cursor_close(cursor);
  ASSERT_EQ(mdb_txn_commit(txn), MDB_SUCCESS);
  mdb_env_close(env);
}

TEST_F(BlockStoreTest, DamagedBlockIsReportedNamingTheFolder) {
  const std::string folder = path("store");
  const std::map<std::uint64_t, VoxelBlock> blocks = randomBlocks(7, 12);
  {
    BlockStore store(storeConfig(folder));
    putAll(&store, blocks);
  }
  damageFirstBlock(folder, "12345");  // no encoding: shorter than a brick mask
  BlockStore store(storeConfig(folder));
  VoxelBlock read;
  std::string message = errorOf([&] { store.get(blocks.begin()->first, &read); }, folder);
  EXPECT_NE(message.find("damaged"), std::string::npos) << message;
  message = errorOf([&] { store.forEach([](std::uint64_t, const VoxelBlock&) {}); }, folder);
  EXPECT_NE(message.find("damaged"), std::string::npos) << message;
  // The other blocks still read.
  ASSERT_TRUE(store.get(std::next(blocks.begin())->first, &read));
  EXPECT_TRUE(sameVoxels(read, std::next(blocks.begin())->second));
}

TEST_F(BlockStoreTest, FolderInUseIsRefusedNamingTheFolder) {
  const std::string folder = path("store");
  {
    BlockStore first(storeConfig(folder));
    first.put(packKey(Eigen::Vector3i(1, 2, 3)), VoxelBlock());
    const std::string message = errorOf([&] { BlockStore second(storeConfig(folder)); }, folder);
    EXPECT_NE(message.find("in use"), std::string::npos) << message;
    EXPECT_EQ(first.size(), 1u);  // the refused store touched nothing
  }
  BlockStore after(storeConfig(folder));  // free again once the first is closed
  EXPECT_EQ(after.size(), 1u);
}

TEST_F(BlockStoreTest, UnwritableFolderIsRefusedNamingTheFolder) {
  // Under a regular file: no folder can be made there, whoever runs the test.
  std::ofstream(path("file")) << "not a folder";
  const std::string folder = path("file") + "/store";
  const std::string message = errorOf([&] { BlockStore store(storeConfig(folder)); }, folder);
  EXPECT_NE(message.find("cannot create the folder"), std::string::npos) << message;

  // A folder without write permission (the superuser writes anyway: not checked then).
  if (::geteuid() == 0) return;
  const std::string locked = path("locked");
  std::filesystem::create_directories(locked);
  std::filesystem::permissions(
      locked, std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec);
  errorOf([&] { BlockStore store(storeConfig(locked)); }, locked);
  std::filesystem::permissions(locked, std::filesystem::perms::owner_all);
}

TEST_F(BlockStoreTest, DamagedStoreIsRefusedNamingTheFolder) {
  const std::string folder = path("store");
  {
    BlockStore store(storeConfig(folder));
    putAll(&store, randomBlocks(2, 10));
  }
  // Overwrite the data file's header pages (LMDB's meta pages) with garbage.
  {
    std::fstream data(folder + "/data.mdb", std::ios::in | std::ios::out | std::ios::binary);
    ASSERT_TRUE(data.good());
    const std::string garbage(8192, '\x5a');
    data.write(garbage.data(), static_cast<std::streamsize>(garbage.size()));
  }
  const std::string message = errorOf([&] { BlockStore store(storeConfig(folder)); }, folder);
  EXPECT_NE(message.find("damaged"), std::string::npos) << message;

  // A data file that is no store at all.
  const std::string other = path("other");
  std::filesystem::create_directories(other);
  std::ofstream(other + "/data.mdb") << std::string(20000, 'x');
  errorOf([&] { BlockStore store(storeConfig(other)); }, other);
}

}  // namespace
}  // namespace occupancy_fusion
