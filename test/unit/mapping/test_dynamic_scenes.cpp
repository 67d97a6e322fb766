// The dynamic-scene evaluation (eval/dynamic_scenes.h): a box taken away in front of a sensor,
// its ghost counted against what the update rules predict.
#include <gtest/gtest.h>

#include <cmath>

#include "occupancy_fusion/eval/dynamic_scenes.h"

namespace occupancy_fusion {
namespace {

DynamicSceneCase removedBox(DynamicMapper mapper) {
  DynamicSceneCase setup;
  setup.event = DynamicEvent::kRemovedBox;
  setup.mapper = mapper;
  setup.resolution = 0.1;
  setup.frames_after = 15;
  return setup;
}

// OctoMap's update on the disparities: 15 frames clamp the box's voxels at the maximum, and each
// frame after its removal is one miss on every ray through them; a voxel is free once
// ceil(max / -miss) misses brought it to 0 or below (3.51 / 0.405: 9 frames).
TEST(DynamicScenes, OctomapUpdateClearsAClampedBoxInMaxOverMissFrames) {
  const DynamicSceneCase setup = removedBox(DynamicMapper::kStereoOctomap);
  const DynamicSceneResult result = evaluateDynamicScene(setup);
  const OccupancyModel& model = setup.mapping.map.model;
  const int expected =
      static_cast<int>(std::ceil(model.maxLogOdds() / -model.missLogOdds() - 1e-6));
  EXPECT_EQ(expected, 9);
  EXPECT_GT(result.object_voxels, 100u);
  EXPECT_EQ(result.frames_to_clear, expected);
  // Nearly all of the box is still there one frame before.
  EXPECT_GT(result.ghost[static_cast<std::size_t>(expected - 2)], result.object_voxels / 2);
  EXPECT_EQ(result.change_frame, setup.frames_before);
  EXPECT_EQ(result.ghost.size(), static_cast<std::size_t>(setup.frames_after));
}

// The laser layer: the box's front face in a few cells, gone within two scans (Yguel's model
// gives a free cell min_log_ratio at once).
TEST(DynamicScenes, LaserClearsTheBoxWithinTwoScans) {
  const DynamicSceneResult result = evaluateDynamicScene(removedBox(DynamicMapper::kLaser));
  EXPECT_GE(result.object_voxels, 5u);
  EXPECT_GE(result.frames_to_clear, 1);
  EXPECT_LE(result.frames_to_clear, 2);
  EXPECT_GT(result.static_coverage, 0.5);
}

// Depth images with config/depth_mapper.yaml's Eq. 7 (k = sigma = 0.05 m; the paper's 0.6 m
// spreads every surface over the box's depth).
TEST(DynamicScenes, DepthImagesClearTheBox) {
  DynamicSceneCase setup = removedBox(DynamicMapper::kDepth);
  setup.mapping.depth.k = 0.05;
  setup.mapping.depth.sigma = 0.05;
  const DynamicSceneResult result = evaluateDynamicScene(setup);
  EXPECT_GT(result.object_voxels, 100u);
  EXPECT_GE(result.frames_to_clear, 1);
  EXPECT_LE(result.frames_to_clear, 8);
  EXPECT_EQ(result.ghost.back(), 0u);
}

// Point clouds of a standing camera: the box's top edge is passed only by rays that reach
// nothing within the camera's 8 m, which carry no free space, so it stays; the seen-through count
// leaves it out and falls below 5 % when OctoMap's update clears the rest.
TEST(DynamicScenes, WhatOnlyRaysWithoutAReturnPassIsNotSeenThrough) {
  const DynamicSceneCase setup = removedBox(DynamicMapper::kPointCloud);
  const DynamicSceneResult result = evaluateDynamicScene(setup);
  ASSERT_EQ(result.ghost_seen_through.size(), result.ghost.size());
  for (std::size_t i = 0; i < result.ghost.size(); ++i) {
    EXPECT_LE(result.ghost_seen_through[i], result.ghost[i]);
  }
  EXPECT_GT(result.object_voxels, 50u);
  EXPECT_GT(result.ghost.back(), result.object_voxels / 20);  // the edge stays
  EXPECT_EQ(result.frames_to_clear, -1);
  EXPECT_EQ(result.ghost_seen_through.back(), 0u);
  EXPECT_GE(result.frames_to_clear_seen_through, 1);
  EXPECT_LE(result.frames_to_clear_seen_through, 9);  // OctoMap's update: max / -miss
}

TEST(DynamicScenes, RejectsBadCases) {
  DynamicSceneCase setup;
  setup.resolution = 0.0;
  EXPECT_THROW(evaluateDynamicScene(setup), std::invalid_argument);
  setup = DynamicSceneCase();
  setup.speed = 5.0;
  EXPECT_THROW(evaluateDynamicScene(setup), std::invalid_argument);
  EXPECT_THROW(dynamicEventFromString("dog"), std::invalid_argument);
  EXPECT_EQ(dynamicMapperFromString("stereo_table_i"), DynamicMapper::kStereoTableI);
}

}  // namespace
}  // namespace occupancy_fusion
