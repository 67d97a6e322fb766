// Depth rendering against analytic z-depths.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>

#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {
namespace sim {
namespace {

PinholeCamera smallCamera() {
  PinholeCamera camera;
  camera.width = 81;
  camera.height = 61;
  camera.fx = 100.0;
  camera.fy = 120.0;
  camera.cx = 40.0;
  camera.cy = 30.0;
  return camera;
}

// Camera at the origin looking along world +x (optical z = world x, x = -y, y = -z).
Eigen::Isometry3d lookingAlongX() { return opticalFrameInBody(); }

TEST(DepthCameraTest, FrontoParallelWallHasConstantZDepth) {
  Scene scene;
  scene.add(Box::axisAligned({3, -50, -50}, {4, 50, 50}));
  const PinholeCamera camera = smallCamera();
  const DepthImage image = renderDepth(scene, camera, lookingAlongX(), 10.0);
  ASSERT_EQ(image.width, 81);
  ASSERT_EQ(image.height, 61);
  EXPECT_EQ(image.at(40, 30), 3.0f);  // the principal ray: exact
  // z-depth, not ray length: the corner pixel's ray is longer but its z is still 3.
  for (float z : image.depth) EXPECT_NEAR(z, 3.0, 1e-6);
}

TEST(DepthCameraTest, TiltedPlaneMatchesAnalyticDepth) {
  // Plane x + 0.5 y = 3 in the world. Pixel (u, v) looks along optical (a, b, 1) with
  // a = (u - cx) / fx, b = (v - cy) / fy, i.e. world (1, -a, -b) per metre of z, so
  // z (1 - 0.5 a) = 3.
  Scene scene;
  scene.add(Plane{{3, 0, 0}, Eigen::Vector3d(-1, -0.5, 0).normalized()});
  const PinholeCamera camera = smallCamera();
  const DepthImage image = renderDepth(scene, camera, lookingAlongX(), 10.0);
  for (int u : {0, 20, 40, 65, 80}) {
    for (int v : {0, 30, 60}) {
      const double a = (u - camera.cx) / camera.fx;
      EXPECT_NEAR(image.at(u, v), 3.0 / (1.0 - 0.5 * a), 1e-5) << u << "," << v;
    }
  }
  EXPECT_NEAR(image.at(80, 0), 3.75, 1e-5);  // a = 0.4
}

TEST(DepthCameraTest, MaxRangeLimitsZAndEmptyIsNaN) {
  Scene scene;
  scene.add(Plane{{3, 0, 0}, Eigen::Vector3d(-1, -0.5, 0).normalized()});
  const PinholeCamera camera = smallCamera();
  // z ranges from 3 / 1.2 = 2.5 (u = 0) to 3.75 (u = 80); a limit of 3.2 keeps the left part.
  const DepthImage image = renderDepth(scene, camera, lookingAlongX(), 3.2);
  for (int u = 0; u < camera.width; ++u) {
    const double expected = 3.0 / (1.0 - 0.5 * (u - camera.cx) / camera.fx);
    if (expected <= 3.2 - 1e-9) {
      EXPECT_NEAR(image.at(u, 10), expected, 1e-5);
    } else if (expected > 3.2 + 1e-9) {
      EXPECT_TRUE(std::isnan(image.at(u, 10))) << u;
    }
  }
  // Looking away from the plane: nothing.
  const Eigen::Isometry3d backwards = lookAt(Eigen::Vector3d::Zero(), Eigen::Vector3d(-1, 0, 0));
  for (float z : renderDepth(scene, camera, backwards, 100.0).depth) EXPECT_TRUE(std::isnan(z));
}

TEST(DepthCameraTest, PointCloudLiesOnTheSurfaceInCameraFrame) {
  const Scene scene = makeRoomScene();
  const PinholeCamera camera = smallCamera();
  const Eigen::Isometry3d pose = lookAt({-1, -1, 1.2}, {1.5, 1.0, 0.0});
  const auto points = renderPointCloud(scene, camera, pose, 20.0);
  EXPECT_EQ(points.size(), static_cast<std::size_t>(camera.width * camera.height));  // closed view
  for (const auto& p : points) {
    EXPECT_NEAR(scene.distanceToSurface(pose * p), 0.0, 1e-5);
  }
  // Row-major order: the first point is pixel (0, 0), on its ray.
  EXPECT_NEAR(points.front().x() / points.front().z(), -camera.cx / camera.fx, 1e-12);
  EXPECT_NEAR(points.front().y() / points.front().z(), -camera.cy / camera.fy, 1e-12);
}

TEST(DepthCameraTest, ValidateNamesTheBadField) {
  PinholeCamera camera;
  camera.fy = 0;
  try {
    camera.validate();
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fy"), std::string::npos);
  }
  camera = PinholeCamera();
  camera.width = 0;
  EXPECT_THROW(renderDepth(Scene(), camera, Eigen::Isometry3d::Identity(), 1.0),
               std::invalid_argument);
}

TEST(DepthCameraTest, BoxSceneRendersQuickly) {
  const Scene scene = makeBoxScene();
  const PinholeCamera camera = pirkerSyntheticCamera();
  const auto poses = rotationSweep(boxSceneCameraPosition());
  renderDepth(scene, camera, poses[0], 20.0);  // warm-up (thread pool)
  const auto start = std::chrono::steady_clock::now();
  const int frames = 10;
  std::size_t valid = 0;
  for (int k = 0; k < frames; ++k) {
    for (float z : renderDepth(scene, camera, poses[k * 17], 20.0).depth) valid += std::isfinite(z);
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() /
      frames;
  std::cout << "BOX scene 400x400 depth render: " << ms << " ms per frame\n";
  EXPECT_EQ(valid, static_cast<std::size_t>(frames) * 400 * 400);  // closed room: all valid
}

}  // namespace
}  // namespace sim
}  // namespace occupancy_fusion
