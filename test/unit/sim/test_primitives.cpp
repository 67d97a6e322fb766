// Ray intersection, inside tests and distances of each primitive against hand-computed values.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "occupancy_fusion/sim/primitives.h"

namespace occupancy_fusion {
namespace sim {
namespace {

constexpr double kTol = 1e-12;

Eigen::Vector3d unit(double x, double y, double z) { return Eigen::Vector3d(x, y, z).normalized(); }

TEST(BoxTest, AxisAlignedRayHitsNearFace) {
  const Box box = Box::axisAligned({1, -1, -1}, {3, 1, 1});
  const auto t = box.intersect({0, 0, 0}, {1, 0, 0});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 1.0, kTol);
}

TEST(BoxTest, DiagonalRayHitsFaceAtAnalyticDistance) {
  // Ray at 45 deg in x-y from the origin hits the face x = 1 at (1, 1, 0): t = sqrt(2).
  const Box box = Box::axisAligned({1, -2, -1}, {3, 2, 1});
  const auto t = box.intersect({0, 0, 0}, unit(1, 1, 0));
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, std::sqrt(2.0), kTol);
}

TEST(BoxTest, RayFromInsideReportsExit) {
  const Box box = Box::axisAligned({-1, -2, -3}, {1, 2, 3});
  const auto t = box.intersect({0, 0, 0}, {0, -1, 0});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 2.0, kTol);
}

TEST(BoxTest, MissesAndBehind) {
  const Box box = Box::axisAligned({1, -1, -1}, {3, 1, 1});
  EXPECT_FALSE(box.intersect({0, 0, 0}, {-1, 0, 0}));        // box behind the ray
  EXPECT_FALSE(box.intersect({0, 2, 0}, {1, 0, 0}));         // passes beside it
  EXPECT_FALSE(box.intersect({0, 0, 0}, unit(1, 1.01, 0)));  // just misses the edge (1, 1)
  EXPECT_TRUE(box.intersect({0, 0, 0}, unit(1, 0.99, 0)));   // just hits near the edge
}

TEST(BoxTest, OrientedBoxHitsCornerAtAnalyticDistance) {
  // A unit cube turned 45 deg about z, centred at (5, 0, 0): its corner points at -x and lies
  // at x = 5 - sqrt(2)/2.
  const Box box = Box::yawed({5, 0, 0}, {1, 1, 1}, M_PI / 4);
  const auto t = box.intersect({0, 0, 0}, {1, 0, 0});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 5 - std::sqrt(0.5), 1e-12);
  // A ray at y = 0.6 passes outside the diamond (half-width there is sqrt(2)/2 - 0.6 > 0, so it
  // hits: x = 5 - (sqrt(2)/2 - 0.6)).
  const auto t2 = box.intersect({0, 0.6, 0}, {1, 0, 0});
  ASSERT_TRUE(t2);
  EXPECT_NEAR(*t2, 5 - (std::sqrt(0.5) - 0.6), 1e-12);
  EXPECT_FALSE(box.intersect({0, 0.75, 0}, {1, 0, 0}));  // beyond the corner at y = 0.707
}

TEST(BoxTest, ContainsAndDistance) {
  const Box box = Box::yawed({5, 0, 0}, {1, 1, 1}, M_PI / 4);
  EXPECT_TRUE(box.contains({5, 0.7, 0}));     // inside the corner pointing at +y
  EXPECT_FALSE(box.contains({5.5, 0.5, 0}));  // a corner of the unturned cube is outside
  EXPECT_NEAR(box.distanceToSurface({5, 0, 0}), 0.5, kTol);
  // From the corner (5 - sqrt(0.5), 0, 0) straight out along -x by 1: distance 1.
  EXPECT_NEAR(box.distanceToSurface({4 - std::sqrt(0.5), 0, 0}), 1.0, kTol);
  const Box aligned = Box::axisAligned({0, 0, 0}, {2, 4, 6});
  EXPECT_NEAR(aligned.distanceToSurface({3, 5, 3}), std::sqrt(2.0), kTol);  // off an edge
  EXPECT_NEAR(aligned.distanceToSurface({1, 0.25, 3}), 0.25, kTol);         // inside, near y=0
  EXPECT_TRUE(aligned.contains({2, 4, 6}));                                 // boundary is inside
}

TEST(BoxTest, BoundsOfTurnedBox) {
  const Eigen::AlignedBox3d b = Box::yawed({5, 0, 0}, {1, 1, 2}, M_PI / 4).bounds();
  EXPECT_NEAR(b.min().x(), 5 - std::sqrt(0.5), kTol);
  EXPECT_NEAR(b.max().y(), std::sqrt(0.5), kTol);
  EXPECT_NEAR(b.max().z(), 1.0, kTol);
}

TEST(SphereTest, RayDistances) {
  const Sphere sphere{{0, 0, 5}, 1.0};
  auto t = sphere.intersect({0, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 4.0, kTol);
  // Ray offset by 0.6 in x: enters where z = 5 - sqrt(1 - 0.36) = 4.2.
  t = sphere.intersect({0.6, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 4.2, kTol);
  t = sphere.intersect({0, 0, 5}, {1, 0, 0});  // from the centre
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 1.0, kTol);
  EXPECT_FALSE(sphere.intersect({1.01, 0, 0}, {0, 0, 1}));
  EXPECT_FALSE(sphere.intersect({0, 0, 0}, {0, 0, -1}));
}

TEST(SphereTest, ContainsAndDistance) {
  const Sphere sphere{{1, 2, 3}, 2.0};
  EXPECT_TRUE(sphere.contains({1, 2, 5}));
  EXPECT_FALSE(sphere.contains({1, 2, 5.001}));
  EXPECT_NEAR(sphere.distanceToSurface({1, 2, 3}), 2.0, kTol);
  EXPECT_NEAR(sphere.distanceToSurface({4, 6, 3}), 3.0, kTol);  // |(3, 4, 0)| = 5
}

TEST(PlaneTest, FloorIsSolidBelow) {
  const Plane floor{{0, 0, 1}, {0, 0, 1}};
  EXPECT_TRUE(floor.contains({10, -3, 0.5}));
  EXPECT_FALSE(floor.contains({10, -3, 1.5}));
  EXPECT_NEAR(floor.distanceToSurface({3, 3, 4}), 3.0, kTol);
  EXPECT_NEAR(floor.distanceToSurface({3, 3, -1}), 2.0, kTol);
  // From (0, 0, 3) at 30 deg below horizontal: t = 2 / sin(30 deg) = 4.
  const auto t = floor.intersect({0, 0, 3}, {std::cos(M_PI / 6), 0, -std::sin(M_PI / 6)});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 4.0, kTol);
  EXPECT_FALSE(floor.intersect({0, 0, 3}, {1, 0, 0}));  // parallel
  EXPECT_FALSE(floor.intersect({0, 0, 3}, {0, 0, 1}));  // away
}

TEST(PlaneTest, TiltedPlane) {
  const Plane wall{{2, 0, 0}, Eigen::Vector3d(-1, -1, 0).normalized()};
  // The plane x + y = 2; along +x from the origin: t = 2; along the normal direction: sqrt(2).
  EXPECT_NEAR(*wall.intersect({0, 0, 0}, {1, 0, 0}), 2.0, kTol);
  EXPECT_NEAR(*wall.intersect({0, 0, 0}, unit(1, 1, 0)), std::sqrt(2.0), kTol);
  EXPECT_TRUE(wall.contains({2, 1, 0}));
}

TEST(CylinderTest, SideAndCapHits) {
  const Cylinder cylinder = Cylinder::upright(5, 0, 0, 1.0, 2.0);  // z in [0, 2]
  auto t = cylinder.intersect({0, 0, 1}, {1, 0, 0});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 4.0, kTol);
  // Offset ray y = 0.8: hits the side at x = 5 - sqrt(1 - 0.64) = 4.4.
  t = cylinder.intersect({0, 0.8, 1}, {1, 0, 0});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 4.4, kTol);
  // Straight down onto the top cap from z = 5 over (5.5, 0).
  t = cylinder.intersect({5.5, 0, 5}, {0, 0, -1});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 3.0, kTol);
  // Passes above the top cap.
  EXPECT_FALSE(cylinder.intersect({0, 0, 2.1}, {1, 0, 0}));
  // Diagonal ray from (3, 0, 2.5) going down at 45 deg: reaches the side x = 4 at z = 1.5,
  // t = sqrt(2).
  t = cylinder.intersect({3, 0, 2.5}, unit(1, 0, -1));
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, std::sqrt(2.0), 1e-9);
}

TEST(CylinderTest, TiltedAxis) {
  // Axis along x, centred at origin, radius 1, length 4: a ray down from z = 5 at x = 1.9 hits
  // the curved side at z = 1; at x = 2.1 it misses.
  Cylinder cylinder;
  cylinder.axis = {1, 0, 0};
  cylinder.radius = 1.0;
  cylinder.height = 4.0;
  auto t = cylinder.intersect({1.9, 0, 5}, {0, 0, -1});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 4.0, kTol);
  EXPECT_FALSE(cylinder.intersect({2.1, 0, 5}, {0, 0, -1}));
  // Along the axis from outside: the cap at x = -2.
  t = cylinder.intersect({-10, 0.5, 0}, {1, 0, 0});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 8.0, kTol);
  const Eigen::AlignedBox3d b = cylinder.bounds();
  EXPECT_NEAR(b.min().x(), -2.0, kTol);
  EXPECT_NEAR(b.max().y(), 1.0, kTol);
  EXPECT_NEAR(b.max().z(), 1.0, kTol);
}

TEST(CylinderTest, ContainsAndDistance) {
  const Cylinder cylinder = Cylinder::upright(0, 0, 0, 1.0, 2.0);
  EXPECT_TRUE(cylinder.contains({0.7, 0.7, 1.9}));
  EXPECT_FALSE(cylinder.contains({0.8, 0.7, 1.0}));  // radius 1.063
  EXPECT_FALSE(cylinder.contains({0, 0, 2.01}));
  EXPECT_NEAR(cylinder.distanceToSurface({0, 0, 1}), 1.0, kTol);    // centre: side and caps
  EXPECT_NEAR(cylinder.distanceToSurface({0, 0, 1.8}), 0.2, kTol);  // inside near the top
  EXPECT_NEAR(cylinder.distanceToSurface({3, 0, 1}), 2.0, kTol);    // beside
  EXPECT_NEAR(cylinder.distanceToSurface({0.5, 0, 5}), 3.0, kTol);  // above the cap
  EXPECT_NEAR(cylinder.distanceToSurface({4, 0, 6}), 5.0, kTol);    // off the rim: (3, 4)
}

TEST(PrimitiveValidateTest, NamesTheBadField) {
  Sphere sphere;
  sphere.radius = -1;
  try {
    sphere.validate();
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("Sphere.radius"), std::string::npos);
  }
  Plane plane;
  plane.normal = {0, 0, 2};
  EXPECT_THROW(plane.validate(), std::invalid_argument);
  Cylinder cylinder;
  cylinder.height = 0;
  EXPECT_THROW(cylinder.validate(), std::invalid_argument);
  Box box;
  box.T_world_box.linear() *= 2.0;  // not a rotation
  EXPECT_THROW(box.validate(), std::invalid_argument);
}

TEST(SurfaceSamplesTest, LieOnTheSurfaceWithRequestedDensity) {
  const Eigen::AlignedBox3d everywhere(Eigen::Vector3d::Constant(-100),
                                       Eigen::Vector3d::Constant(100));
  std::vector<Eigen::Vector3d> samples;
  const Sphere sphere{{1, 1, 1}, 1.0};
  sphere.appendSurfaceSamples(0.1, everywhere, samples);
  EXPECT_EQ(samples.size(), static_cast<std::size_t>(std::ceil(4 * M_PI / 0.01)));
  for (const auto& p : samples) EXPECT_NEAR(sphere.distanceToSurface(p), 0.0, 1e-12);

  samples.clear();
  const Box box = Box::axisAligned({0, 0, 0}, {1, 2, 3});
  box.appendSurfaceSamples(0.5, everywhere, samples);
  // Faces: 2*(2*4) + 2*(4*6) + 2*(6*2) cells of 0.5 m.
  EXPECT_EQ(samples.size(), 2u * (8 + 24 + 12));
  for (const auto& p : samples) EXPECT_NEAR(box.distanceToSurface(p), 0.0, 1e-12);

  samples.clear();
  const Cylinder cylinder = Cylinder::upright(0, 0, 0, 0.5, 1.0);
  cylinder.appendSurfaceSamples(0.1, everywhere, samples);
  for (const auto& p : samples) EXPECT_NEAR(cylinder.distanceToSurface(p), 0.0, 1e-12);
  EXPECT_GT(samples.size(), 2 * M_PI * 0.5 * 1.0 / 0.01);  // side area / spacing^2

  samples.clear();
  const Plane floor{{0, 0, 0}, {0, 0, 1}};
  const Eigen::AlignedBox3d clip(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 1, 1));
  floor.appendSurfaceSamples(0.5, clip, samples);
  ASSERT_FALSE(samples.empty());
  for (const auto& p : samples) {
    EXPECT_NEAR(p.z(), 0.0, 1e-12);
    EXPECT_TRUE(clip.contains(p));
  }
  // Every point of the clipped floor is within half a grid diagonal of some sample.
  for (double x = 0; x <= 2; x += 0.05) {
    for (double y = 0; y <= 1; y += 0.05) {
      double nearest = 1e9;
      for (const auto& p : samples)
        nearest = std::min(nearest, (p - Eigen::Vector3d(x, y, 0)).norm());
      EXPECT_LE(nearest, 0.5 * std::sqrt(0.5) + 1e-9) << x << " " << y;
    }
  }
}

}  // namespace
}  // namespace sim
}  // namespace occupancy_fusion
