// The building floor scene and its corridor loop: where the walls and doorways are, that the
// loop's centre line is free, and the path the robot drives around it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "occupancy_fusion/sim/odometry_drift.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {
namespace sim {
namespace {

constexpr double kLoopLength = 90.0 - 8.0 + 2.0 * M_PI;  // 1 m corner arcs

// Points every `spacing` metres along the outline of `rectangle`, at height z.
std::vector<Eigen::Vector3d> outlinePoints(const Eigen::AlignedBox2d& rectangle, double spacing,
                                           double z) {
  const Eigen::Vector2d lo = rectangle.min(), hi = rectangle.max();
  std::vector<Eigen::Vector3d> points;
  for (double x = lo.x(); x <= hi.x() + 1e-9; x += spacing) {
    points.emplace_back(x, lo.y(), z);
    points.emplace_back(x, hi.y(), z);
  }
  for (double y = lo.y(); y <= hi.y() + 1e-9; y += spacing) {
    points.emplace_back(lo.x(), y, z);
    points.emplace_back(hi.x(), y, z);
  }
  return points;
}

TEST(BuildingFloorTest, OutlineAndHeight) {
  const Scene scene = makeBuildingFloorScene();
  EXPECT_TRUE(scene.bounds().min().isApprox(Eigen::Vector3d(-20, -12.5, 0)));
  EXPECT_TRUE(scene.bounds().max().isApprox(Eigen::Vector3d(20, 12.5, 2.5)));
  EXPECT_TRUE(scene.isOccupied({0, 0, -0.01}));  // the floor
  EXPECT_FALSE(scene.isOccupied({2, 10, 2.6}));  // no ceiling
  const Eigen::AlignedBox2d line = buildingLoopCentreLine();
  EXPECT_TRUE(line.min().isApprox(Eigen::Vector2d(-15, -7.5)));
  EXPECT_TRUE(line.max().isApprox(Eigen::Vector2d(15, 7.5)));
}

TEST(BuildingFloorTest, CorridorCentreLineIsFree) {
  const Scene scene = makeBuildingFloorScene();
  for (double z : {0.05, 0.3, 1.0, 2.4}) {
    for (const Eigen::Vector3d& point : outlinePoints(buildingLoopCentreLine(), 0.05, z)) {
      ASSERT_FALSE(scene.isOccupied(point)) << point.transpose();
      // Clear by 0.6 m sideways: only the floor may come nearer, below the point.
      EXPECT_GE(scene.distanceToSurface(point), std::min(0.6, z) - 1e-9) << point.transpose();
    }
  }
  // The narrowest places: the pillar at (-6, -8.3) and the cabinet at y = -6.85 leave 0.65 m.
  EXPECT_NEAR(scene.distanceToSurface({-6, -7.5, 1}), 0.65, 1e-9);
  EXPECT_NEAR(scene.distanceToSurface({4.4, -7.5, 1}), 0.65, 1e-9);
}

TEST(BuildingFloorTest, WallsAndDoorwaysWhereDocumented) {
  const Scene scene = makeBuildingFloorScene();
  auto hit = [&](const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) {
    return scene.castRay(origin, direction, 50.0).value_or(-1.0);
  };
  const Eigen::Vector3d north = Eigen::Vector3d::UnitY(), east = Eigen::Vector3d::UnitX();
  // From the centre line, the corridor's walls are 1 m away on both sides.
  EXPECT_NEAR(hit({0, -7.5, 1}, north), 1.0, 1e-9);   // central block
  EXPECT_NEAR(hit({0, -7.5, 1}, -north), 1.0, 1e-9);  // outer rooms
  EXPECT_NEAR(hit({15, 0, 1}, east), 1.0, 1e-9);
  EXPECT_NEAR(hit({15, 0, 1}, -east), 1.0, 1e-9);
  EXPECT_NEAR(hit({0, 7.5, 1}, north), 1.0, 1e-9);
  EXPECT_NEAR(hit({-15, 0, 1}, -east), 1.0, 1e-9);
  // Through the south doorway at x = -2 into a central room, up to the spine wall at y = -0.075.
  EXPECT_NEAR(hit({-2, -7.5, 1}, north), 7.5 - 0.075, 1e-9);
  // Through the north outer doorway at x = 4.5 to the exterior wall (inner face y = 12.3).
  EXPECT_NEAR(hit({4.5, 7.5, 1}, north), 12.3 - 7.5, 1e-9);
  // Through the west outer doorway at y = 2 to the exterior wall (inner face x = -19.8).
  EXPECT_NEAR(hit({-15, 2, 1}, -east), 19.8 - 15, 1e-9);
  // Wall centres are solid, doorway centres free.
  EXPECT_TRUE(scene.isOccupied({0, -6.42, 1}));
  EXPECT_FALSE(scene.isOccupied({-2, -6.42, 1}));
  EXPECT_TRUE(scene.isOccupied({16.07, 0, 1}));
  EXPECT_FALSE(scene.isOccupied({16.07, -4, 1}));
  EXPECT_TRUE(scene.isOccupied({5, 3, 1}));  // partition
  EXPECT_TRUE(scene.isOccupied({-19.9, 0, 1}));
  EXPECT_TRUE(scene.isOccupied({0, 12.4, 2.4}));
}

TEST(BuildingFloorTest, LoopPathGoesRoundTheCorridor) {
  const Scene scene = makeBuildingFloorScene();
  EXPECT_NEAR(buildingLoopLength(), kLoopLength, 1e-9);
  EXPECT_GE(buildingLoopLength(), 60.0);
  const std::vector<Eigen::Isometry3d> path = buildingLoopPath(0.2, 1.0);
  ASSERT_EQ(path.size(), 442u);  // floor(88.28 / 0.2) + 1
  EXPECT_TRUE(path[0].translation().isApprox(Eigen::Vector3d(0, -7.5, 0)));
  EXPECT_NEAR(yawOf(path[0]), 0.0, 1e-12);
  double length = 0.0, turned = 0.0;
  Eigen::AlignedBox3d visited;
  for (std::size_t k = 0; k < path.size(); ++k) {
    const Eigen::Vector3d p = path[k].translation();
    visited.extend(p);
    EXPECT_EQ(p.z(), 0.0);
    EXPECT_NEAR(path[k].linear()(2, 2), 1.0, 1e-12);  // upright
    EXPECT_FALSE(scene.isOccupied(p + Eigen::Vector3d(0, 0, 0.3))) << k;
    EXPECT_GE(scene.distanceToSurface(p + Eigen::Vector3d(0, 0, 1)), 0.6) << k;
    if (k == 0) continue;
    const Eigen::Vector3d step = p - path[k - 1].translation();
    length += step.norm();
    const double turn = std::remainder(yawOf(path[k]) - yawOf(path[k - 1]), 2 * M_PI);
    turned += turn;
    EXPECT_GE(turn, -1e-12) << k;       // counter-clockwise only
    EXPECT_LE(turn, 0.2 + 1e-12) << k;  // smoothly: 0.2 m on a 1 m arc
    // Heading along the travel: the chord's direction lies between the two yaws (their mean
    // on an arc, equal to both on a straight).
    const double chord =
        std::remainder(std::atan2(step.y(), step.x()) - yawOf(path[k - 1]), 2 * M_PI);
    EXPECT_GE(chord, -1e-9) << k;
    EXPECT_LE(chord, turn + 1e-9) << k;
    if (std::abs(turn - 0.2) < 1e-9) {
      EXPECT_NEAR(chord, turn / 2, 1e-9) << k;
    }
  }
  // Chords of 0.2 rad on the arcs are 0.3 mm shorter than the arc: 1 cm over 31 of them.
  EXPECT_NEAR(length, 441 * 0.2 - 0.0102, 0.001);
  EXPECT_NEAR(turned, 2 * M_PI, 1e-9);
  EXPECT_TRUE(visited.min().isApprox(Eigen::Vector3d(-15, -7.5, 0), 1e-9));
  EXPECT_TRUE(visited.max().isApprox(Eigen::Vector3d(15, 7.5, 0), 1e-9));
  // Back near the start after a lap; 1.25 laps go on along the south and east corridors.
  EXPECT_NEAR((path.back().translation() - path[0].translation()).norm(), kLoopLength - 88.2, 1e-9);
  const std::vector<Eigen::Isometry3d> longer = buildingLoopPath(0.2, 1.25);
  ASSERT_EQ(longer.size(), 552u);
  EXPECT_NEAR(longer.back().translation().x(), 15.0, 1e-9);  // on the east side
}

// Stretched to 60 x 40 m: walls, doorways and the corridor where the plan puts them times the
// stretch, the things that stand in rooms at their size, the loop still clear of everything.
TEST(BuildingFloorTest, StretchedFloorKeepsItsPlan) {
  const Eigen::Vector2d stretch(1.5, 1.6);
  const Scene scene = stretchedInPlane(makeBuildingFloorScene(), stretch);
  EXPECT_TRUE(scene.bounds().min().isApprox(Eigen::Vector3d(-30, -20, 0)));
  EXPECT_TRUE(scene.bounds().max().isApprox(Eigen::Vector3d(30, 20, 2.5)));
  // The spine wall along y = 0 (0.15 m thick, 0.24 stretched) and its doorway at x = -9.5.
  EXPECT_TRUE(scene.isOccupied({0.0 * 1.5, 0.0, 1.0}));
  EXPECT_TRUE(scene.isOccupied({3.0 * 1.5, 0.11, 1.0}));
  EXPECT_FALSE(scene.isOccupied({-9.5 * 1.5, 0.0, 1.0}));
  // The sphere of r = 0.4 m at (-2.5, 4.8, 0.4) keeps its radius.
  EXPECT_NEAR(scene.distanceToSurface({-2.5 * 1.5, 4.8 * 1.6, 1.3}), 0.5, 1e-9);
  const std::vector<Eigen::Isometry3d> path = buildingLoopPath(0.2, 1.0, stretch);
  const double length = 2.0 * (30.0 * 1.5 + 15.0 * 1.6) - 8.0 + 2.0 * M_PI;
  EXPECT_NEAR(0.2 * static_cast<double>(path.size() - 1), length, 0.2);
  for (const Eigen::Isometry3d& pose : path) {
    ASSERT_GE(scene.distanceToSurface(pose.translation() + Eigen::Vector3d(0, 0, 1)), 0.6)
        << pose.translation().transpose();
  }
  EXPECT_THROW(stretchedInPlane(scene, Eigen::Vector2d(0.0, 1.0)), std::invalid_argument);
}

TEST(BuildingFloorTest, RoundedRectanglePathChecksItsArguments) {
  const Eigen::AlignedBox2d box(Eigen::Vector2d(0, 0), Eigen::Vector2d(4, 2));
  EXPECT_EQ(roundedRectanglePath(box, 0.5, 2.0, 0.1, 0.0).size(), 1u);
  EXPECT_NEAR(roundedRectangleLength(box, 0.5), 12.0 - 4.0 + M_PI, 1e-12);
  EXPECT_THROW(roundedRectanglePath(box, 0.5, 2.0, 0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(roundedRectanglePath(box, 0.5, 2.0, 0.1, -1.0), std::invalid_argument);
  EXPECT_THROW(roundedRectanglePath(box, 1.5, 2.0, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(roundedRectanglePath(box, 0.5, 0.2, 0.1, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace sim
}  // namespace occupancy_fusion
