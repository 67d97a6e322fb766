// The loop-closure evaluation: a robot with a depth camera, two 2D lasers and a stereo camera
// drives a building floor's corridor loop with drifting odometry while a graph-SLAM stand-in
// (sim/localisation_stand_in.h) publishes map -> odom and its keyframe path, correcting the past
// when the robot returns to a place it saw. The same rendered frames are mapped
//  - as without submaps (frames placed by map -> odom at their time, never moved),
//  - re-anchored by the path and by tf's map -> odom (mapping/map_reanchoring.h),
//  - with the true poses all along,
// and each map is measured against the scene and the true-pose map as the frames come: false
// occupied voxels (in free space, farther than a voxel diagonal from any surface), coverage of
// the scene's surface (a sample with an occupied voxel within one voxel), and the occupied cells
// of the fused 2D grid (projected_map) against the true-pose map's (IoU). Shared by `benchmark
// loop-closure` and the tests.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/mapping/map_reanchoring.h"
#include "occupancy_fusion/mapping/mapping_session.h"
#include "occupancy_fusion/sim/localisation_stand_in.h"
#include "occupancy_fusion/sim/odometry_drift.h"

namespace occupancy_fusion {

struct LoopClosureCase {
  // The mappers' settings (the shipped config files', as the benchmark reads them); resolution,
  // the fused band and reanchoring are set per run from the fields below.
  MappingSessionConfig mapping;
  double resolution = 0.05;  // m
  double step = 0.2;         // m between frames along the loop (5 Hz: 1 m/s)
  double laps = 1.25;        // of the 88 m loop: back at the start once, then on
  double rate_hz = 5.0;      // frames per second (the stamps)
  // Frames fed at rate_hz by the wall clock, as sensors give them (a correction then runs beside
  // the mappers on the cores they leave), instead of each as soon as the one before is mapped.
  bool real_time = false;
  sim::OdometryDriftConfig drift = sim::OdometryDriftConfig();
  // The odometry slips by (x m, y m, yaw rad) between the first two frames (a wheel slip), and
  // the localisation learns it at the first loop closure: with drift.scaled(0) the corrections
  // are then this slip exactly, so what is left of a re-anchored map's error is its submaps'
  // re-sampling (and the first submap, which holds the slip).
  Eigen::Vector3d odometry_slip = Eigen::Vector3d::Zero();
  sim::LocalisationConfig localisation;
  bool depth = true, lasers = true, stereo = true;
  int evaluate_every = 25;       // frames between the points of the curves (and the last frame)
  double submap_distance = 3.0;  // m (reanchoring/submap_distance)
  // The building floor stretched in x and y (sim::stretchedInPlane): (1.5, 1.6) is 60 x 40 m.
  Eigen::Vector2d stretch = Eigen::Vector2d::Ones();

  void validate() const;  // throws std::invalid_argument naming the bad field
};

enum class LoopClosureMapping { kToday, kPath, kTf, kTruePoses };
const char* loopClosureMappingName(LoopClosureMapping mapping);

struct LoopClosureQuality {
  int frame = 0;
  std::size_t occupied = 0;
  std::size_t false_occupied = 0;
  double coverage = 0.0;          // of the scene's surface samples in the sensors' height band
  std::size_t grid_occupied = 0;  // cells of the fused 2D grid
  double grid_iou = 0.0;          // with the true-pose map's grid at the same frame
  // The same within one cell: of both grids' occupied cells, those with one of the other's in
  // their 3 x 3 neighbourhood (a wall one cell off counts; a wall 0.5 m off does not).
  double grid_agreement = 0.0;
};

struct LoopClosureRun {
  LoopClosureMapping mapping = LoopClosureMapping::kToday;
  std::vector<LoopClosureQuality> curve;             // every evaluate_every frames, and the last
  LoopClosureQuality last;                           // after the last frame
  double depth_ms = 0, laser_ms = 0, stereo_ms = 0;  // integration per frame, pose lookup included
  std::size_t map_bytes = 0;                         // voxels and laser layer
  std::size_t submap_bytes = 0;                      // the submaps' changes (reanchored runs)
  std::size_t submaps = 0;
  std::size_t corrections = 0;              // that moved a submap
  double slowest_correction_seconds = 0.0;  // laser cells drawn again included
  double slowest_move_seconds = 0.0;        // until the map was re-sampled at the new places
  OccupancyRaster final_grid;               // projected_map after the last frame
};

struct LoopClosureResult {
  LoopClosureCase setup;
  int frames = 0;
  std::vector<int> corrections;       // frames at which the stand-in corrected the past
  double loop_length = 0.0;           // m of travel
  double drift_before_closure = 0.0;  // m, odometry's error at the first correction
  std::vector<LoopClosureRun> runs;   // true poses first, then as asked
};

// Renders the case's frames once and maps them as each of `mappings` (the true-pose run always
// comes first: the others' grids are compared with its). `progress` (may be null) gets a line
// per run.
LoopClosureResult evaluateLoopClosure(const LoopClosureCase& setup,
                                      const std::vector<LoopClosureMapping>& mappings,
                                      std::ostream* progress);

// A real laser log with its corrected poses (CARMEN): odometry made from the corrected poses with
// the case's seeded drift, and the corrected trajectory published as the SLAM path every
// `path_every` scans (keyframes a metre apart). The laser layer mapped without submaps (each scan
// placed by the correction of the last path), re-anchored by the path, and with the corrected
// poses; the occupied cells of each against the corrected-pose layer's.
struct CarmenReanchoringResult {
  std::size_t scans = 0;
  double travel = 0.0;              // m, of the corrected trajectory
  double largest_drift = 0.0;       // m, the odometry's largest error
  std::size_t corrected_cells = 0;  // occupied cells of the corrected-pose layer
  double iou_without_submaps = 0.0, iou_path = 0.0;
  double within_one_cell_without_submaps = 0.0, within_one_cell_path = 0.0;
  double slowest_correction_seconds = 0.0;
};
CarmenReanchoringResult evaluateCarmenReanchoring(const std::string& log_path,
                                                  const LoopClosureCase& setup, int path_every,
                                                  std::size_t max_scans);

}  // namespace occupancy_fusion
