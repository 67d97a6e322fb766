#include "occupancy_fusion/sim/scenes.h"

#include <cmath>

namespace occupancy_fusion {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

Box aabb(double x0, double y0, double z0, double x1, double y1, double z1) {
  return Box::axisAligned({x0, y0, z0}, {x1, y1, z1});
}

Plane floorAtZero() { return Plane{Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()}; }

// Walls 0.1 m thick along the inside of the outline x in [-half_x, half_x], y in [-half_y,
// half_y], `height` high: right (-y), left (+y), back (-x), front (+x).
void addWalls(Scene* scene, double half_x, double half_y, double height) {
  constexpr double kThickness = 0.1;
  const double inner_y = half_y - kThickness;
  scene->add(aabb(-half_x, -half_y, 0.0, half_x, -inner_y, height))
      .add(aabb(-half_x, inner_y, 0.0, half_x, half_y, height))
      .add(aabb(-half_x, -inner_y, 0.0, -half_x + kThickness, inner_y, height))
      .add(aabb(half_x - kThickness, -inner_y, 0.0, half_x, inner_y, height));
}

// A desk's top (x0, y0)-(x1, y1), 3 cm thick at 0.72-0.75 m, on four 4 cm legs at its corners.
void addDesk(Scene* scene, double x0, double y0, double x1, double y1) {
  constexpr double kTop = 0.72, kLeg = 0.04;
  scene->add(aabb(x0, y0, kTop, x1, y1, kTop + 0.03));
  for (double x : {x0, x1 - kLeg}) {
    for (double y : {y0, y1 - kLeg}) scene->add(aabb(x, y, 0.0, x + kLeg, y + kLeg, kTop));
  }
}

// A chair at (x, y) (its seat's corner), 0.45 m square: a 4 cm seat at 0.45 m on 3 cm legs and
// a 4 cm back up to 0.95 m along its +y edge.
void addChair(Scene* scene, double x, double y) {
  constexpr double kSide = 0.45, kSeat = 0.45, kLeg = 0.03;
  scene->add(aabb(x, y, kSeat, x + kSide, y + kSide, kSeat + 0.04))
      .add(aabb(x, y + kSide - 0.04, kSeat + 0.04, x + kSide, y + kSide, 0.95));
  for (double lx : {x, x + kSide - kLeg}) {
    for (double ly : {y, y + kSide - kLeg}) {
      scene->add(aabb(lx, ly, 0.0, lx + kLeg, ly + kLeg, kSeat));
    }
  }
}

}  // namespace

Scene makeBoxScene() {
  Scene scene;
  // Shell: floor, ceiling, back (behind the camera), front, right (-y) and left (+y) slabs.
  scene.add(aabb(-1.2, -5.4, -0.2, 10.0, 5.4, 0.0))
      .add(aabb(-1.2, -5.4, 7.9, 10.0, 5.4, 8.1))
      .add(aabb(-1.2, -5.4, 0.0, -1.0, 5.4, 7.9))
      .add(aabb(9.8, -5.4, 0.0, 10.0, 5.4, 7.9))
      .add(aabb(-1.0, -5.4, 0.0, 9.8, -5.2, 7.9))
      .add(aabb(-1.0, 5.2, 0.0, 9.8, 5.4, 7.9));
  // Six 1 m wide objects at increasing depth, spread sideways so each stays partly visible.
  scene.add(aabb(2.0, -0.9, 0.0, 3.0, 0.1, 1.0))
      .add(Sphere{Eigen::Vector3d(4.0, 0.8, 1.0), 0.5})
      .add(Cylinder::upright(5.5, -1.6, 0.0, 0.5, 2.5))
      .add(Box::yawed(Eigen::Vector3d(7.0, 2.4, 1.0), Eigen::Vector3d(1.0, 1.0, 2.0), kPi / 6))
      .add(aabb(8.0, -4.0, 0.0, 9.0, -3.0, 4.0))
      .add(aabb(8.8, 0.0, 2.0, 9.8, 1.0, 3.0));
  return scene;
}

Eigen::Vector3d boxSceneCameraPosition() { return {0.0, 0.0, 1.5}; }

Scene makeSpheresScene() {
  Scene scene;
  scene.add(aabb(1.4, -1.1, 0.0, 2.0, -0.3, 2.1))
      .add(Sphere{Eigen::Vector3d(1.5, 0.6, 0.5), 0.5})
      .add(Sphere{Eigen::Vector3d(0.9, -0.6, 0.4), 0.4})
      .add(Sphere{Eigen::Vector3d(0.3, 0.75, 0.3), 0.3})
      .add(Sphere{Eigen::Vector3d(0.2, -0.1, 0.2), 0.2});
  return scene;
}

Eigen::Vector3d spheresSceneCameraPosition() { return {-2.0, 0.0, 1.05}; }

Scene makeCorridorScene() {
  Scene scene;
  scene.add(floorAtZero())
      .add(aabb(0.0, -1.4, 0.0, 20.2, -1.2, 2.5))  // right wall
      .add(aabb(0.0, 1.2, 0.0, 7.0, 1.4, 2.5))     // left wall, before the doorway
      .add(aabb(8.0, 1.2, 0.0, 20.2, 1.4, 2.5))    // left wall, after the doorway
      .add(aabb(20.0, -1.2, 0.0, 20.2, 1.2, 2.5))  // end wall
      .add(Cylinder::upright(4.0, 1.05, 0.0, 0.15, 2.5))
      .add(Cylinder::upright(9.0, -1.05, 0.0, 0.15, 2.5))
      .add(Cylinder::upright(14.0, 1.05, 0.0, 0.15, 2.5))
      .add(aabb(5.7, -1.0, 0.0, 6.3, -0.4, 0.8))
      .add(Box::yawed(Eigen::Vector3d(11.5, 0.6, 0.5), Eigen::Vector3d(0.8, 0.5, 1.0),
                      20.0 * kPi / 180.0))
      .add(aabb(16.75, -0.75, 0.0, 17.25, -0.25, 0.4));
  return scene;
}

Scene makeAisleScene() {
  Scene scene;
  scene.add(floorAtZero());
  for (double x = 1.0; x < 13.0; x += 2.6) {
    scene
        .add(aabb(x, 1.5, 0.0, x + 2.2, 2.2, 2.2))           // left shelving unit
        .add(aabb(x + 0.7, -2.3, 0.0, x + 2.9, -1.6, 1.6));  // right one, shifted
  }
  scene.add(aabb(14.0, -4.0, 0.0, 14.3, 4.0, 3.0))
      .add(Cylinder::upright(5.0, 0.9, 0.0, 0.08, 2.8))
      .add(Cylinder::upright(9.5, -1.0, 0.0, 0.3, 1.7))
      .add(Box::yawed(Eigen::Vector3d(7.2, 0.2, 0.25), Eigen::Vector3d(1.2, 0.8, 0.5), 0.5))
      .add(Sphere{Eigen::Vector3d(11.0, 0.6, 0.35), 0.35})
      .add(aabb(3.0, -1.2, 0.7, 3.8, -0.6, 0.75));
  return scene;
}

Scene makeRoomScene() {
  Scene scene;
  scene.add(floorAtZero());
  addWalls(&scene, 4.0, 3.0, 2.5);
  scene
      .add(aabb(0.7, 0.55, 0.0, 2.3, 1.45, 0.75))  // table
      .add(Cylinder::upright(-2.0, -1.5, 0.0, 0.25, 1.2))
      .add(Sphere{Eigen::Vector3d(-1.5, 1.6, 0.4), 0.4})
      .add(aabb(2.4, -2.9, 0.0, 3.2, -2.4, 1.8));  // cabinet
  return scene;
}

Scene makeOfficeScene() {
  Scene scene;
  scene.add(floorAtZero());
  addWalls(&scene, 5.0, 4.0, 2.6);
  addDesk(&scene, -1.6, -1.4, 0.0, -0.6);
  addDesk(&scene, 0.6, 0.8, 2.2, 1.6);
  addChair(&scene, -1.0, -0.55);
  addChair(&scene, 1.2, 0.55);
  scene
      .add(Cylinder::upright(2.8, -1.8, 0.70, 0.5, 0.03))  // round table's top
      .add(Cylinder::upright(2.8, -1.8, 0.0, 0.04, 0.70))  // and its pole
      .add(aabb(-4.9, 1.5, 0.0, -4.5, 3.5, 2.0))           // bookshelf
      .add(aabb(3.5, 2.5, 0.0, 4.9, 3.9, 0.45))            // couch
      .add(aabb(4.7, 2.5, 0.45, 4.9, 3.9, 0.9))            // its back
      .add(Cylinder::upright(-3.5, -3.2, 0.0, 0.02, 1.6))  // floor lamp
      .add(Sphere{Eigen::Vector3d(-3.5, -3.2, 1.7), 0.15})
      .add(Cylinder::upright(0.5, -3.0, 0.0, 0.2, 2.6))  // column
      .add(aabb(-2.5, 3.5, 0.0, -1.5, 3.9, 1.0));        // cabinet
  return scene;
}

}  // namespace sim
}  // namespace occupancy_fusion
