// Scene queries and the ready-made scenes' geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/scene.h"
#include "occupancy_fusion/sim/scenes.h"

namespace occupancy_fusion {
namespace sim {
namespace {

Scene boxOnFloor() {
  Scene scene;
  scene.add(Plane{{0, 0, 0}, {0, 0, 1}}).add(Box::axisAligned({1, -1, 0}, {3, 1, 2}));
  return scene;
}

TEST(SceneTest, CastRayTakesNearestHitWithinRange) {
  Scene scene;
  scene.add(Sphere{{10, 0, 0}, 1.0}).add(Box::axisAligned({4, -1, -1}, {5, 1, 1}));
  auto t = scene.castRay({0, 0, 0}, {1, 0, 0}, 100.0);
  ASSERT_TRUE(t);
  EXPECT_DOUBLE_EQ(*t, 4.0);
  EXPECT_FALSE(scene.castRay({0, 0, 0}, {1, 0, 0}, 3.9));  // beyond max_range
  t = scene.castRay({0, 0, 0}, {1, 0, 0}, 4.0);            // range is inclusive
  ASSERT_TRUE(t);
  t = scene.castRay({6, 0, 0}, {1, 0, 0}, 100.0);  // past the box: the sphere at 9
  ASSERT_TRUE(t);
  EXPECT_DOUBLE_EQ(*t, 3.0);
  EXPECT_FALSE(scene.castRay({0, 0, 0}, {0, 1, 0}, 100.0));
}

// castRay's prepared fast path must agree with each primitive's own intersect().
TEST(SceneTest, CastRayAgreesWithPerPrimitiveIntersection) {
  Scene scene = makeBoxScene();
  scene.add(Box::yawed({3, -3, 3}, {0.5, 2, 1}, 0.7)).add(Plane{{0, 0, 7}, {0, 0.6, -0.8}});
  std::uint64_t state = 12345;
  auto uniform = [&state]() {  // small LCG: the test needs no statistical quality
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d origin(-1 + 11 * uniform(), -5.4 + 10.8 * uniform(), 8 * uniform());
    const Eigen::Vector3d dir =
        Eigen::Vector3d(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5).normalized();
    double expected = std::numeric_limits<double>::infinity();
    for (const Primitive& primitive : scene.primitives()) {
      const auto t = std::visit([&](const auto& p) { return p.intersect(origin, dir); }, primitive);
      if (t) expected = std::min(expected, *t);
    }
    const auto t = scene.castRay(origin, dir, 100.0);
    ASSERT_EQ(t.has_value(), std::isfinite(expected)) << i;
    if (t) {
      EXPECT_NEAR(*t, expected, 1e-9) << i;
      ++hits;
    }
  }
  EXPECT_GT(hits, 19000);
}

TEST(SceneTest, OccupancyAndDistance) {
  const Scene scene = boxOnFloor();
  EXPECT_TRUE(scene.isOccupied({0, 0, -0.1}));  // below the floor
  EXPECT_TRUE(scene.isOccupied({2, 0, 1}));     // in the box
  EXPECT_FALSE(scene.isOccupied({0, 0, 0.1}));
  EXPECT_FALSE(scene.isOccupied({2, 0, 2.1}));
  EXPECT_NEAR(scene.distanceToSurface({0, 0, 1.5}), 1.0, 1e-12);  // box face x = 1
  EXPECT_NEAR(scene.distanceToSurface({0, 5, 0.5}), 0.5, 1e-12);  // floor
  EXPECT_NEAR(scene.distanceToSurface({2, 0, 4}), 2.0, 1e-12);    // box top
}

TEST(SceneTest, BoundsIgnoreHalfSpaces) {
  const Scene scene = boxOnFloor();
  EXPECT_TRUE(scene.bounds().min().isApprox(Eigen::Vector3d(1, -1, 0)));
  EXPECT_TRUE(scene.bounds().max().isApprox(Eigen::Vector3d(3, 1, 2)));
}

TEST(SceneTest, SurfaceSamplesAreVisibleSurface) {
  const Scene scene = boxOnFloor();
  const auto samples = scene.sampleSurface(0.1);
  ASSERT_FALSE(samples.empty());
  std::size_t on_floor = 0;
  for (const auto& p : samples) {
    EXPECT_NEAR(scene.distanceToSurface(p), 0.0, 1e-9);
    // The box's bottom face and the floor beneath it are buried: no sample at z = 0 under it.
    EXPECT_FALSE(std::abs(p.z()) < 1e-9 && p.x() > 1 && p.x() < 3 && std::abs(p.y()) < 1);
    if (std::abs(p.z()) < 1e-9) ++on_floor;
  }
  // The floor is clipped to the bounds (2 x 2 m) and entirely under the box: nothing left.
  EXPECT_EQ(on_floor, 0u);
  // Box: top (2 x 2) and four sides (2 x 2 each) at 0.1 m: 5 * 400 cells.
  EXPECT_EQ(samples.size(), 2000u);
}

// Checks that a ray from `eye` to `target` first hits the surface of `primitive` and that the
// target lies inside the field of view of the depth paper's camera looking along +x.
void expectVisibleFrom(const Scene& scene, const Eigen::Vector3d& eye, const Primitive& primitive,
                       const Eigen::Vector3d& target) {
  const Eigen::Vector3d direction = (target - eye).normalized();
  const auto t = scene.castRay(eye, direction, 100.0);
  ASSERT_TRUE(t);
  const Eigen::Vector3d hit = eye + *t * direction;
  EXPECT_NEAR(std::visit([&](const auto& p) { return p.distanceToSurface(hit); }, primitive), 0.0,
              1e-9);
  const PinholeCamera camera = pirkerSyntheticCamera();
  const Eigen::Vector3d offset = target - eye;
  EXPECT_LE(std::abs(offset.y() / offset.x()) * camera.fx, camera.cx);
  EXPECT_LE(std::abs(offset.z() / offset.x()) * camera.fy, camera.cy);
}

TEST(ReadyMadeScenesTest, BoxSceneMatchesPaperDimensions) {
  const Scene scene = makeBoxScene();
  const Eigen::Vector3d size = scene.bounds().sizes();
  EXPECT_NEAR(size.x(), 11.2, 1e-9);  // depth
  EXPECT_NEAR(size.y(), 10.8, 1e-9);  // width
  EXPECT_NEAR(size.z(), 8.3, 1e-9);   // height
  const Eigen::Vector3d eye = boxSceneCameraPosition();
  EXPECT_FALSE(scene.isOccupied(eye));
  // Six objects after the six shell slabs, each seen by the centre view, at increasing depth.
  ASSERT_EQ(scene.primitives().size(), 12u);
  double previous_depth = 0;
  for (std::size_t i = 6; i < 12; ++i) {
    const Primitive& object = scene.primitives()[i];
    const Eigen::AlignedBox3d b = std::visit([](const auto& p) { return p.bounds(); }, object);
    expectVisibleFrom(scene, eye, object, b.center());
    EXPECT_GT(b.min().x(), previous_depth);
    previous_depth = b.min().x();
  }
  // 1 m width: the axis-aligned, spherical and cylindrical objects span 1 m across the view.
  for (std::size_t i : {6u, 7u, 8u, 10u, 11u}) {
    const Eigen::AlignedBox3d b =
        std::visit([](const auto& p) { return p.bounds(); }, scene.primitives()[i]);
    EXPECT_NEAR(b.sizes().y(), 1.0, 1e-9) << "object " << i;
  }
  // The closed shell: every direction from the camera hits something within the room.
  for (double angle = 0; angle < 2 * M_PI; angle += 0.3) {
    EXPECT_TRUE(scene.castRay(eye, {std::cos(angle), 0, std::sin(angle)}, 20.0));
    EXPECT_TRUE(scene.castRay(eye, {0, std::cos(angle), std::sin(angle)}, 20.0));
  }
}

TEST(ReadyMadeScenesTest, SpheresSceneMatchesPaperDimensions) {
  const Scene scene = makeSpheresScene();
  const Eigen::Vector3d size = scene.bounds().sizes();
  EXPECT_NEAR(size.y(), 2.2, 1e-9);
  EXPECT_NEAR(size.z(), 2.1, 1e-9);
  EXPECT_NEAR(size.x(), 2.0, 1e-9);
  ASSERT_EQ(scene.primitives().size(), 5u);  // a box and four spheres
  EXPECT_TRUE(std::holds_alternative<Box>(scene.primitives()[0]));
  const Eigen::Vector3d eye = spheresSceneCameraPosition();
  for (const Primitive& object : scene.primitives()) {
    const Eigen::AlignedBox3d b = std::visit([](const auto& p) { return p.bounds(); }, object);
    // Aim at the object's upper part (the smaller spheres hide lower parts of the box).
    expectVisibleFrom(scene, eye, object, b.center() + Eigen::Vector3d(0, 0, 0.25 * b.sizes().z()));
  }
}

TEST(ReadyMadeScenesTest, RoomAndCorridor) {
  const Scene room = makeRoomScene();
  EXPECT_TRUE(room.bounds().sizes().isApprox(Eigen::Vector3d(8, 6, 2.5)));
  EXPECT_FALSE(room.isOccupied({0, 0, 1}));
  EXPECT_TRUE(room.isOccupied({1.5, 1.0, 0.5}));  // the table
  EXPECT_NEAR(*room.castRay({0, 0, 1}, {1, 0, 0}, 10), 3.9, 1e-12);
  EXPECT_NEAR(*room.castRay({0, 0, 1}, {0, 0, -1}, 10), 1.0, 1e-12);
  EXPECT_FALSE(room.castRay({0, 0, 1}, {0, 0, 1}, 10));  // no ceiling

  const Scene corridor = makeCorridorScene();
  EXPECT_NEAR(corridor.bounds().min().x(), 0.0, 1e-12);
  EXPECT_NEAR(corridor.bounds().max().x(), 20.2, 1e-12);
  EXPECT_NEAR(corridor.bounds().sizes().y(), 2.8, 1e-12);
  const Eigen::Vector3d eye(2, 0, 0.3);
  EXPECT_NEAR(*corridor.castRay(eye, {0, -1, 0}, 30), 1.2, 1e-12);
  EXPECT_FALSE(corridor.castRay(eye, {-1, 0, 0}, 30));                      // open end
  EXPECT_FALSE(corridor.castRay({7.5, 0, 1.5}, {0, 1, 0}, 30));             // through the doorway
  EXPECT_NEAR(*corridor.castRay({18, 0, 1.5}, {1, 0, 0}, 30), 2.0, 1e-12);  // end wall
}

}  // namespace
}  // namespace sim
}  // namespace occupancy_fusion
