// Ready-made scenes. All use the world frame of REP-103 (x forward, y left, z up, metres).
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "occupancy_fusion/sim/scene.h"

namespace occupancy_fusion {
namespace sim {

// BOX scene of the depth paper (Sec. 5.1, Fig. 3a): 10.8 x 8.3 x 11.2 m^3 holding six objects
// of 1 m width at different depths. The figure is not available; this layout is our reading.
// The paper's camera frame (x right, y down, z forward) maps onto the world as depth = +x,
// width = y, height = z, so the scene's bounds are exactly 11.2 (x) x 10.8 (y) x 8.3 (z):
// a closed room of 0.2 m thick slabs (outer x in [-1.2, 10], y in [-5.4, 5.4], z in [-0.2, 8.1];
// floor top at z = 0) so every ray of the sweep hits a surface, and inside it, seen from
// boxSceneCameraPosition() looking along +x, six objects whose near sides lie at depths
// 2, 3.5, 5, ~6.3, 8 and 8.8 m:
//   1 m cube on the floor; sphere of 1 m diameter floating at z = 1; upright cylinder of 1 m
//   diameter, 2.5 m high; 1 x 1 x 2 m box turned 30 deg about z; 1 x 1 x 4 m pillar; 1 m cube
//   fixed to the back wall at z = 2..3.
Scene makeBoxScene();
Eigen::Vector3d boxSceneCameraPosition();  // (0, 0, 1.5): centre of the paper's sweep

// SPHERES scene of the depth paper (Sec. 5.1, Fig. 3b): 2.2 x 2.1 x 2 m^3 holding a box and
// four spheres of variable size (our layout): width 2.2 along y (y in [-1.1, 1.1]), height 2.1
// along z (z in [0, 2.1]), depth 2 along x (x in [0, 2]). A 0.6 x 0.8 x 2.1 m box stands at
// the back left; spheres of radius 0.5, 0.4, 0.3 and 0.2 m rest on z = 0 at depths from 0 to
// 1.5 m. No floor, so the bounds are the objects' own.
Scene makeSpheresScene();
Eigen::Vector3d spheresSceneCameraPosition();  // (-2, 0, 1.05): 2 m in front, mid-height

// A straight corridor for stereo and laser tests: floor (half-space z <= 0), inner width 2.4 m
// (y in [-1.2, 1.2]) between 0.2 m thick, 2.5 m high walls, from an open end at x = 0 to an
// end wall at x = 20; a 1 m doorway in the left wall at x in [7, 8] (open behind it); three
// pillars (cylinders, r = 0.15 m) against the walls at x = 4, 9 and 14; three boxes on the floor
// at x = 6, 11.5 (turned 20 deg) and 17 (0.4 m high). No ceiling.
Scene makeCorridorScene();

// The demo room: 8 x 6 x 2.5 m (x in [-4, 4], y in [-3, 3]), floor (half-space z <= 0), 0.1 m
// thick walls along the inside of that outline, no ceiling; a table-like box
// (1.6 x 0.9 x 0.75 m) at (1.5, 1.0), an upright cylinder (r = 0.25 m, 1.2 m high) at
// (-2, -1.5), a sphere (r = 0.4 m) resting on the floor at (-1.5, 1.6) and a cabinet
// (0.8 x 0.5 x 1.8 m) against the right wall at (2.8, -2.65). The centre (0, 0) is free, so
// sensors can move around it.
Scene makeRoomScene();

// A warehouse aisle for the stereo evaluation's check outside its matrix (other scene, camera,
// motions): floor (half-space z <= 0); along +x, shelving 2.2 m high at y in [1.5, 2.2] and 1.6 m
// high at y in [-2.3, -1.6], in 2.2 m long units with 0.4 m gaps, the right row shifted by
// 0.7 m; a wall across at x in [14, 14.3]; a thin pole (r = 0.08 m) at (5, 0.9), a drum
// (r = 0.3 m, 1.7 m high) at (9.5, -1.0), a pallet (1.2 x 0.8 x 0.5 m, yawed 0.5 rad) at
// (7.2, 0.2), a sphere (r = 0.35 m) on the floor at (11, 0.6) and a thin table top (0.8 x 0.6 m,
// 5 cm thick, floating at 0.7 m) at x in [3, 3.8], y in [-1.2, -0.6].
Scene makeAisleScene();

// An office for a third check of the stereo evaluation (other scene, camera and motions again):
// 10 x 8 x 2.6 m (x in [-5, 5], y in [-4, 4]), floor (half-space z <= 0), 0.1 m thick walls
// along the inside of that outline, no ceiling; furniture of thin parts: two desks (tops 3 cm
// thick at 0.72-0.75 m on 4 cm legs), a round table (r = 0.5 m top on a 4 cm pole) at
// (2.8, -1.8), two chairs (4 cm seats at 0.45 m, backs up to 0.95 m, 3 cm legs), a bookshelf, a
// couch, a floor lamp (a 2 cm pole with a 0.15 m sphere at 1.7 m), a column (r = 0.2 m) and a
// cabinet. The ellipse about (0.3, 0.1) with half-axes 3.2 and 2.2 m, and the line y = 0.15 from
// x = -4 to 4, are free at 1.1 m height.
Scene makeOfficeScene();

// A building floor for loop closures: 40 x 25 m (x in [-20, 20], y in [-12.5, 12.5]), floor
// (half-space z <= 0), walls 2.5 m high, no ceiling; exterior walls 0.2 m thick along the inside
// of the outline, inner walls 0.15 m thick, doorways 1 m wide and full height.
//  - A ring corridor, 2 m wide: free between its outer walls (faces at x = +-16, y = +-8.5) and
//    the central block (faces at x = +-14, y = +-6.5). Its free centre line is the rectangle
//    x in [-15, 15], y in [-7.5, 7.5] (90 m; buildingLoopCentreLine()); nothing stands within
//    0.6 m of it (walls 1 m away, at the corners 1.41 m from the inner corner).
//  - Inside the ring, a central block of six rooms: a spine wall along y = 0 (a doorway at
//    x = -9.5) and partitions at x = +-5; doorways onto the corridor at x = -9, 2, 9 (north side),
//    x = -10, -2, 10 (south side), y = 3.5 (west) and y = -3 (east).
//  - Outside the ring, rooms between the corridor and the exterior walls: north, four rooms
//    (partitions at x = -8, 0, 8; doorways at x = -12, -3, 4.5, 12.5); south, a hall
//    (x in [-16, 4], three columns, doorways at x = -11, -1) and a room (doorway at x = 10); west,
//    one room (doorway at y = 2); east, two rooms (partition at y = 0; doorways at y = -4, 4.5).
//  - In the corridor, against its walls 0.6-1 m from the centre line: pillars (r = 0.15 m) at
//    (-6, -8.3), (14.2, 2) and (6, 8.3); cabinets 1.8 m high at x in [4, 4.8] (south, inner wall),
//    x in [-1, -0.2] (north, inner wall) and y in [-3, -2.2] (west, outer wall); low boxes at
//    y in [-1.5, -0.9] (east), x in [-6, -5.5] (north) and y in [-5, -3.8] (west). The rooms hold
//    tables, a desk, shelves, cabinets, columns, crates, a barrel and spheres.
Scene makeBuildingFloorScene();
Eigen::AlignedBox2d buildingLoopCentreLine();  // x in [-15, 15], y in [-7.5, 7.5]

// A larger (or smaller) floor of the same plan: every position x, y times `stretch`'s x and y,
// and axis-aligned boxes (walls, tables, cabinets) stretched with it; spheres, cylinders and
// turned boxes keep their size. Stretched by (1.5, 1.6): a 60 x 40 m floor, a 138 m loop.
Scene stretchedInPlane(const Scene& scene, const Eigen::Vector2d& stretch);

// Robot (body) poses every step_m metres along the building's corridor loop for `laps` laps
// (roundedRectanglePath of buildingLoopCentreLine() with 1 m corner arcs: 88.28 m per lap):
// from (0, -7.5) in the south corridor heading +x, counter-clockwise (east, north, west, south),
// z = 0, yaw along the direction of travel. The default 1.25 laps returns to the start once (a
// loop closure) and goes on over corridor already seen. Throws std::invalid_argument unless
// step_m > 0 and laps >= 0.
std::vector<Eigen::Isometry3d> buildingLoopPath(double step_m = 0.2, double laps = 1.25);
double buildingLoopLength();  // m per lap
// The same on the stretched floor (stretchedInPlane): the centre line stretched, 1 m corner arcs.
std::vector<Eigen::Isometry3d> buildingLoopPath(double step_m, double laps,
                                                const Eigen::Vector2d& stretch);

}  // namespace sim
}  // namespace occupancy_fusion
