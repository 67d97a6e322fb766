#include "occupancy_fusion/sim/scenes.h"

#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
// The building loop's turns: arcs of 1 m radius pass 1 m from the corridor's inner corner.
constexpr double kLoopCornerRadius = 1.0;  // m

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

// A wall 2.5 m high over the footprint [x0, x1] x [y0, y1], running along its longer side, with
// a 1 m doorway (full height: there is no ceiling) centred at each of `doors` (ascending
// positions along it).
void addWall(Scene* scene, double x0, double y0, double x1, double y1,
             std::initializer_list<double> doors = {}) {
  constexpr double kHeight = 2.5, kHalfDoor = 0.5;
  const bool along_x = x1 - x0 >= y1 - y0;
  auto piece = [&](double from, double to) {
    if (to > from)
      scene->add(along_x ? aabb(from, y0, 0, to, y1, kHeight) : aabb(x0, from, 0, x1, to, kHeight));
  };
  double from = along_x ? x0 : y0;
  for (double door : doors) {
    piece(from, door - kHalfDoor);
    from = door + kHalfDoor;
  }
  piece(from, along_x ? x1 : y1);
}

// The building floor's walls: exterior, the corridor ring's two sides, the rooms' partitions.
void addBuildingWalls(Scene* scene) {
  addWall(scene, -20, -12.5, 20, -12.3);
  addWall(scene, -20, 12.3, 20, 12.5);
  addWall(scene, -20, -12.3, -19.8, 12.3);
  addWall(scene, 19.8, -12.3, 20, 12.3);
  // The corridor's outer side; its west and east walls run on to the exterior walls.
  addWall(scene, -16, -8.65, 16, -8.5, {-11, -1, 10});
  addWall(scene, -16, 8.5, 16, 8.65, {-12, -3, 4.5, 12.5});
  addWall(scene, -16.15, -12.3, -16, 12.3, {2});
  addWall(scene, 16, -12.3, 16.15, 12.3, {-4, 4.5});
  // Its inner side: the central block.
  addWall(scene, -14, -6.5, 14, -6.35, {-10, -2, 10});
  addWall(scene, -14, 6.35, 14, 6.5, {-9, 2, 9});
  addWall(scene, -14, -6.35, -13.85, 6.35, {3.5});
  addWall(scene, 13.85, -6.35, 14, 6.35, {-3});
  // Rooms: the central block's spine and partitions, then the outer rooms'.
  addWall(scene, -13.85, -0.075, 13.85, 0.075, {-9.5});
  for (double x : {-5.0, 5.0}) {
    addWall(scene, x - 0.075, 0.075, x + 0.075, 6.35);
    addWall(scene, x - 0.075, -6.35, x + 0.075, -0.075);
  }
  for (double x : {-8.0, 0.0, 8.0}) addWall(scene, x - 0.075, 8.65, x + 0.075, 12.3);
  addWall(scene, 3.925, -12.3, 4.075, -8.65);
  addWall(scene, 16.15, -0.075, 19.8, 0.075);
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

Scene makeBuildingFloorScene() {
  Scene scene;
  scene.add(floorAtZero());
  addBuildingWalls(&scene);
  // The corridor: pillars, cabinets and low boxes against its walls, clear of the centre line.
  scene.add(Cylinder::upright(-6.0, -8.3, 0.0, 0.15, 2.5))
      .add(Cylinder::upright(14.2, 2.0, 0.0, 0.15, 2.5))
      .add(Cylinder::upright(6.0, 8.3, 0.0, 0.15, 2.5))
      .add(aabb(4.0, -6.85, 0.0, 4.8, -6.5, 1.8))
      .add(aabb(-1.0, 6.5, 0.0, -0.2, 6.85, 1.8))
      .add(aabb(-16.0, -3.0, 0.0, -15.65, -2.2, 1.8))
      .add(aabb(15.65, -1.5, 0.0, 16.0, -0.9, 0.5))
      .add(aabb(-6.0, 8.15, 0.0, -5.5, 8.5, 0.4))
      .add(aabb(-14.35, -5.0, 0.0, -14.0, -3.8, 0.45));
  // The central rooms.
  scene
      .add(aabb(-10.3, 2.5, 0.0, -8.7, 3.4, 0.75))  // table
      .add(Cylinder::upright(0.0, 3.2, 0.0, 0.3, 2.5))
      .add(Sphere{Eigen::Vector3d(-2.5, 4.8, 0.4), 0.4})
      .add(aabb(8.0, 0.075, 0.0, 11.0, 0.575, 2.0))  // shelves on the spine
      .add(Box::yawed(Eigen::Vector3d(-9.0, -3.5, 0.4), Eigen::Vector3d(0.8, 0.8, 0.8), 0.4))
      .add(aabb(12.8, -4.5, 0.0, 13.85, -3.7, 1.8));  // cabinet
  addDesk(&scene, -1.0, -4.2, 0.6, -3.4);
  // The outer rooms.
  addDesk(&scene, -14.0, 10.5, -12.4, 11.3);
  scene.add(aabb(14.0, 11.8, 0.0, 15.5, 12.3, 2.0));  // cabinet
  for (double x : {-12.0, -6.0, 0.0}) scene.add(Cylinder::upright(x, -10.5, 0.0, 0.2, 2.5));
  scene.add(Box::yawed(Eigen::Vector3d(2.0, -11.2, 0.5), Eigen::Vector3d(1.2, 0.8, 1.0), 0.3))
      .add(aabb(12.0, -12.3, 0.0, 14.0, -11.7, 1.2))       // counter
      .add(Cylinder::upright(-18.0, -5.0, 0.0, 0.4, 1.0))  // barrel
      .add(aabb(-19.8, 6.0, 0.0, -19.2, 9.0, 1.5))
      .add(Sphere{Eigen::Vector3d(18.0, -8.0, 0.5), 0.5})
      .add(aabb(17.5, 8.0, 0.0, 18.5, 9.0, 0.9));
  return scene;
}

Eigen::AlignedBox2d buildingLoopCentreLine() {
  return Eigen::AlignedBox2d(Eigen::Vector2d(-15.0, -7.5), Eigen::Vector2d(15.0, 7.5));
}

std::vector<Eigen::Isometry3d> buildingLoopPath(double step_m, double laps) {
  return roundedRectanglePath(buildingLoopCentreLine(), kLoopCornerRadius, 0.0, step_m, laps);
}

std::vector<Eigen::Isometry3d> buildingLoopPath(double step_m, double laps,
                                                const Eigen::Vector2d& stretch) {
  const Eigen::AlignedBox2d line = buildingLoopCentreLine();
  const Eigen::AlignedBox2d stretched(line.min().cwiseProduct(stretch),
                                      line.max().cwiseProduct(stretch));
  return roundedRectanglePath(stretched, kLoopCornerRadius, 0.0, step_m, laps);
}

Scene stretchedInPlane(const Scene& scene, const Eigen::Vector2d& stretch) {
  if (!(stretch.minCoeff() > 0.0) || !stretch.allFinite()) {
    throw std::invalid_argument("stretchedInPlane: the stretch must be finite and > 0");
  }
  const Eigen::Vector3d factor(stretch.x(), stretch.y(), 1.0);
  Scene stretched;
  for (const Primitive& primitive : scene.primitives()) {
    std::visit(
        [&](auto shape) {
          using Shape = decltype(shape);
          if constexpr (std::is_same_v<Shape, Box>) {
            shape.T_world_box.translation() = shape.T_world_box.translation().cwiseProduct(factor);
            if (shape.T_world_box.linear().isIdentity(1e-12)) {
              shape.half_extents = shape.half_extents.cwiseProduct(factor);
            }
          } else if constexpr (std::is_same_v<Shape, Plane>) {
            shape.point = shape.point.cwiseProduct(factor);  // exact for the floor and walls
          } else {
            shape.center = shape.center.cwiseProduct(factor);
          }
          stretched.add(shape);
        },
        primitive);
  }
  return stretched;
}

double buildingLoopLength() {
  return roundedRectangleLength(buildingLoopCentreLine(), kLoopCornerRadius);
}

}  // namespace sim
}  // namespace occupancy_fusion
