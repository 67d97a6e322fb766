#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

#include "occupancy_fusion/map/octomap_conversion.h"

namespace occupancy_fusion {
namespace {

VoxelMapConfig mapConfig(double resolution = 0.1) {
  VoxelMapConfig config;
  config.resolution = resolution;
  return config;
}

// A map with clamped random values around the origin, negative indices included.
void fillRandom(VoxelMap* map, unsigned seed, int count = 3000) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> coordinate(-30, 30);
  std::uniform_real_distribution<float> delta(-2.5f, 4.0f);
  std::vector<VoxelUpdate> updates;
  for (int i = 0; i < count; ++i) {
    updates.push_back({{coordinate(rng), coordinate(rng), coordinate(rng) / 3}, delta(rng)});
  }
  map->applyUpdates(updates);
}

TEST(OctomapConversion, EveryKnownVoxelKeepsItsLogOddsAtLiboctomapsKey) {
  VoxelMap map(mapConfig(0.1));
  fillRandom(&map, 7);
  std::size_t skipped = 99;
  const std::unique_ptr<octomap::OcTree> tree = toOcTree(map, &skipped);
  EXPECT_EQ(skipped, 0u);
  EXPECT_DOUBLE_EQ(tree->getResolution(), 0.1);
  EXPECT_NEAR(tree->getProbHit(), 0.7, 1e-6);
  EXPECT_NEAR(tree->getProbMiss(), 0.4, 1e-6);
  EXPECT_NEAR(tree->getClampingThresMin(), 0.1192, 1e-6);
  EXPECT_NEAR(tree->getClampingThresMax(), 0.971, 1e-6);
  EXPECT_NEAR(tree->getOccupancyThres(), 0.5, 1e-6);
  std::size_t checked = 0;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    const Eigen::Vector3d c = map.centerOf(index);
    // liboctomap's own coordinate-to-key mapping, and its own search.
    const octomap::OcTreeNode* node = tree->search(tree->coordToKey(c.x(), c.y(), c.z()));
    ASSERT_NE(node, nullptr) << index.transpose();
    EXPECT_FLOAT_EQ(node->getLogOdds(), log_odds) << index.transpose();
    EXPECT_EQ(tree->isNodeOccupied(node), map.occupancy(index) == Occupancy::kOccupied);
    ++checked;
  });
  EXPECT_EQ(checked, map.knownVoxelCount());
  // Unknown voxels are absent from the tree.
  for (int x = -30; x <= 30; ++x) {
    const VoxelIndex index(x, 31, 0);
    const Eigen::Vector3d c = map.centerOf(index);
    EXPECT_EQ(tree->search(c.x(), c.y(), c.z()), nullptr);
  }
}

TEST(OctomapConversion, VoxelsOutsideTheKeyRangeAreSkippedAndCounted) {
  VoxelMap map(mapConfig(0.1));
  map.setLogOdds({32767, 0, 0}, 1.0f);
  map.setLogOdds({-32768, 0, 0}, 1.0f);
  map.setLogOdds({32768, 0, 0}, 1.0f);
  map.setLogOdds({0, -32769, 5}, 1.0f);
  std::size_t skipped = 0;
  const std::unique_ptr<octomap::OcTree> tree = toOcTree(map, &skipped);
  EXPECT_EQ(skipped, 2u);
  EXPECT_EQ(tree->getNumLeafNodes(), 2u);
  EXPECT_TRUE(isOctomapRepresentable({-32768, 32767, 0}));
  EXPECT_FALSE(isOctomapRepresentable({0, 0, 32768}));
}

TEST(OctomapConversion, EqualSiblingsArePrunedAndRoundTrip) {
  VoxelMap map(mapConfig(0.1));
  const float value = map.maxLogOdds();
  for (int z = 0; z < 4; ++z) {
    for (int y = 0; y < 4; ++y) {
      for (int x = 0; x < 4; ++x) map.setLogOdds({x, y, z}, value);
    }
  }
  map.setLogOdds({-1, 0, 0}, -1.0f);
  const std::unique_ptr<octomap::OcTree> tree = toOcTree(map);
  EXPECT_EQ(tree->getNumLeafNodes(), 2u);  // one 4^3 leaf at depth 14, one voxel

  VoxelMap back(mapConfig(0.1));
  fromOcTree(*tree, &back);
  EXPECT_EQ(back.knownVoxelCount(), 65u);
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    ASSERT_TRUE(back.logOdds(index).has_value()) << index.transpose();
    EXPECT_FLOAT_EQ(*back.logOdds(index), log_odds);
  });
}

TEST(OctomapConversion, ImportExpandsPrunedLeavesOfATreeBuiltByLiboctomap) {
  octomap::OcTree tree(0.05);
  // A free 8^3 cube at keys aligned to depth 13, plus occupied single voxels, negative included.
  for (int z = 0; z < 8; ++z) {
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 8; ++x) {
        tree.updateNode(octomap::OcTreeKey(32768 + 8 + x, 32768 - 16 + y, 32768 + z), false);
      }
    }
  }
  tree.updateNode(octomap::point3d(-1.01f, 2.02f, -0.33f), true);
  tree.updateNode(octomap::point3d(0.51f, 0.52f, 0.53f), true);
  tree.updateInnerOccupancy();
  tree.prune();
  std::size_t coarse_leaves = 0;
  std::size_t covered = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    coarse_leaves += it.getDepth() < tree.getTreeDepth() ? 1 : 0;
    const std::size_t side = std::size_t{1} << (tree.getTreeDepth() - it.getDepth());
    covered += side * side * side;
  }
  ASSERT_GE(coarse_leaves, 1u);  // the cube was pruned
  ASSERT_EQ(covered, 514u);

  VoxelMap map(mapConfig(0.05));
  fromOcTree(tree, &map);
  EXPECT_EQ(map.knownVoxelCount(), 514u);
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    const Eigen::Vector3d c = map.centerOf(index);
    const octomap::OcTreeNode* node = tree.search(c.x(), c.y(), c.z());
    ASSERT_NE(node, nullptr) << index.transpose();
    EXPECT_FLOAT_EQ(node->getLogOdds(), log_odds);
  });
  EXPECT_EQ(map.occupancy({8, -16, 0}), Occupancy::kFree);
  EXPECT_EQ(map.occupancy({15, -9, 7}), Occupancy::kFree);
  EXPECT_EQ(map.occupancy({16, -9, 7}), Occupancy::kUnknown);
  EXPECT_EQ(map.occupancyAt({-1.01, 2.02, -0.33}), Occupancy::kOccupied);
}

TEST(OctomapConversion, ImportRejectsAnotherResolution) {
  octomap::OcTree tree(0.1);
  tree.updateNode(octomap::point3d(0, 0, 0), true);
  VoxelMap map(mapConfig(0.05));
  EXPECT_THROW(fromOcTree(tree, &map), std::invalid_argument);
}

}  // namespace
}  // namespace occupancy_fusion
