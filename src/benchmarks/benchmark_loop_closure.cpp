// benchmark loop-closure: a robot with a depth camera, two lasers and a stereo camera drives the
// simulated building floor's corridor loop on drifting odometry while a graph-SLAM stand-in
// corrects the past at loop closures (eval/loop_closure.h). The frames are mapped without
// submaps (as before reanchoring), re-anchored by the SLAM path and by tf's map -> odom, and
// with the true poses; each map against the scene and the true-pose map, after the last frame
// (one line per mapping) and along the way (--curves CSV).
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "occupancy_fusion/eval/loop_closure.h"
#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/tools/command_line.h"
#include "shipped_config.h"

namespace occupancy_fusion {
namespace {

LoopClosureCase caseFrom(const CommandLine& args) {
  LoopClosureCase setup;
  setup.mapping = shippedOrGivenMappingConfig(args);
  setup.resolution = args.doubleValue("resolution", setup.resolution);
  setup.step = args.doubleValue("step", setup.step);
  setup.laps = args.doubleValue("laps", setup.laps);
  setup.drift = setup.drift.scaled(args.doubleValue("drift_scale", 1.0));
  setup.drift.seed = static_cast<unsigned>(args.intValue("drift_seed", 3));
  setup.odometry_slip =
      Eigen::Vector3d(args.doubleValue("slip_x", 0.0), args.doubleValue("slip_y", 0.0),
                      args.doubleValue("slip_yaw", 0.0) * M_PI / 180.0);
  setup.localisation.closure_radius =
      args.doubleValue("closure_radius", setup.localisation.closure_radius);
  setup.localisation.correct_every_frames = args.intValue("correct_every", 0);
  setup.localisation.keyframe_distance =
      args.doubleValue("keyframe_distance", setup.localisation.keyframe_distance);
  setup.submap_distance = args.doubleValue("submap_distance", setup.submap_distance);
  setup.stretch =
      Eigen::Vector2d(args.doubleValue("stretch_x", 1.0), args.doubleValue("stretch_y", 1.0));
  setup.evaluate_every = args.intValue("evaluate_every", setup.evaluate_every);
  setup.real_time = args.intValue("real_time", 0) != 0;
  const std::string sensors = args.value("sensors", "depth,laser,stereo");
  setup.depth = sensors.find("depth") != std::string::npos;
  setup.lasers = sensors.find("laser") != std::string::npos;
  setup.stereo = sensors.find("stereo") != std::string::npos;
  try {
    setup.validate();
  } catch (const std::invalid_argument& error) {
    throw UsageError(error.what());
  }
  return setup;
}

void printRun(const LoopClosureResult& result, const LoopClosureRun& run) {
  const LoopClosureRun& truth = result.runs.front();
  const LoopClosureQuality& q = run.last;
  const double truth_false = static_cast<double>(truth.last.false_occupied);
  // The sensors' own false-occupied voxels are in every map: of those beyond the true-pose map's,
  // the share of the map without submaps' excess.
  const double today_excess = static_cast<double>(result.runs[1].last.false_occupied) - truth_false;
  const double excess = static_cast<double>(q.false_occupied) - truth_false;
  std::printf(
      "loop_closure mapping=%s resolution=%.3f frames=%d corrections=%zu false_occupied=%zu "
      "false_occupied_x_true_poses=%.2f excess_false_occupied_x_without_submaps=%.2f "
      "coverage=%.3f coverage_x_true_poses=%.3f "
      "projected_iou=%.3f projected_within_one_cell=%.3f occupied=%zu depth_ms=%.2f laser_ms=%.2f "
      "stereo_ms=%.2f "
      "map_mb=%.1f submaps=%zu submap_mb=%.1f slowest_move_ms=%.0f slowest_correction_ms=%.0f\n",
      loopClosureMappingName(run.mapping), result.setup.resolution, result.frames, run.corrections,
      q.false_occupied, truth_false > 0 ? q.false_occupied / truth_false : 0.0,
      today_excess > 0 ? excess / today_excess : 0.0, q.coverage,
      truth.last.coverage > 0 ? q.coverage / truth.last.coverage : 0.0, q.grid_iou,
      q.grid_agreement, q.occupied, run.depth_ms, run.laser_ms, run.stereo_ms,
      run.map_bytes / 1048576.0, run.submaps, run.submap_bytes / 1048576.0,
      1e3 * run.slowest_move_seconds, 1e3 * run.slowest_correction_seconds);
}

void writeCurves(const LoopClosureResult& result, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "mapping,frame,occupied,false_occupied,coverage,grid_occupied,projected_iou,"
         "projected_within_one_cell\n";
  for (const LoopClosureRun& run : result.runs) {
    for (const LoopClosureQuality& q : run.curve) {
      out << loopClosureMappingName(run.mapping) << "," << q.frame << "," << q.occupied << ","
          << q.false_occupied << "," << q.coverage << "," << q.grid_occupied << "," << q.grid_iou
          << "," << q.grid_agreement << "\n";
    }
  }
  std::ostringstream corrections;
  for (int frame : result.corrections) corrections << " " << frame;
  std::cerr << "loop closure: curves in " << path << " (corrections at frames" << corrections.str()
            << ")\n";
}

}  // namespace

// --carmen LOG ...: each real log, its laser layer re-anchored against its corrected poses.
int runCarmen(const CommandLine& args, const LoopClosureCase& setup) {
  const int path_every = args.intValue("path_every", 50);
  const int max_scans = args.intValue("max_scans", 0);
  if (path_every < 1 || max_scans < 0) {
    throw UsageError("--path_every must be >= 1 and --max_scans >= 0");
  }
  for (const std::string& log : args.values("carmen")) {
    std::cerr << "loop closure: " << log << "\n";
    const CarmenReanchoringResult result =
        evaluateCarmenReanchoring(log, setup, path_every, static_cast<std::size_t>(max_scans));
    std::printf(
        "loop_closure_carmen log=%s resolution=%.3f scans=%zu travel_m=%.0f largest_drift_m=%.2f "
        "path_every=%d corrected_cells=%zu iou_without_submaps=%.3f iou_reanchored_path=%.3f "
        "within_one_cell_without_submaps=%.3f within_one_cell_reanchored_path=%.3f "
        "slowest_correction_ms=%.0f\n",
        log.substr(log.find_last_of('/') + 1).c_str(), setup.resolution, result.scans,
        result.travel, result.largest_drift, path_every, result.corrected_cells,
        result.iou_without_submaps, result.iou_path, result.within_one_cell_without_submaps,
        result.within_one_cell_path, 1e3 * result.slowest_correction_seconds);
  }
  return 0;
}

int runLoopClosure(const CommandLine& args) {
  const LoopClosureCase setup = caseFrom(args);
  if (args.has("carmen")) return runCarmen(args, setup);
  const LoopClosureResult result = evaluateLoopClosure(
      setup, {LoopClosureMapping::kToday, LoopClosureMapping::kPath, LoopClosureMapping::kTf},
      &std::cerr);
  std::printf(
      "loop_closure_setup frames=%d travel_m=%.1f corrections=%zu "
      "drift_before_first_closure_m=%.2f\n",
      result.frames, result.loop_length, result.corrections.size(), result.drift_before_closure);
  for (const LoopClosureRun& run : result.runs) printRun(result, run);
  if (args.has("curves")) writeCurves(result, args.value("curves"));
  if (args.has("grids")) {
    for (const LoopClosureRun& run : result.runs) {
      const std::string prefix = args.value("grids") + "_" + loopClosureMappingName(run.mapping);
      writePng(run.final_grid, prefix + ".png");
      std::cerr << "loop closure: projected_map of " << loopClosureMappingName(run.mapping)
                << " in " << prefix << ".png\n";
    }
  }
  return 0;
}

}  // namespace occupancy_fusion
