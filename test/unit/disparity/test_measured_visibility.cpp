// unknown_neighbours: measured (parameter_set: measured, the mappers' default): a camera's first
// view of a wall is mapped at once, and patches of wrong disparity that stick to image positions
// leave nothing behind the wall and no phantom in front of it. Counted against the wall's
// analytic position, and against the paper's readings of unknown space on the same image.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "occupancy_fusion/integrators/stereo/visibility_stereo_integrator.h"

namespace occupancy_fusion {
namespace {

constexpr int kWidth = 64, kHeight = 48;
constexpr double kWallX = 2.0;  // m, a fronto-parallel wall 2 m in front of the camera
constexpr double kResolution = 0.1;
const StereoCamera kCamera{60.0, 60.0, 31.5, 23.5, 0.12};  // f b = 7.2 px m: d = 3.6 px at 2 m

Eigen::Isometry3d cameraPose() {
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  T_map_camera.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // optical z -> map x
  T_map_camera.translation() = Eigen::Vector3d(0.05, 0.05, 1.05);
  return T_map_camera;
}

// The wall's disparity everywhere, a 12 x 12 px patch shifted by `patch_offset` px at the centre.
std::vector<float> wallImage(float patch_offset) {
  std::vector<float> image(static_cast<std::size_t>(kWidth) * kHeight,
                           static_cast<float>(kCamera.fx * kCamera.baseline / kWallX));
  for (int v = 18; v < 30; ++v) {
    for (int u = 26; u < 38; ++u) image[static_cast<std::size_t>(v) * kWidth + u] += patch_offset;
  }
  return image;
}

struct OccupiedCounts {
  std::size_t on_wall = 0;   // the voxel holding the wall plane or the one behind it
  std::size_t behind = 0;    // farther than 0.3 m behind the wall
  std::size_t in_front = 0;  // nearer than 0.3 m in front of it
};

OccupiedCounts mapOnce(const VisibilityStereoConfig& config, const std::vector<float>& image) {
  VoxelMapConfig map_config;
  map_config.resolution = kResolution;
  VoxelMap map(map_config);
  const DisparityImageView view{kWidth, kHeight, image.data(), 0};
  VisibilityStereoIntegrator(config).integrate(view, kCamera, cameraPose(), &map);
  OccupiedCounts counts;
  map.forEachOccupiedVoxel([&](const VoxelIndex& index, float) {
    const double x = (index.x() + 0.5) * kResolution;
    if (x > kWallX + 0.3) {
      ++counts.behind;
    } else if (x < kWallX - 0.3) {
      ++counts.in_front;
    } else if (index.x() == 20 || index.x() == 21) {
      ++counts.on_wall;
    }
  });
  return counts;
}

VisibilityStereoConfig withUnknownNeighbours(UnknownNeighbours policy) {
  VisibilityStereoConfig config = visibilityStereoConfigFor(StereoParameterSet::kMeasured);
  config.unknown_neighbours = policy;
  return config;
}

const VisibilityStereoConfig kMeasured = visibilityStereoConfigFor(StereoParameterSet::kMeasured);

TEST(MeasuredVisibilityTest, TheFirstViewOfAWallIsMappedAtOnce) {
  // The wall seen from 2 m covers 2.1 x 1.6 m: about 21 x 16 voxels of 0.1 m.
  const OccupiedCounts measured = mapOnce(kMeasured, wallImage(0.0f));
  EXPECT_GE(measured.on_wall, 250u);
  EXPECT_EQ(measured.behind, 0u);
  EXPECT_EQ(measured.in_front, 0u);
  // Table I's reading (unknown space occludes as P(O) = 0.5) reaches 4 voxels deep per frame.
  const OccupiedCounts table_i = mapOnce(VisibilityStereoConfig(), wallImage(0.0f));
  EXPECT_EQ(table_i.on_wall, 0u);
}

TEST(MeasuredVisibilityTest, APatchShiftedAwayLeavesNothingBehindTheWall) {
  // -1.5 px: the patch's 144 pixels say 3.4 m, 1.4 m behind the wall.
  const std::vector<float> image = wallImage(-1.5f);
  const OccupiedCounts measured = mapOnce(kMeasured, image);
  EXPECT_EQ(measured.behind, 0u);
  EXPECT_GE(measured.on_wall, 200u);
  // Unknown space read as transparent (the paper's known_only variant) maps the patch.
  const OccupiedCounts transparent =
      mapOnce(withUnknownNeighbours(UnknownNeighbours::kKnownOnly), image);
  EXPECT_GE(transparent.behind, 4u);
}

TEST(MeasuredVisibilityTest, APatchShiftedTowardsTheCameraMapsNoPhantom) {
  // +1.5 px: a phantom surface at 1.41 m, 0.6 m in front of the wall.
  const std::vector<float> image = wallImage(+1.5f);
  const OccupiedCounts measured = mapOnce(kMeasured, image);
  EXPECT_EQ(measured.in_front, 0u);
  VisibilityStereoConfig octomap = kMeasured;
  octomap.method = StereoIntegrationMethod::kOctomap;
  EXPECT_GE(mapOnce(octomap, image).in_front, 4u);
  // Each part of the measured reading is needed for this: without the cap on P(I_v) and the
  // measured prior, the phantom's own rays put their hit into space the frame shows free.
  VisibilityStereoConfig without_cap = kMeasured;
  without_cap.measured_inside = false;
  without_cap.measured_prior = false;
  EXPECT_GE(mapOnce(without_cap, image).in_front, 4u);
}

TEST(MeasuredVisibilityTest, ASurfaceNextToAnInvalidRegionIsMappedAtOnce) {
  // A wall 4 m ahead below the optical axis only; above it no disparity (beyond the matcher's
  // range). The camera at 1.02 m: the voxels of the 1.0-1.1 m layer that the rays to the wall's
  // top rows cross have their centres (1.05 m) above the axis, in the invalid half, up to 2 m out
  // (a 0.1 m voxel is 30 px wide at 1 m here). The nearest surface in a voxel's image says that
  // it lies well in front of the wall; read as unknown (P(O) = 0.5, Table I's reading), each such
  // neighbour took 0.4 of a ray's visibility, and the rays stopped about 0.5 m out.
  constexpr int kW = 320, kH = 240;
  const StereoCamera camera{300.0, 300.0, 159.5, 119.5, 0.12};  // d = 9 px at 4 m
  constexpr double kFarWallX = 4.0;
  std::vector<float> image(static_cast<std::size_t>(kW) * kH,
                           static_cast<float>(camera.fx * camera.baseline / kFarWallX));
  std::fill(image.begin(), image.begin() + static_cast<std::size_t>(kW) * (kH / 2),
            std::numeric_limits<float>::quiet_NaN());
  Eigen::Isometry3d pose = cameraPose();
  pose.translation() = Eigen::Vector3d(0.05, 0.05, 1.02);
  VoxelMapConfig map_config;
  map_config.resolution = kResolution;
  VoxelMap map(map_config);
  const DisparityImageView view{kW, kH, image.data(), 0};
  VisibilityStereoIntegrator(kMeasured).integrate(view, camera, pose, &map);
  // The wall's voxels (x index 40 or 41) by height layer: rows 120 to 239 see it from 1.02 m down
  // to 0 m, 4.3 m wide (about 43 voxels).
  std::vector<int> per_layer(11, 0);
  std::size_t behind = 0, in_front = 0;
  map.forEachOccupiedVoxel([&](const VoxelIndex& index, float) {
    const double x = (index.x() + 0.5) * kResolution;
    if (x > kFarWallX + 0.3) ++behind;
    if (x < kFarWallX - 0.3) ++in_front;
    if ((index.x() == 40 || index.x() == 41) && index.z() >= 0 && index.z() <= 10) {
      ++per_layer[index.z()];
    }
  });
  for (int layer = 1; layer <= 10; ++layer) EXPECT_GE(per_layer[layer], 38) << "layer " << layer;
  EXPECT_EQ(behind, 0u);
  EXPECT_EQ(in_front, 0u);
}

TEST(MeasuredVisibilityTest, NamesAndValidation) {
  EXPECT_EQ(stereoParameterSetFromString("measured"), StereoParameterSet::kMeasured);
  EXPECT_EQ(toString(StereoParameterSet::kMeasured), "measured");
  EXPECT_EQ(unknownNeighboursFromString("measured"), UnknownNeighbours::kMeasured);
  EXPECT_EQ(toString(UnknownNeighbours::kMeasured), "measured");
  EXPECT_EQ(kMeasured.unknown_neighbours, UnknownNeighbours::kMeasured);
  // Table I's values otherwise.
  EXPECT_EQ(kMeasured.visibility_min, VisibilityStereoConfig().visibility_min);
  EXPECT_EQ(kMeasured.prob_hit_invisible, VisibilityStereoConfig().prob_hit_invisible);
  VisibilityStereoConfig bad = kMeasured;
  bad.measured_sigma_min_voxels = 0.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = kMeasured;
  bad.measured_sigma_max_voxels = 0.5;  // below the minimum
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = kMeasured;
  bad.measured_surface.window_px = 0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(MeasuredVisibilityTest, StageTimesSplitTheCall) {
  // What a frame's time is spent on: each stage is timed once, in turn, within the call.
  VoxelMapConfig map_config;
  map_config.resolution = kResolution;
  VoxelMap map(map_config);
  const std::vector<float> image = wallImage(0.0f);
  const DisparityImageView view{kWidth, kHeight, image.data(), 0};
  const VisibilityStereoIntegrator integrator(kMeasured);
  for (int frame = 0; frame < 3; ++frame) {
    const StereoIntegrationStats stats = integrator.integrate(view, kCamera, cameraPose(), &map);
    ASSERT_GT(stats.rays, 0u);
    for (double stage : {stats.conversion_seconds, stats.bundling_seconds, stats.walk_seconds,
                         stats.write_seconds}) {
      EXPECT_GT(stage, 0.0);
    }
    EXPECT_LE(stats.conversion_seconds + stats.bundling_seconds + stats.walk_seconds +
                  stats.write_seconds,
              stats.seconds);
  }
  // Points given as points: nothing to convert.
  const StereoIntegrationStats points = integrator.integrate(
      {Eigen::Vector3f(2.0f, 0.0f, 1.0f)}, {0.01f}, cameraPose().translation(), &map);
  EXPECT_EQ(points.conversion_seconds, 0.0);
  EXPECT_GT(points.walk_seconds, 0.0);
}

}  // namespace
}  // namespace occupancy_fusion
