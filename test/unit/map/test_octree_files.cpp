// The streamed .ot / .bt writer against liboctomap's own OcTree::write and writeBinary of the tree
// toOcTree builds (an independent implementation of the same files): every byte equal.
#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "../../common/test_folder.h"
#include "occupancy_fusion/map/octomap_conversion.h"
#include "occupancy_fusion/map/octree_files.h"

namespace occupancy_fusion {
namespace {

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

struct LiboctomapFiles {
  std::string ot, bt;
  std::size_t ot_nodes = 0, bt_nodes = 0, skipped = 0;
};

// As saveMap wrote them before: .ot first, then writeBinary (which prunes the tree to maximum
// likelihood first).
LiboctomapFiles liboctomapFiles(const VoxelMap& map) {
  LiboctomapFiles files;
  const std::unique_ptr<octomap::OcTree> tree = toOcTree(map, &files.skipped);
  std::ostringstream ot, bt;
  EXPECT_TRUE(tree->write(ot));
  files.ot_nodes = tree->size();
  EXPECT_TRUE(tree->writeBinary(bt));
  files.bt_nodes = tree->size();
  files.ot = ot.str();
  files.bt = bt.str();
  return files;
}

class OctreeFiles : public ::testing::Test {
 protected:
  // Both files of the map streamed, against liboctomap's.
  void expectAsLiboctomap(const VoxelMap& map, const std::string& what) {
    const LiboctomapFiles expected = liboctomapFiles(map);
    const OctreeFilePaths paths{folder_.path("map.ot"), folder_.path("map.bt")};
    const OctreeFilesWritten written =
        writeOctreeFiles(blockSourceOf(map), map.resolution(), map.model(), paths);
    EXPECT_EQ(written.ot_nodes, expected.ot_nodes) << what;
    EXPECT_EQ(written.bt_nodes, expected.bt_nodes) << what;
    EXPECT_EQ(written.skipped_voxels, expected.skipped) << what;
    const std::string ot = fileBytes(paths.ot), bt = fileBytes(paths.bt);
    EXPECT_EQ(ot.size(), expected.ot.size()) << what;
    EXPECT_TRUE(ot == expected.ot) << what << ": .ot differs";
    EXPECT_EQ(bt.size(), expected.bt.size()) << what;
    EXPECT_TRUE(bt == expected.bt) << what << ": .bt differs";
    // Nothing left beside them: the scratch files are gone.
    std::size_t entries = 0;
    for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(folder_.path()))
      ++entries;
    EXPECT_EQ(entries, 2u) << what;
  }

  TemporaryFolder folder_;
};

VoxelMapConfig mapConfig(double resolution = 0.1) {
  VoxelMapConfig config;
  config.resolution = resolution;
  return config;
}

TEST_F(OctreeFiles, RandomMapsAreLiboctomapsFilesByteForByte) {
  for (unsigned seed : {1u, 2u, 3u}) {
    VoxelMap map(mapConfig());
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> coordinate(-40, 40);
    std::uniform_real_distribution<float> delta(-3.0f, 4.5f);  // beyond both clamping bounds
    std::vector<VoxelUpdate> updates;
    for (int i = 0; i < 20000; ++i) {
      updates.push_back({{coordinate(rng), coordinate(rng), coordinate(rng) / 4}, delta(rng)});
    }
    map.applyUpdates(updates);
    // Unclamped values too (setLogOdds), which the tree clamps.
    map.setLogOdds({3, 3, 3}, 7.5f);
    map.setLogOdds({4, 3, 3}, -9.0f);
    expectAsLiboctomap(map, "seed " + std::to_string(seed));
  }
}

// Uniform regions collapse at every depth: voxel pairs, blocks, groups of blocks; free space
// at the clamping minimum is what real maps are full of.
TEST_F(OctreeFiles, UniformRegionsPruneAsInLiboctomap) {
  VoxelMap map(mapConfig(0.05));
  const float low = map.minLogOdds(), high = map.maxLogOdds();
  // 64^3 voxels of free space at the minimum (a node at depth 10), one occupied wall in it.
  for (int z = -32; z < 32; ++z) {
    for (int y = -32; y < 32; ++y) {
      for (int x = -32; x < 32; ++x) map.setLogOdds({x, y, z}, x == 5 ? high : low);
    }
  }
  // A 2^3 group of another value (collapses at depth 15 only) and a free region of values that
  // differ but are all free (pruned in the .bt only).
  for (int z = 40; z < 42; ++z)
    for (int y = 40; y < 42; ++y)
      for (int x = 40; x < 42; ++x) map.setLogOdds({x, y, z}, -0.7f);
  for (int z = 48; z < 64; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) map.setLogOdds({x, y, z}, -1.0f - 0.001f * ((x + y + z) % 5));
  expectAsLiboctomap(map, "uniform regions");
}

// liboctomap's prune stops at the first depth where nothing collapses: here the .ot has already
// collapsed every 2^3 group, so writeBinary's prune collapses nothing at depth 15 and stops,
// although the groups (free, of different values) would collapse at depth 14.
TEST_F(OctreeFiles, TheBinaryPruneStopsWhereLiboctomapsStops) {
  VoxelMap map(mapConfig(0.1));
  for (int gz = 0; gz < 4; ++gz) {
    for (int gy = 0; gy < 4; ++gy) {
      for (int gx = 0; gx < 4; ++gx) {
        const float value = -0.5f - 0.01f * static_cast<float>(gx + 4 * gy + 16 * gz);
        for (int z = 0; z < 2; ++z)
          for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 2; ++x) map.setLogOdds({2 * gx + x, 2 * gy + y, 2 * gz + z}, value);
      }
    }
  }
  expectAsLiboctomap(map, "stopped prune");
  // With one ordinary voxel pair elsewhere, depth 15 collapses something and the prune goes on.
  map.setLogOdds({100, 0, 0}, -0.3f);
  map.setLogOdds({101, 0, 0}, -0.4f);
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 2; ++x)
        if (x + y + z > 0) map.setLogOdds({100 + x, y, z}, -0.2f);
  expectAsLiboctomap(map, "continued prune");
}

TEST_F(OctreeFiles, EmptyMapsSingleVoxelsAndVoxelsOutsideTheKeyRange) {
  VoxelMap map(mapConfig());
  expectAsLiboctomap(map, "empty");
  map.setLogOdds({-1, -1, -1}, 0.8f);
  expectAsLiboctomap(map, "one voxel");
  map.setLogOdds({32767, -32768, 0}, 0.3f);  // the key range's corners
  map.setLogOdds({40000, 0, 0}, 0.3f);       // outside: skipped and counted
  map.setLogOdds({40001, 0, 0}, -0.3f);
  map.setLogOdds({0, 0, -32769}, 0.3f);
  expectAsLiboctomap(map, "key range");
}

TEST_F(OctreeFiles, CopiedBlocksGiveTheMapsFiles) {
  VoxelMap map(mapConfig());
  for (int i = 0; i < 300; ++i) map.setLogOdds({i % 37, i % 11, i % 5}, -0.01f * i + 1.0f);
  const OctreeFilePaths from_map{folder_.path("a.ot"), ""};
  const OctreeFilePaths from_copy{folder_.path("b.ot"), folder_.path("b.bt")};
  writeOctreeFiles(blockSourceOf(map), map.resolution(), map.model(), from_map);
  const std::vector<VoxelMap::BlockCopy> copies = map.copyBlocks();
  writeOctreeFiles(blockSourceOf(copies), map.resolution(), map.model(), from_copy);
  EXPECT_TRUE(fileBytes(from_map.ot) == fileBytes(from_copy.ot));
  EXPECT_FALSE(std::filesystem::exists(folder_.path("a.bt")));
}

TEST_F(OctreeFiles, AnUnwritableFolderIsNamed) {
  VoxelMap map(mapConfig());
  map.setLogOdds({0, 0, 0}, 0.5f);
  const std::string path = folder_.path("missing/map.ot");
  try {
    writeOctreeFiles(blockSourceOf(map), map.resolution(), map.model(), {path, ""});
    FAIL() << "no error";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(path), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace occupancy_fusion
