// The Sec. 5.1 accuracy metric (eval/surface_accuracy) on tiny maps whose answers are known in
// closed form: a flat iso-surface between two slabs of voxels, unknown neighbours, and a
// 4 x 4 camera looking at a wall.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "occupancy_fusion/eval/surface_accuracy.h"

namespace occupancy_fusion {
namespace {

constexpr double kResolution = 0.1;

VoxelMapConfig mapConfig() {
  VoxelMapConfig config;
  config.resolution = kResolution;
  return config;
}

// Voxels x = 0 ... 14 (y, z in -4 ... 4): log-odds `in_front` for x < 5, `behind` for x >= 5,
// so the only label change is between the centres x = 0.45 and x = 0.55.
void fillSlab(float in_front, float behind, VoxelMap* map) {
  for (int x = 0; x < 15; ++x) {
    for (int y = -4; y <= 4; ++y) {
      for (int z = -4; z <= 4; ++z) map->setLogOdds({x, y, z}, x < 5 ? in_front : behind);
    }
  }
}

TEST(SurfaceAccuracy, CrossingInterpolatedBetweenOppositeCentres) {
  // Symmetric log-odds: the crossing lies half-way, on the plane x = 0.5.
  VoxelMap symmetric(mapConfig());
  fillSlab(-1.0f, 1.0f, &symmetric);
  EXPECT_NEAR(distanceToIsoSurface(symmetric, {0.53, 0.05, 0.05}), 0.03, 1e-9);
  EXPECT_NEAR(distanceToIsoSurface(symmetric, {0.42, 0.05, 0.05}), 0.08, 1e-9);
  // -1 at 0.45 and +3 at 0.55: zero a quarter of the way, at x = 0.475.
  VoxelMap skewed(mapConfig());
  fillSlab(-1.0f, 3.0f, &skewed);
  EXPECT_NEAR(distanceToIsoSurface(skewed, {0.5, 0.05, 0.05}), 0.025, 1e-9);
  // The plane is found from any point whose voxel lies within two voxels of it.
  EXPECT_NEAR(distanceToIsoSurface(skewed, {0.66, 0.05, 0.05}), 0.185, 1e-9);
}

TEST(SurfaceAccuracy, NoCrossingFarAwayOrInUniformLabels) {
  EXPECT_TRUE(std::isinf(distanceToIsoSurface(VoxelMap(mapConfig()), {0.0, 0.0, 0.0})));
  VoxelMap slab(mapConfig());
  fillSlab(-1.0f, 1.0f, &slab);
  // Three voxels behind the plane: beyond the search, so no crossing is reported (the nearest
  // one is farther than one voxel anyway).
  EXPECT_TRUE(std::isinf(distanceToIsoSurface(slab, {0.85, 0.05, 0.05})));
  // All free, with free neighbours on every side searched: no crossing.
  VoxelMap all_free(mapConfig());
  fillSlab(-1.0f, -1.0f, &all_free);
  EXPECT_TRUE(std::isinf(distanceToIsoSurface(all_free, {0.45, 0.05, 0.05})));
}

TEST(SurfaceAccuracy, UnknownReadsAsHalf) {
  // One occupied voxel alone: the iso-surface passes through its unknown neighbours' centres
  // (log-odds 0 there), one voxel from its own centre along each axis.
  VoxelMap map(mapConfig());
  map.setLogOdds({0, 0, 0}, 2.0f);
  EXPECT_NEAR(distanceToIsoSurface(map, {0.05, 0.05, 0.05}), 0.1, 1e-9);
  EXPECT_NEAR(distanceToIsoSurface(map, {0.17, 0.05, 0.05}), 0.02, 1e-9);
  // A free voxel next to unknown ones: 0 is "not occupied" like the free voxel, no crossing.
  VoxelMap free_only(mapConfig());
  free_only.setLogOdds({0, 0, 0}, -2.0f);
  EXPECT_TRUE(std::isinf(distanceToIsoSurface(free_only, {0.05, 0.05, 0.05})));
}

TEST(SurfaceAccuracy, OccupiedWithinOneVoxel) {
  VoxelMap map(mapConfig());
  map.setLogOdds({3, 3, 3}, 0.5f);
  map.setLogOdds({0, 0, 0}, -0.5f);
  EXPECT_TRUE(occupiedWithinOneVoxel(map, {0.25, 0.25, 0.25}));   // diagonal neighbour
  EXPECT_FALSE(occupiedWithinOneVoxel(map, {0.15, 0.35, 0.35}));  // two voxels away in x
  EXPECT_FALSE(occupiedWithinOneVoxel(map, {0.05, 0.05, 0.05}));  // only a free voxel near
}

TEST(SurfaceAccuracy, SurfacePointObservedOnlyWhereTheImageMeasuredIt) {
  CameraIntrinsics camera;
  camera.width = camera.height = 4;
  camera.fx = camera.fy = 4.0;
  camera.cx = camera.cy = 1.5;
  std::vector<float> depth(16, 2.0f);  // a wall 2 m in front
  depth[1 * 4 + 1] = std::numeric_limits<float>::quiet_NaN();
  PosedDepthView view;
  view.T_world_camera.translation() = Eigen::Vector3d(1.0, 0.0, 0.0);
  view.depth = {4, 4, depth.data()};
  const double tolerance = 0.01;
  // Camera (0.1, 0.1, z) projects onto pixel (1.7, 1.7) -> pixel (2, 2), depth 2.
  EXPECT_TRUE(observesSurfacePoint(view, camera, {1.1, 0.1, 2.005}, tolerance));
  EXPECT_FALSE(observesSurfacePoint(view, camera, {1.1, 0.1, 2.02}, tolerance));  // behind
  // Pixel (1, 1) holds no measurement.
  EXPECT_FALSE(observesSurfacePoint(view, camera, {1.0 - 0.05, -0.05, 2.0}, tolerance));
  EXPECT_FALSE(observesSurfacePoint(view, camera, {1.0 + 1.0, 0.0, 2.0}, tolerance));  // outside
  EXPECT_FALSE(observesSurfacePoint(view, camera, {1.0, 0.0, -2.0}, tolerance));  // behind camera
}

TEST(SurfaceAccuracy, ScoresCountPointsAndObservedFreeVoxels) {
  VoxelMap slab(mapConfig());
  fillSlab(-1.0f, 1.0f, &slab);
  // Beside a crossing (0.07 from the nearest, which lie on voxel-centre lines), 0.08 in front
  // of the plane, and 0.15 behind it.
  const SurfaceScores surface =
      scoreSurfacePoints(slab, {{0.5, 0.0, 0.0}, {0.42, 0.05, 0.05}, {0.65, 0.05, 0.05}});
  EXPECT_EQ(surface.points, 3u);
  EXPECT_EQ(surface.near_iso, 2u);
  EXPECT_EQ(surface.near_occupied, 3u);  // the first two have x = 0.55 voxels as neighbours
  // Ground truth: free for x < 0.3. Known voxels there: x = 0, 1, 2 times 81, all labelled free.
  // With x < 0.7 the x = 5, 6 layers (occupied) join as wrongly labelled.
  const FreeSpaceScores near =
      scoreFreeSpace(slab, [](const Eigen::Vector3d& c) { return c.x() < 0.3; });
  EXPECT_EQ(near.voxels, 3u * 81u);
  EXPECT_EQ(near.labelled_free, 3u * 81u);
  const FreeSpaceScores wide =
      scoreFreeSpace(slab, [](const Eigen::Vector3d& c) { return c.x() < 0.7; });
  EXPECT_EQ(wide.voxels, 7u * 81u);
  EXPECT_EQ(wide.labelled_free, 5u * 81u);
}

}  // namespace
}  // namespace occupancy_fusion
