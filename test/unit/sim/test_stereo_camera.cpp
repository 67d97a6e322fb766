// Disparity rendering: d = f b / z, and the error model's layout, persistence and statistics.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <tuple>

#include "occupancy_fusion/sim/stereo_camera.h"
#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {
namespace sim {
namespace {

PinholeCamera camera160() {
  PinholeCamera camera;
  camera.width = 160;
  camera.height = 120;
  camera.fx = camera.fy = 200.0;
  camera.cx = 79.5;
  camera.cy = 59.5;
  return camera;
}

// A tilted wall so the disparity varies across the image, seen from the origin along +x.
Scene tiltedWall() {
  Scene scene;
  scene.add(Plane{{4, 0, 0}, Eigen::Vector3d(-1, 0.3, -0.2).normalized()});
  return scene;
}

const Eigen::Isometry3d kPose = opticalFrameInBody();

TEST(StereoCameraTest, NoiselessDisparityIsFocalTimesBaselineOverZ) {
  const Scene scene = tiltedWall();
  const PinholeCamera camera = camera160();
  const DisparityImage disparity = renderDisparity(scene, camera, 0.12, kPose, 50.0);
  const DepthImage depth = renderDepth(scene, camera, kPose, 50.0);
  EXPECT_EQ(disparity.focal_px, 200.0);
  EXPECT_EQ(disparity.baseline_m, 0.12);
  // Near the centre z is about 4, so d is about 200 * 0.12 / 4 = 6.
  EXPECT_NEAR(disparity.at(80, 60), 200.0 * 0.12 / depth.at(80, 60), 1e-5);
  for (std::size_t i = 0; i < depth.depth.size(); ++i) {
    ASSERT_TRUE(std::isfinite(depth.depth[i]));
    EXPECT_NEAR(disparity.disparity[i], 24.0 / depth.depth[i], 1e-4);
  }
  const DepthImage back = disparityToDepth(disparity);
  for (std::size_t i = 0; i < depth.depth.size(); ++i) {
    EXPECT_NEAR(back.depth[i], depth.depth[i], 1e-4);
  }
}

TEST(StereoCameraTest, InvalidWhereNothingIsSeen) {
  Scene scene;
  scene.add(Box::axisAligned({5, -1, -1}, {6, 1, 1}));
  const PinholeCamera camera = camera160();
  const DisparityImage image = renderDisparity(scene, camera, 0.1, kPose, 50.0);
  // The box spans |y| <= 1 at x = 5: |u - cx| <= 200 / 5 = 40 px.
  EXPECT_NEAR(image.at(80, 60), 200.0 * 0.1 / 5.0, 1e-6);
  EXPECT_TRUE(std::isnan(image.at(10, 60)));
  EXPECT_TRUE(std::isnan(image.at(150, 60)));
}

// Offsets actually applied: noisy minus clean disparity.
std::vector<float> appliedOffsets(const Scene& scene, const DisparityNoise& noise, int frame) {
  const PinholeCamera camera = camera160();
  const DisparityImage clean = renderDisparity(scene, camera, 0.12, kPose, 50.0);
  const DisparityImage noisy = renderDisparity(scene, camera, 0.12, kPose, 50.0, noise, frame);
  std::vector<float> offsets(clean.disparity.size());
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    offsets[i] = noisy.disparity[i] - clean.disparity[i];
  }
  return offsets;
}

DisparityNoise patchNoise() {
  DisparityNoise noise;
  noise.patch_probability = 0.5;
  noise.patch_size_px = 20;
  noise.patch_offset_px = 2.0;
  noise.patch_persistence_frames = 4;
  noise.seed = 7;
  return noise;
}

TEST(StereoCameraTest, PatchesShiftDisparityByTheOffsetWhereTheyCover) {
  const Scene scene = tiltedWall();
  const DisparityNoise noise = patchNoise();
  const std::vector<float> offsets = appliedOffsets(scene, noise, 0);
  const auto patches = disparityPatches(noise, 160, 120, 0);
  ASSERT_FALSE(patches.empty());
  bool positive = false;
  bool negative = false;
  for (int v = 0; v < 120; ++v) {
    for (int u = 0; u < 160; ++u) {
      double expected = 0;
      for (const auto& patch : patches) {
        if (patch.covers(u, v)) expected = patch.offset_px;
      }
      EXPECT_NEAR(offsets[v * 160 + u], expected, 1e-4) << u << "," << v;
      positive |= expected > 0;
      negative |= expected < 0;
    }
  }
  EXPECT_TRUE(positive && negative);   // surfaces appear in front and behind
  for (const auto& patch : patches) {  // sizes and placement as documented
    EXPECT_GE(patch.width, 10);
    EXPECT_LE(patch.width, 20);
    EXPECT_EQ(patch.u0 / 20, (patch.u0 + patch.width - 1) / 20);  // inside its cell
    EXPECT_EQ(patch.v0 / 20, (patch.v0 + patch.height - 1) / 20);
    EXPECT_EQ(std::abs(patch.offset_px), 2.0);
  }
}

TEST(StereoCameraTest, PatchesPersistForTheirFramesAndChangeAfter) {
  const Scene scene = tiltedWall();
  const DisparityNoise noise = patchNoise();  // persistence 4: frames 0-3, 4-7, 8-11
  const std::vector<float> first = appliedOffsets(scene, noise, 0);
  for (int frame : {1, 2, 3}) EXPECT_EQ(appliedOffsets(scene, noise, frame), first) << frame;
  const std::vector<float> second = appliedOffsets(scene, noise, 4);
  EXPECT_NE(second, first);
  for (int frame : {5, 6, 7}) EXPECT_EQ(appliedOffsets(scene, noise, frame), second) << frame;
  EXPECT_NE(appliedOffsets(scene, noise, 8), second);
  // Another seed gives another layout; the same seed the same.
  DisparityNoise other = noise;
  other.seed = 8;
  EXPECT_NE(appliedOffsets(scene, other, 0), first);
  EXPECT_EQ(appliedOffsets(scene, noise, 0), first);
}

TEST(StereoCameraTest, PatchCoverageFollowsProbability) {
  DisparityNoise noise = patchNoise();
  noise.patch_size_px = 10;
  // Expected covered fraction per cell: p * E[w] E[h] / s^2 * (1 for rectangles,
  // pi/4 for ellipses, even odds). With w, h uniform-ish in [s/2, s]: E = 0.75 s.
  const double expected = 0.5 * 0.75 * 0.75 * 0.5 * (1 + M_PI / 4);
  std::size_t covered = 0;
  const int width = 1000;
  const int height = 1000;
  const auto patches = disparityPatches(noise, width, height, 3);
  for (const auto& patch : patches) {
    for (int v = patch.v0; v < patch.v0 + patch.height; ++v) {
      for (int u = patch.u0; u < patch.u0 + patch.width; ++u) covered += patch.covers(u, v);
    }
  }
  EXPECT_NEAR(static_cast<double>(patches.size()) / (100 * 100), 0.5, 0.02);
  EXPECT_NEAR(static_cast<double>(covered) / (width * height), expected, 0.02);
}

TEST(StereoCameraTest, WhiteNoiseHasSigmaAndChangesEveryFrame) {
  const Scene scene = tiltedWall();
  DisparityNoise noise;
  noise.sigma_px = 0.5;
  noise.seed = 3;
  const std::vector<float> a = appliedOffsets(scene, noise, 0);
  double sum = 0;
  double sum_sq = 0;
  for (float e : a) {
    sum += e;
    sum_sq += e * e;
  }
  const double n = static_cast<double>(a.size());
  EXPECT_NEAR(sum / n, 0.0, 0.02);
  EXPECT_NEAR(std::sqrt(sum_sq / n - (sum / n) * (sum / n)), 0.5, 0.02);
  EXPECT_EQ(appliedOffsets(scene, noise, 0), a);  // reproducible
  const std::vector<float> b = appliedOffsets(scene, noise, 1);
  std::size_t same = 0;
  for (std::size_t i = 0; i < a.size(); ++i) same += a[i] == b[i];
  EXPECT_LT(same, a.size() / 100);
}

TEST(StereoCameraTest, ShiftBelowZeroDisparityIsInvalid) {
  Scene scene;
  scene.add(Box::axisAligned({5, -10, -10}, {6, 10, 10}));  // d = 200 * 0.1 / 5 = 4 px
  DisparityNoise noise;
  noise.patch_probability = 1.0;
  noise.patch_offset_px = 5.0;
  noise.patch_size_px = 8;
  const PinholeCamera camera = camera160();
  const DisparityImage image = renderDisparity(scene, camera, 0.1, kPose, 50.0, noise, 0);
  const auto patches = disparityPatches(noise, 160, 120, 0);
  std::size_t checked = 0;
  for (const auto& patch : patches) {
    const int u = patch.u0 + patch.width / 2;
    const int v = patch.v0 + patch.height / 2;
    ASSERT_TRUE(patch.covers(u, v));
    if (patch.offset_px > 0) {
      EXPECT_NEAR(image.at(u, v), 9.0, 1e-5);
    } else {
      EXPECT_TRUE(std::isnan(image.at(u, v)));
    }
    ++checked;
  }
  EXPECT_EQ(checked, 20u * 15u);  // probability 1: one patch per cell
}

TEST(StereoCameraTest, LeftRightCheckInvalidatesPixelsTheRightCameraCannotSee) {
  // Wall at x = 5 behind a thin post at x in [2, 2.2], |y| <= 0.1. The right camera sits 0.5 m
  // along optical +x, i.e. at world y = -0.5. Its segment to the wall point (5, y) crosses the
  // post for y in about [0.5, 0.86]: at x = 2 it is at -0.5 + 0.4 (y + 0.5).
  Scene scene;
  scene.add(Box::axisAligned({5, -20, -20}, {6, 20, 20}))
      .add(Box::axisAligned({2, -0.1, -20}, {2.2, 0.1, 20}));
  const PinholeCamera camera = camera160();
  DisparityNoise noise;
  noise.left_right_check = true;
  const DisparityImage checked = renderDisparity(scene, camera, 0.5, kPose, 50.0, noise);
  const DisparityImage unchecked = renderDisparity(scene, camera, 0.5, kPose, 50.0);
  // Pixel column of wall point y (optical x = -y): u = cx - fx y / 5 = 79.5 - 40 y.
  const int v = 60;
  const int occluded_u = 51;  // y = 0.7125
  const int visible_u = 19;   // y = 1.5125: right ray at x = 2.2 is at y = 0.37, clear of the post
  EXPECT_TRUE(std::isnan(checked.at(occluded_u, v)));
  EXPECT_NEAR(unchecked.at(occluded_u, v), 200.0 * 0.5 / 5.0, 1e-4);
  EXPECT_NEAR(checked.at(visible_u, v), 200.0 * 0.5 / 5.0, 1e-4);
  EXPECT_NEAR(checked.at(80, v), 200.0 * 0.5 / 2.0, 1e-4);  // the post itself
  // Exactly the wall columns whose right-camera segment meets the post are invalid.
  for (int u = 0; u < camera.width; ++u) {
    const double y = -(u - camera.cx) / camera.fx * 5.0;
    if (std::abs(y) <= 0.1 * 5.0 / 2.2 + 0.03) continue;  // post or its silhouette edge
    const double y_at_front = -0.5 + 0.4 * (y + 0.5);
    const double y_at_back = -0.5 + 0.44 * (y + 0.5);
    const bool blocked =
        std::max(y_at_front, y_at_back) >= -0.1 && std::min(y_at_front, y_at_back) <= 0.1;
    if (std::abs(y_at_front - 0.1) < 0.02 || std::abs(y_at_back + 0.1) < 0.02) continue;  // edge
    EXPECT_EQ(std::isnan(checked.at(u, v)), blocked) << u;
  }
}

TEST(StereoCameraTest, ValidateNamesTheBadField) {
  DisparityNoise noise;
  noise.patch_persistence_frames = 0;
  try {
    noise.validate();
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("patch_persistence_frames"), std::string::npos);
  }
  noise = DisparityNoise();
  noise.patch_probability = 1.5;
  EXPECT_THROW(noise.validate(), std::invalid_argument);
  EXPECT_THROW(renderDisparity(tiltedWall(), camera160(), 0.0, kPose, 10.0), std::invalid_argument);
}

}  // namespace
}  // namespace sim
}  // namespace occupancy_fusion
