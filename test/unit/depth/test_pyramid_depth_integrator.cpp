// Per-voxel interpolation (Eq. 15-17), Andert's lookup, and whole-frame integration of analytic
// depth images: a fronto-parallel wall and images with invalid pixels.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"

namespace occupancy_fusion {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

CameraIntrinsics smallCamera(int width, int height, double focal) {
  CameraIntrinsics camera;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = focal;
  camera.cx = 0.5 * (width - 1);
  camera.cy = 0.5 * (height - 1);
  return camera;
}

// z-depth that makes pixel (u, v) measure the given distance (Eq. 6 inverted).
float depthFor(const CameraIntrinsics& camera, int u, int v, double distance) {
  return static_cast<float>(distance / camera.pixelRay(u, v).norm());
}

// The point at `distance` from the camera centre on the ray through pixel coordinates (u, v).
Eigen::Vector3d pointOnRay(const CameraIntrinsics& camera, double u, double v, double distance) {
  return distance * camera.pixelRay(u, v).normalized();
}

TEST(PyramidDepthIntegrator, Eq15BilinearInterpolationOfLogOdds) {
  const CameraIntrinsics camera = smallCamera(4, 4, 2.0);  // t0 = 2 * 0.1 = 0.2 m
  std::vector<float> depth(16);
  for (int v = 0; v < 4; ++v) {
    for (int u = 0; u < 4; ++u) depth[v * 4 + u] = depthFor(camera, u, v, 2.0);
  }
  depth[2 * 4 + 1] = depthFor(camera, 1, 2, 1.8);
  depth[2 * 4 + 2] = depthFor(camera, 2, 2, 2.0);
  depth[3 * 4 + 1] = depthFor(camera, 1, 3, 2.2);
  depth[3 * 4 + 2] = depthFor(camera, 2, 3, 1.9);
  PyramidDepthConfig config;
  config.min_range = 0.05;
  const PyramidDepthIntegrator integrator(config);
  const DepthInverseModel& model = integrator.model();
  // A voxel at 1.9 m (beyond t0: layer 0 alone) projecting to (1.3, 2.6): <u> = 0.3, <v> = 0.6,
  // weights 0.7*0.4, 0.3*0.4, 0.7*0.6, 0.3*0.6 on pixels (1,2), (2,2), (1,3), (2,3).
  const double z = 1.9;
  const Eigen::Vector3d voxel = pointOnRay(camera, 1.3, 2.6, z);
  DepthFrame frame =
      integrator.prepare({4, 4, depth.data()}, camera, Eigen::Isometry3d::Identity(), 0.1);
  const double expected = 0.28 * model.logOdds(z, 1.8) + 0.12 * model.logOdds(z, 2.0) +
                          0.42 * model.logOdds(z, 2.2) + 0.18 * model.logOdds(z, 1.9);
  const std::optional<float> value = integrator.voxelLogOdds(frame, voxel);
  ASSERT_TRUE(value.has_value());
  EXPECT_NEAR(*value, expected, 1e-5);

  // An invalid neighbour drops out and the remaining weights are renormalised.
  depth[3 * 4 + 2] = kNaN;
  frame = integrator.prepare({4, 4, depth.data()}, camera, Eigen::Isometry3d::Identity(), 0.1);
  const double renormalised =
      (0.28 * model.logOdds(z, 1.8) + 0.12 * model.logOdds(z, 2.0) + 0.42 * model.logOdds(z, 2.2)) /
      0.82;
  ASSERT_TRUE(integrator.voxelLogOdds(frame, voxel).has_value());
  EXPECT_NEAR(*integrator.voxelLogOdds(frame, voxel), renormalised, 1e-5);
}

// 16 x 16 image, f = 16, r = 0.1: t0 = 1.6 m, t1 = 0.8 m. Pixels with even u and v measure A,
// the others B, so layer 1 (closest to t1) holds B everywhere and Andert's min layer too.
class TwoLayerImage : public ::testing::Test {
 protected:
  static constexpr double kA = 1.3;
  static constexpr double kB = 0.85;
  void SetUp() override {
    camera_ = smallCamera(16, 16, 16.0);
    depth_.resize(256);
    for (int v = 0; v < 16; ++v) {
      for (int u = 0; u < 16; ++u) {
        depth_[v * 16 + u] = depthFor(camera_, u, v, (u % 2 == 0 && v % 2 == 0) ? kA : kB);
      }
    }
  }
  std::optional<float> logOddsAt(DepthMethod method, double distance) const {
    PyramidDepthConfig config;
    config.method = method;
    const PyramidDepthIntegrator integrator(config);
    const DepthFrame frame =
        integrator.prepare({16, 16, depth_.data()}, camera_, Eigen::Isometry3d::Identity(), 0.1);
    return integrator.voxelLogOdds(frame, pointOnRay(camera_, 6.0, 6.0, distance));
  }
  CameraIntrinsics camera_;
  std::vector<float> depth_;
};

TEST_F(TwoLayerImage, Eq17InterpolatesLinearlyBetweenTheBracketingLayers) {
  const DepthInverseModel model{PyramidDepthConfig()};
  const double z = 1.2;                    // t1 = 0.8 < z <= t0 = 1.6: layers 0 and 1
  const double l0 = model.logOdds(z, kA);  // pixel (6, 6) itself
  const double l1 = model.logOdds(z, kB);  // every layer-1 cell
  const double expected = l0 + (z - 1.6) * (l1 - l0) / (0.8 - 1.6);
  ASSERT_GT(std::abs(l1 - l0), 0.3);  // the two layers really differ
  const std::optional<float> value = logOddsAt(DepthMethod::kPyramid, z);
  ASSERT_TRUE(value.has_value());
  EXPECT_NEAR(*value, expected, 1e-4);
  // At t0 layer 0 alone counts; beyond t0 too.
  EXPECT_NEAR(*logOddsAt(DepthMethod::kPyramid, 1.6), model.logOdds(1.6, kA), 1e-4);
  EXPECT_NEAR(*logOddsAt(DepthMethod::kPyramid, 1.7), model.logOdds(1.7, kA), 1e-4);
}

TEST_F(TwoLayerImage, AndertReadsTheNearestMinimumLayerWithoutInterpolation) {
  const DepthInverseModel model{PyramidDepthConfig()};
  // Footprint t0 / z = 1.78 px rounds to layer 1 (min of each 2 x 2 block: B).
  EXPECT_NEAR(*logOddsAt(DepthMethod::kAndert, 0.9), model.logOdds(0.9, kB), 1e-5);
  // Footprint 1.07 px rounds to layer 0: the pixel itself, A.
  EXPECT_NEAR(*logOddsAt(DepthMethod::kAndert, 1.5), model.logOdds(1.5, kA), 1e-5);
}

// A fronto-parallel wall at z-depth 2 m before a 64 x 48 camera (f = 50, so t0 = 2.5 m at
// 5 cm), sigma = 5 cm: free in front, occupied at the wall, unknown behind it, for each method.
class WallTest : public ::testing::TestWithParam<DepthMethod> {
 protected:
  static constexpr double kWall = 2.0;
  static constexpr double kResolution = 0.05;
  WallTest() : map_(mapConfig()) {
    camera_ = smallCamera(64, 48, 50.0);
    config_.k = 0.05;
    config_.sigma = 0.05;
    config_.method = GetParam();
  }
  static VoxelMapConfig mapConfig() {
    VoxelMapConfig config;
    config.resolution = kResolution;
    return config;
  }
  CameraIntrinsics camera_;
  PyramidDepthConfig config_;
  VoxelMap map_;
};

TEST_P(WallTest, FreeInFrontOccupiedAtTheWallUnknownBehind) {
  const std::vector<float> depth(64 * 48, static_cast<float>(kWall));
  const PyramidDepthIntegrator integrator(config_);
  const DepthImageView view{64, 48, depth.data()};
  const DepthIntegrationStats stats =
      integrator.integrate(view, camera_, Eigen::Isometry3d::Identity(), &map_);
  EXPECT_GT(stats.voxels_updated, 10000u);
  EXPECT_EQ(stats.blocks_updated, map_.blockCount());
  EXPECT_EQ(stats.voxels_updated, map_.knownVoxelCount());
  EXPECT_LE(stats.blocks_updated, stats.candidate_blocks);

  // Along the optical axis (voxel column x, y in [0, 0.05)).
  const float far_in_front = std::log(0.3f / 0.7f);  // Eq. 7 more than 8 sigma in front
  for (int k = 6; k < 34; ++k) {                     // centres 0.325 ... 1.675 m
    const std::optional<float> value = map_.logOdds(VoxelIndex(0, 0, k));
    ASSERT_TRUE(value.has_value()) << k;
    EXPECT_NEAR(*value, far_in_front, 1e-3) << k;
  }
  const std::optional<float> at_wall = map_.logOdds(VoxelIndex(0, 0, 39));  // 1.95 ... 2.0 m
  ASSERT_TRUE(at_wall.has_value());
  EXPECT_EQ(map_.classify(*at_wall), Occupancy::kOccupied);
  EXPECT_GT(*at_wall, 1.0f);
  for (int k = 44; k < 60; ++k) EXPECT_FALSE(map_.logOdds(VoxelIndex(0, 0, k))) << k;

  // Everywhere: no known voxel behind the wall's 3-sigma band, each known voxel projects into
  // the image and holds exactly the per-voxel value (one frame, within the clamping bounds).
  const DepthFrame frame =
      integrator.prepare(view, camera_, Eigen::Isometry3d::Identity(), kResolution);
  std::size_t free_in_front = 0, mismatches = 0;
  double farthest = 0.0;
  map_.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    const Eigen::Vector3d center = map_.centerOf(index);
    farthest = std::max(farthest, center.z());
    const std::optional<float> expected = integrator.voxelLogOdds(frame, center);
    if (!expected || std::abs(*expected - log_odds) > 1e-6f) ++mismatches;
    if (center.z() < 1.7 && log_odds < 0.0f) ++free_in_front;
  });
  EXPECT_EQ(mismatches, 0u);
  EXPECT_LT(farthest, kWall + 3 * config_.sigma + 0.01);
  // Voxels in the frustum with centres at z in (0.3, 1.7), at least one pixel inside the image
  // border: all of them known and free.
  std::size_t in_frustum = 0, free_there = 0;
  for (int kz = 6; kz < 34; ++kz) {
    for (int ky = -30; ky < 30; ++ky) {
      for (int kx = -40; kx < 40; ++kx) {
        const Eigen::Vector3d c = map_.centerOf(VoxelIndex(kx, ky, kz));
        const Eigen::Vector2d uv = camera_.project(c);
        if (uv.x() < 0.5 || uv.x() > 62.5 || uv.y() < 0.5 || uv.y() > 46.5) continue;
        ++in_frustum;
        const std::optional<float> value = map_.logOdds(VoxelIndex(kx, ky, kz));
        if (value && *value < 0.0f) ++free_there;
      }
    }
  }
  EXPECT_GT(in_frustum, 5000u);
  EXPECT_EQ(free_there, in_frustum);
  EXPECT_GE(free_in_front, free_there);
}

TEST_P(WallTest, EveryVoxelOfTheFrustumGetsItsPerVoxelValueUnderATiltedPose) {
  // A tilted, offset camera: voxel rows cross the image border obliquely, so integrate()'s
  // per-row skipping of voxels outside the image must keep every voxel that projects inside.
  std::vector<float> depth(64 * 48);
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) depth[v * 64 + u] = static_cast<float>(1.2 + 0.02 * u);
  }
  const Eigen::Isometry3d pose =
      Eigen::Translation3d(0.13, -0.27, 0.41) *
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1.0, 2.0, -0.5).normalized());
  const PyramidDepthIntegrator integrator(config_);
  const DepthImageView view{64, 48, depth.data()};
  integrator.integrate(view, camera_, pose, &map_);
  const DepthFrame frame = integrator.prepare(view, camera_, pose, kResolution);
  std::size_t expected_known = 0, mismatches = 0;
  for (const BlockIndex& block : integrator.candidateBlocks(frame)) {
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
      const VoxelIndex index = VoxelMap::voxelIndex(block, linear);
      const std::optional<float> expected = integrator.voxelLogOdds(frame, map_.centerOf(index));
      const std::optional<float> stored = map_.logOdds(index);
      expected_known += expected.has_value();
      if (expected.has_value() != stored.has_value() || (expected && *expected != *stored)) {
        ++mismatches;
      }
    }
  }
  EXPECT_GT(expected_known, 5000u);
  EXPECT_EQ(expected_known, map_.knownVoxelCount());
  EXPECT_EQ(mismatches, 0u);
}

// Voxels clamped free in front of every surface they see are skipped (their update is a no-op):
// frames from a camera moving past a slanted wall, mapped until most of the free space is
// clamped, give the map voxel-by-voxel updates give, bit for bit, with many voxels skipped.
TEST_P(WallTest, SkippingClampedFreeVoxelsLeavesTheMapBitForBit) {
  if (GetParam() == DepthMethod::kIdeal) GTEST_SKIP() << "Eq. 8-9 read every pixel ray: no skip";
  std::vector<float> depth(64 * 48);
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) depth[v * 64 + u] = static_cast<float>(1.6 + 0.015 * u);
  }
  depth[5 * 64 + 7] = std::nanf("");  // an invalid pixel: its cells give nothing
  const DepthImageView view{64, 48, depth.data()};
  const PyramidDepthIntegrator integrator(config_);
  VoxelMap reference(mapConfig());
  std::size_t skipped = 0;
  for (int frame_number = 0; frame_number < 12; ++frame_number) {
    const Eigen::Isometry3d pose =
        Eigen::Translation3d(0.013 * frame_number, -0.007 * frame_number, 0.0) *
        Eigen::AngleAxisd(0.01 * frame_number, Eigen::Vector3d::UnitY());
    skipped += integrator.integrate(view, camera_, pose, &map_).voxels_unchanged;
    const DepthFrame frame = integrator.prepare(view, camera_, pose, kResolution);
    for (const BlockIndex& block : integrator.candidateBlocks(frame)) {
      for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
        const VoxelIndex index = VoxelMap::voxelIndex(block, linear);
        const std::optional<float> delta =
            integrator.voxelLogOdds(frame, reference.centerOf(index));
        if (delta) reference.updateVoxel(index, *delta);
      }
    }
  }
  EXPECT_GT(skipped, 20000u);
  EXPECT_EQ(map_.knownVoxelCount(), reference.knownVoxelCount());
  std::size_t mismatches = 0;
  reference.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    const std::optional<float> value = map_.logOdds(index);
    if (!value || *value != log_odds) ++mismatches;
  });
  EXPECT_EQ(mismatches, 0u);
}

// clear_passed: a wall at 2 m mapped until clamped, then gone (the camera sees a wall at 4 m
// behind it). Eq. 7's constant logit(0.3) = -0.85 needs ceil(3.51 / 0.85) = 5 frames to bring
// the clamped voxels to free, the passed miss logit(0.25) = -1.10 ceil(3.51 / 1.10) = 4.
int framesUntilTheWallLeft(PyramidDepthConfig config, const CameraIntrinsics& camera,
                           double resolution) {
  VoxelMapConfig map_config;
  map_config.resolution = resolution;
  VoxelMap map(map_config);
  const PyramidDepthIntegrator integrator(config);
  const std::vector<float> near_wall(64 * 48, 2.0f), far_wall(64 * 48, 4.0f);
  for (int i = 0; i < 10; ++i) {
    integrator.integrate({64, 48, near_wall.data()}, camera, Eigen::Isometry3d::Identity(), &map);
  }
  const auto occupied_at_the_wall = [&] {
    std::size_t count = 0;
    map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
      const double z = map.centerOf(index).z();
      count += (z > 1.9 && z < 2.1 && log_odds > 0.0f) ? 1 : 0;
    });
    return count;
  };
  const std::size_t before = occupied_at_the_wall();
  EXPECT_GT(before, 500u);
  for (int frames = 1; frames <= 10; ++frames) {
    integrator.integrate({64, 48, far_wall.data()}, camera, Eigen::Isometry3d::Identity(), &map);
    if (occupied_at_the_wall() < before / 100) return frames;
  }
  return -1;
}

TEST(PyramidDepthIntegrator, ClearPassedClearsWhatLeftInFourFrames) {
  for (DepthMethod method : {DepthMethod::kPyramid, DepthMethod::kAndert}) {
    PyramidDepthConfig config;
    config.k = 0.05;
    config.sigma = 0.05;
    config.method = method;
    const CameraIntrinsics camera = smallCamera(64, 48, 50.0);
    EXPECT_EQ(framesUntilTheWallLeft(config, camera, 0.05), 5) << toString(method);
    config.clear_passed = true;
    EXPECT_EQ(framesUntilTheWallLeft(config, camera, 0.05), 4) << toString(method);
  }
}

// clear_passed beside a nearer surface: the left half of the image sees a wall at 1 m, the
// right half a panel at 2 m (10 frames), then, the panel gone, `without`. Returns the panel's
// occupied voxels whose centre projects within 3 px right of the edge (32.5) after `frames`
// frames of `without`, and in *near_wall the near wall's occupied voxels.
std::size_t panelLeftBesideANearerWall(const std::vector<float>& without, bool clear_passed,
                                       int frames, std::size_t* near_wall) {
  const CameraIntrinsics camera = smallCamera(64, 48, 50.0);
  std::vector<float> with_panel(64 * 48);
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) with_panel[v * 64 + u] = u < 33 ? 1.0f : 2.0f;  // odd edge
  }
  PyramidDepthConfig config;
  config.k = 0.05;
  config.sigma = 0.05;
  config.clear_passed = clear_passed;
  const PyramidDepthIntegrator integrator(config);
  VoxelMapConfig map_config;
  map_config.resolution = 0.1;  // a voxel covers 2.5 px at 2 m: pyramid layer 1
  VoxelMap map(map_config);
  for (int i = 0; i < 10; ++i) {
    integrator.integrate({64, 48, with_panel.data()}, camera, Eigen::Isometry3d::Identity(), &map);
  }
  for (int i = 0; i < frames; ++i) {
    integrator.integrate({64, 48, without.data()}, camera, Eigen::Isometry3d::Identity(), &map);
  }
  std::size_t panel = 0;
  *near_wall = 0;
  map.forEachOccupiedVoxel([&](const VoxelIndex& index, float) {
    const Eigen::Vector3d centre = map.centerOf(index);
    const double u = camera.project(centre).x();
    if (centre.z() > 1.85 && centre.z() < 2.15 && u >= 32.5 && u < 35.5) ++panel;
    if (centre.z() > 0.85 && centre.z() < 1.15 && u < 32.0) ++*near_wall;
  });
  return panel;
}

// Pyramid cells of 2 x 2 pixels and more keep the nearest measurement (Eq. 10-11), so the
// panel's voxels within a cell of the edge read the near wall too, behind which Eq. 7 says
// nothing: their update is a fraction of a free one, and the passed miss, which needs a whole
// one, never comes. Their centre pixels see 1 m beyond and no pixel of their footprint ends in
// them: passed. The near wall, which rays still end on, stays.
TEST(PyramidDepthIntegrator, ClearPassedClearsWhatLeftBesideANearerSurface) {
  std::vector<float> without(64 * 48);
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) without[v * 64 + u] = u < 33 ? 1.0f : 3.0f;
  }
  std::size_t near_wall = 0;
  const std::size_t held = panelLeftBesideANearerWall(without, true, 0, &near_wall);
  EXPECT_GT(held, 20u);
  const std::size_t near_wall_before = near_wall;
  EXPECT_GT(near_wall_before, 100u);
  EXPECT_GT(panelLeftBesideANearerWall(without, false, 5, &near_wall), held / 2);  // the paper's
  EXPECT_EQ(panelLeftBesideANearerWall(without, true, 5, &near_wall), 0u);
  EXPECT_EQ(near_wall, near_wall_before);
}

// The same panel gone, but behind it every other pixel has no return (a checkerboard, as rays
// past a door's edge into an open room): many of the edge voxels' centre pixels say nothing, a
// neighbour within half a voxel side of the centre's projection (1.25 px) sees 1 m beyond. Those
// rays pass through the voxel itself: passed as well.
TEST(PyramidDepthIntegrator, ClearPassedAsksTheRaysThroughAVoxelWhoseCentreHasNoReturn) {
  std::vector<float> without(64 * 48);
  std::size_t no_return = 0;
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) {
      const bool hole = u >= 33 && (u + v) % 2 == 0;
      without[v * 64 + u] = u < 33 ? 1.0f : (hole ? kNaN : 3.0f);
      no_return += hole ? 1 : 0;
    }
  }
  EXPECT_EQ(no_return, 31u * 24u);
  std::size_t near_wall = 0;
  const std::size_t held = panelLeftBesideANearerWall(without, true, 0, &near_wall);
  const std::size_t near_wall_before = near_wall;
  EXPECT_GT(held, 20u);
  EXPECT_EQ(panelLeftBesideANearerWall(without, true, 5, &near_wall), 0u);
  EXPECT_EQ(near_wall, near_wall_before);
}

// Only rays through the voxel count: a wall at 2 m mapped, then a checkerboard in front of it
// (1.5 m) and behind it (3 m). With 0.02 m voxels a voxel's disc (half its side, 0.25 px at 2 m)
// holds one pixel or two: a voxel whose disc holds only pixels in front of it is never passed,
// though a pixel beside its disc sees 1 m beyond; one whose disc holds a pixel beyond is.
TEST(PyramidDepthIntegrator, ClearPassedAsksOnlyTheRaysThroughTheVoxel) {
  const CameraIntrinsics camera = smallCamera(64, 48, 50.0);
  PyramidDepthConfig config;
  config.k = 0.05;
  config.sigma = 0.05;
  config.clear_passed = true;
  const PyramidDepthIntegrator integrator(config);
  // Off the voxel grid by a fraction of a pixel, so that the voxels' centres fall anywhere
  // between pixels.
  const Eigen::Isometry3d pose(Eigen::Translation3d(0.0037, 0.0061, 0.0));
  const Eigen::Isometry3d from_map = pose.inverse();
  VoxelMapConfig map_config;
  map_config.resolution = 0.02;
  VoxelMap map(map_config);
  const std::vector<float> wall(64 * 48, 2.0f);
  std::vector<float> checkerboard(64 * 48);
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) checkerboard[v * 64 + u] = (u + v) % 2 == 0 ? 1.5f : 3.0f;
  }
  for (int i = 0; i < 10; ++i) {
    integrator.integrate({64, 48, wall.data()}, camera, pose, &map);
  }
  std::vector<VoxelIndex> held;
  map.forEachOccupiedVoxel([&](const VoxelIndex& index, float) {
    const Eigen::Vector3d centre = map.centerOf(index);
    const Eigen::Vector2d uv = camera.project(from_map * centre);
    const bool near_axis = std::abs(uv.x() - camera.cx) < 8 && std::abs(uv.y() - camera.cy) < 8;
    if (std::abs(centre.z() - 2.0) < 0.03 && near_axis) held.push_back(index);
  });
  ASSERT_GT(held.size(), 200u);
  for (int i = 0; i < 5; ++i) {
    integrator.integrate({64, 48, checkerboard.data()}, camera, pose, &map);
  }
  std::size_t in_front_only = 0, in_front_only_cleared = 0, beyond = 0, beyond_cleared = 0;
  for (const VoxelIndex& index : held) {
    const Eigen::Vector3d centre = map.centerOf(index);
    const Eigen::Vector2d uv = camera.project(from_map * centre);
    const double inner = 0.5 * map_config.resolution * camera.fx / centre.z();
    // Independently: whether a pixel behind the voxel (odd u + v) lies in its disc.
    bool sees_beyond = (std::lround(uv.x()) + std::lround(uv.y())) % 2 == 1;
    for (int pv = static_cast<int>(uv.y()) - 1; pv <= static_cast<int>(uv.y()) + 2; ++pv) {
      for (int pu = static_cast<int>(uv.x()) - 1; pu <= static_cast<int>(uv.x()) + 2; ++pu) {
        const bool in_disc = std::hypot(pu - uv.x(), pv - uv.y()) <= inner;
        sees_beyond = sees_beyond || (in_disc && (pu + pv) % 2 == 1);
      }
    }
    const bool cleared = !(*map.logOdds(index) > 0.0f);
    (sees_beyond ? beyond : in_front_only) += 1;
    (sees_beyond ? beyond_cleared : in_front_only_cleared) += cleared ? 1 : 0;
  }
  EXPECT_GT(in_front_only, 50u);
  EXPECT_EQ(in_front_only_cleared, 0u);
  EXPECT_GT(beyond, 50u);
  EXPECT_EQ(beyond_cleared, beyond);
}

TEST_P(WallTest, InvalidPixelsChangeNothing) {
  // 0, NaN and beyond max_range (10 m) everywhere: no block allocated, a prior value untouched.
  std::vector<float> depth(64 * 48, 0.0f);
  for (std::size_t i = 0; i < depth.size(); i += 3) depth[i] = kNaN;
  for (std::size_t i = 1; i < depth.size(); i += 3) depth[i] = 50.0f;
  map_.updateVoxel(VoxelIndex(0, 0, 20), 1.25f);
  const PyramidDepthIntegrator integrator(config_);
  const DepthIntegrationStats stats =
      integrator.integrate({64, 48, depth.data()}, camera_, Eigen::Isometry3d::Identity(), &map_);
  EXPECT_EQ(stats.voxels_updated, 0u);
  EXPECT_EQ(stats.blocks_updated, 0u);
  EXPECT_EQ(map_.blockCount(), 1u);
  EXPECT_EQ(map_.knownVoxelCount(), 1u);
  EXPECT_FLOAT_EQ(*map_.logOdds(VoxelIndex(0, 0, 20)), 1.25f);
}

TEST_P(WallTest, InvalidHalfOfTheImageLeavesItsVoxelsUnknown) {
  // Left half (u < 32) sees the wall, the right half has no measurement.
  std::vector<float> depth(64 * 48, static_cast<float>(kWall));
  for (int v = 0; v < 48; ++v) {
    for (int u = 32; u < 64; ++u) depth[v * 64 + u] = kNaN;
  }
  const PyramidDepthIntegrator integrator(config_);
  integrator.integrate({64, 48, depth.data()}, camera_, Eigen::Isometry3d::Identity(), &map_);
  std::size_t left_known = 0, right_known = 0;
  map_.forEachKnownVoxel([&](const VoxelIndex& index, float) {
    const Eigen::Vector3d center = map_.centerOf(index);
    const double u = camera_.project(center).x();
    // From 1 m on, pyramid cells are at most 4 px wide: 12 px from the border is out of reach.
    if (center.z() >= 1.0 && u >= 44.0) ++right_known;
    if (u < 28.0) ++left_known;
  });
  EXPECT_GT(left_known, 3000u);
  EXPECT_EQ(right_known, 0u);
}

TEST_P(WallTest, RejectsAnImageOfTheWrongSize) {
  const std::vector<float> depth(10 * 10, 1.0f);
  const PyramidDepthIntegrator integrator(config_);
  EXPECT_THROW(
      integrator.integrate({10, 10, depth.data()}, camera_, Eigen::Isometry3d::Identity(), &map_),
      std::invalid_argument);
}

INSTANTIATE_TEST_SUITE_P(AllMethods, WallTest,
                         ::testing::Values(DepthMethod::kPyramid, DepthMethod::kAndert,
                                           DepthMethod::kIdeal),
                         [](const ::testing::TestParamInfo<DepthMethod>& info) {
                           return toString(info.param);
                         });

}  // namespace
}  // namespace occupancy_fusion
