// benchmark: times the package's integrators against their baselines on simulated data.
//
//   benchmark <workload> [options]
//
// One subcommand per workload; each prints one line per case of "key=value" fields, so results
// are easy to grep and compare. Timings are medians over repetitions, each repetition starting
// from empty maps.
#include <octomap/OcTree.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "occupancy_fusion/benchmarks/benchmark_harness.h"
#include "occupancy_fusion/benchmarks/peer_mappers.h"
#include "occupancy_fusion/integrators/point_cloud_integrator.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/trajectory.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {

int runPublish(const CommandLine& args);             // benchmark_publish.cpp
int runDepth(const CommandLine& args);               // benchmark_depth.cpp
int runDepthFig5(const CommandLine& args);           // benchmark_depth_fig5.cpp
int runDepthAccuracy(const CommandLine& args);       // benchmark_depth_accuracy.cpp
int runLaser(const CommandLine& args);               // benchmark_laser.cpp
int runLaserMap(const CommandLine& args);            // benchmark_laser_map.cpp
int runDisparity(const CommandLine& args);           // benchmark_disparity.cpp
int runDisparityArtifacts(const CommandLine& args);  // benchmark_disparity_artifacts.cpp
int runCheckpoint(const CommandLine& args);          // benchmark_checkpoint.cpp
int runSpill(const CommandLine& args);               // benchmark_spill.cpp
int runRobotBudget(const CommandLine& args);         // benchmark_robot_budget.cpp
int runLoopClosure(const CommandLine& args);         // benchmark_loop_closure.cpp
int runDynamic(const CommandLine& args);             // benchmark_dynamic.cpp

namespace {

// ---------------------------------------------------------------------------------------------
// Harness

using bench::Clock;
using bench::median;
using bench::millisecondsSince;
using bench::processCpuMilliseconds;

int positiveInt(const CommandLine& args, const std::string& option, int fallback) {
  const int value = args.intValue(option, fallback);
  if (value < 1) throw UsageError("--" + option + " must be at least 1");
  return value;
}

// ---------------------------------------------------------------------------------------------
// Simulated input

struct SensorCloud {
  std::vector<Eigen::Vector3f> points;  // map frame
  Eigen::Vector3d origin;               // map frame, exactly representable as float
};

// A depth camera of about `points` pixels (4:3, the field of view of a 640 x 480 camera with
// fx = 525 px) orbiting in the simulator's demo room and looking across it; the points of
// each frame in the map frame, as the point-cloud mapper receives them.
std::vector<SensorCloud> roomClouds(int clouds, int points) {
  sim::PinholeCamera camera;
  camera.width = std::max(4, static_cast<int>(std::lround(std::sqrt(points * 4.0 / 3.0))));
  camera.height = std::max(3, (points + camera.width - 1) / camera.width);
  camera.fx = camera.fy = 525.0 * camera.width / 640.0;
  camera.cx = 0.5 * (camera.width - 1);
  camera.cy = 0.5 * (camera.height - 1);
  const sim::Scene scene = sim::makeRoomScene();
  const std::vector<Eigen::Isometry3d> poses = sim::orbitTrajectory(
      Eigen::Vector3d::Zero(), 0.6, 1.2, clouds, Eigen::Vector3d(0.0, 0.0, 0.9));
  constexpr double kRenderRange = 12.0;  // m, beyond the room's diagonal
  std::vector<SensorCloud> result;
  for (Eigen::Isometry3d pose : poses) {
    pose.translation() = pose.translation().cast<float>().cast<double>();
    SensorCloud cloud;
    cloud.origin = pose.translation();
    for (const Eigen::Vector3d& p : sim::renderPointCloud(scene, camera, pose, kRenderRange)) {
      cloud.points.push_back((pose * p).cast<float>());
    }
    result.push_back(std::move(cloud));
  }
  return result;
}

// ---------------------------------------------------------------------------------------------
// pointcloud: PointCloudIntegrator vs octomap::OcTree::insertPointCloud

struct RunResult {
  double ms_per_cloud = 0.0;         // mean, the first cloud's allocations included
  double median_ms_per_cloud = 0.0;  // the peers' statistic (bench::runPeers)
  std::size_t memory_bytes = 0;
  double cpu_ms_per_cloud = 0.0;  // the process's CPU (every thread) over the run, per cloud
};

RunResult runOurs(const std::vector<SensorCloud>& clouds, double resolution, double max_range,
                  bool discretize) {
  VoxelMapConfig map_config;
  map_config.resolution = resolution;
  VoxelMap map(map_config);
  PointCloudIntegratorConfig config;
  config.max_range = max_range;
  config.discretize = discretize;
  const PointCloudIntegrator integrator(config);
  std::vector<double> ms;
  const double cpu_start = processCpuMilliseconds();
  for (const SensorCloud& cloud : clouds) {
    const auto start = Clock::now();
    integrator.integrate(cloud.points, cloud.origin, &map);
    ms.push_back(millisecondsSince(start));
  }
  const double cpu_ms = (processCpuMilliseconds() - cpu_start) / clouds.size();
  double total = 0.0;
  for (double m : ms) total += m;
  return {total / clouds.size(), median(ms), map.memoryBytes(), cpu_ms};
}

RunResult runOctomap(const std::vector<octomap::Pointcloud>& clouds,
                     const std::vector<SensorCloud>& sources, double resolution, double max_range,
                     bool discretize) {
  octomap::OcTree tree = bench::makeOctomapTree(resolution);
  // liboctomap inserts on this thread alone (Debian's library is built without OpenMP: one key
  // ray buffer, so one thread): this thread's CPU, without our team's threads winding down.
  const double cpu_start = bench::threadCpuMilliseconds();
  const auto start = Clock::now();
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    const Eigen::Vector3d& o = sources[i].origin;
    tree.insertPointCloud(clouds[i], octomap::point3d(o.x(), o.y(), o.z()), max_range, false,
                          discretize);
  }
  const double mean = millisecondsSince(start) / clouds.size();
  return {mean, mean, tree.memoryUsage(),
          (bench::threadCpuMilliseconds() - cpu_start) / static_cast<double>(clouds.size())};
}

int runPointCloud(const CommandLine& args) {
  const std::vector<double> resolutions =
      bench::parsePositiveList<double>("resolution", args.value("resolution", "0.05,0.1"));
  const std::vector<int> point_counts =
      bench::parsePositiveList<int>("points", args.value("points", "20000"));
  const int cloud_count = positiveInt(args, "clouds", 10);
  const int repetitions = positiveInt(args, "repetitions", 3);
  const double max_range = args.doubleValue("max_range", -1.0);
  const bool discretize = args.intValue("discretize", 0) != 0;
  const int threads = omp_get_max_threads();

  for (int points : point_counts) {
    const std::vector<SensorCloud> clouds = roomClouds(cloud_count, points);
    std::vector<octomap::Pointcloud> octomap_clouds(clouds.size());
    std::size_t total_points = 0;
    for (std::size_t i = 0; i < clouds.size(); ++i) {
      for (const Eigen::Vector3f& p : clouds[i].points)
        octomap_clouds[i].push_back(p.x(), p.y(), p.z());
      total_points += clouds[i].points.size();
    }
    std::vector<std::vector<Eigen::Vector3f>> peer_points;
    std::vector<Eigen::Vector3d> peer_origins;
    for (const SensorCloud& cloud : clouds) {
      peer_points.push_back(cloud.points);
      peer_origins.push_back(cloud.origin);
    }
    for (double resolution : resolutions) {
      std::vector<double> ours_ms, ours_cloud_ms, octomap_ms, ours_cpu_ms, octomap_cpu_ms;
      RunResult ours, theirs;
      for (int r = 0; r < repetitions; ++r) {
        // OctoMap's insertPointCloud (compiled here from its headers) sets the OpenMP thread
        // count to its number of key rays, 1 in Debian's build: give ours its threads back.
        omp_set_num_threads(threads);
        ours = runOurs(clouds, resolution, max_range, discretize);
        theirs = runOctomap(octomap_clouds, clouds, resolution, max_range, discretize);
        ours_ms.push_back(ours.ms_per_cloud);
        ours_cloud_ms.push_back(ours.median_ms_per_cloud);
        octomap_ms.push_back(theirs.ms_per_cloud);
        ours_cpu_ms.push_back(ours.cpu_ms_per_cloud);
        octomap_cpu_ms.push_back(theirs.cpu_ms_per_cloud);
      }
      const double ours_median = median(ours_ms);
      // Against the peers, their statistic: the median cloud (no map allocations in it).
      const double ours_cloud_median = median(ours_cloud_ms);
      const double octomap_median = median(octomap_ms);
      // The peers (benchmarks/peer_mappers.h, when compiled in) on the same clouds, unlimited
      // range.
      std::string peer_fields;
      if (max_range < 0) {
        omp_set_num_threads(threads);  // for ours in the pairs, after liboctomap
        // Paired: cloud i into a map of ours of its own, a new one at cloud 0.
        PointCloudIntegratorConfig config;
        config.discretize = discretize;
        const PointCloudIntegrator integrator(config);
        VoxelMapConfig map_config;
        map_config.resolution = resolution;
        std::unique_ptr<VoxelMap> paired_map;
        const bench::PairedInsert paired = [&](std::size_t i) {
          if (i == 0 || paired_map == nullptr) paired_map = std::make_unique<VoxelMap>(map_config);
          const auto start = Clock::now();
          integrator.integrate(clouds[i].points, clouds[i].origin, paired_map.get());
          return millisecondsSince(start);
        };
        for (const bench::PeerRun& peer :
             bench::runPeers(peer_points, peer_origins, resolution, paired)) {
          char field[300];
          std::snprintf(field, sizeof(field),
                        " %s_ms_per_cloud=%.3f time_ratio_%s=%.3f paired_time_ratio_%s=%.3f "
                        "%s_cpu_ms_per_cloud=%.3f cpu_ratio_%s=%.3f",
                        peer.name.c_str(), peer.median_ms, peer.name.c_str(),
                        ours_cloud_median / peer.median_ms, peer.name.c_str(), peer.paired_ratio,
                        peer.name.c_str(), peer.cpu_ms, peer.name.c_str(),
                        median(ours_cpu_ms) / peer.cpu_ms);
          peer_fields += field;
        }
      }
      std::printf(
          "pointcloud resolution=%g points=%zu ms_per_cloud=%.3f median_cloud_ms=%.3f "
          "octomap_ms_per_cloud=%.3f time_ratio=%.3f memory_ratio=%.3f threads=%d "
          "discretize=%d cpu_ms_per_cloud=%.3f octomap_cpu_ms_per_cloud=%.3f%s\n",
          resolution, total_points / clouds.size(), ours_median, ours_cloud_median, octomap_median,
          ours_median / octomap_median,
          static_cast<double>(ours.memory_bytes) / static_cast<double>(theirs.memory_bytes),
          threads, discretize ? 1 : 0, median(ours_cpu_ms), median(octomap_cpu_ms),
          peer_fields.c_str());
      std::fflush(stdout);
    }
  }
  return 0;
}

// ---------------------------------------------------------------------------------------------
// Subcommands

struct Workload {
  const char* name;
  const char* usage;
  std::set<std::string> value_options;
  std::function<int(const CommandLine&)> run;
};

const std::vector<Workload>& workloads() {
  static const std::vector<Workload> table{
      {"pointcloud",
       "[--resolution R[,R...]] [--points P[,P...]] [--clouds N] [--repetitions K] "
       "[--max_range M] [--discretize 1]\n"
       "      depth-camera clouds (P points each, N clouds orbiting the simulator's room) into\n"
       "      our voxel map and into octomap::OcTree::insertPointCloud (both discretized with\n"
       "      --discretize 1); ratios are ours / octomap, and ours / each peer compiled in",
       {"resolution", "points", "clouds", "repetitions", "max_range", "discretize"},
       runPointCloud},
      {"publish",
       "[--known_voxels K[,K...]] [--changed_blocks B[,B...]] [--repetitions N] [--resolution R]\n"
       "      MapServer's incremental refresh (occupied-voxel cache, fused 2D view) after B\n"
       "      blocks change in a synthetic map of K known voxels, vs rebuilding from the whole map",
       {"known_voxels", "changed_blocks", "repetitions", "resolution"},
       runPublish},
      {"depth",
       "<folder> [--resolution R[,R...]] [--frames N] [--octomap-frames K] [--peer-frames P]\n"
       "      [--k K] [--sigma S] [--sigma_quadratic Q] [--method pyramid|andert|ideal]\n"
       "      [--image PNG] [--finer_layers F] [--clear_passed 0|1]\n"
       "      a depth sequence in the 7-Scenes layout through the pyramidal depth integrator,\n"
       "      and K of its frames as point clouds through octomap::OcTree::insertPointCloud\n"
       "      (plain and discretized); speedup is octomap / ours in ms per frame; the peers\n"
       "      compiled in on P frames (default all), paired frame by frame with ours",
       {"folder", "resolution", "frames", "octomap-frames", "peer-frames", "k", "sigma",
        "sigma_quadratic", "method", "image", "finer_layers", "clear_passed"},
       runDepth},
      {"depth-fig5",
       "[--output PNG] [--sweep_max PX] [--finer_layers F]\n"
       "      Pirker et al.'s Fig. 5: occupancy along the optical axis (obstacles at 6 and 10 m)\n"
       "      for ideal, pyramid and Andert, errors against ideal, plot; edge moved off the axis;\n"
       "      F > 0 adds the pyramid with depth/finer_layers F (not the paper) to all of it",
       {"output", "sweep_max", "finer_layers"},
       runDepthFig5},
      {"depth-accuracy",
       "[--scenes box,spheres] [--methods pyramid,andert,ideal] [--views N] [--resolution R]\n"
       "      [--k K] [--sigma S] [--sigma_quadratic Q] [--unknown_behind_sigmas U]\n"
       "      [--max_range M] [--clamp on|off] [--observe_views N] [--score_every N]\n"
       "      [--region auto|frustum|surface] [--points_csv PREFIX] [--finer_layers F]\n"
       "      [--clear_passed 0|1]\n"
       "      Pirker et al. Sec. 5.1: N of the 181 sweep views of BOX / SPHERES; surface points\n"
       "      within one voxel of the p = 0.5 iso-surface, observed free voxels labelled free",
       {"scenes", "methods", "views", "resolution", "k", "sigma", "sigma_quadratic",
        "unknown_behind_sigmas", "max_range", "clamp", "observe_views", "score_every", "points_csv",
        "region", "finer_layers", "clear_passed"},
       runDepthAccuracy},
      {"laser",
       "<CARMEN log, .gz accepted> [--scans N] [--resolution R] [--sigma S] [--free_length L]\n"
       "      [--images PREFIX [--image_scan I]]\n"
       "      Yguel et al.'s Table I: each scan into a 60 m x 30 m grid by the exact, lines,\n"
       "      sampling and mipmap polar-to-cartesian methods; errors against exact, ms per scan;\n"
       "      and four scanners fused into the vehicle grid per cycle",
       {"folder", "scans", "resolution", "sigma", "free_length", "range_max", "range_resolution",
        "images", "image_scan"},
       runLaser},
      {"laser-map",
       "<CARMEN log, .gz accepted> --output PNG [--method mipmap|sampling|lines|exact]\n"
       "      [--scans N] [--resolution R] [--sigma S] [--free_length L]\n"
       "      every scan of the log at its corrected pose into one world-frame GridLayer2D,\n"
       "      drawn to PNG (free white, occupied black, unknown grey); ms per scan",
       {"folder", "output", "method", "scans", "resolution", "sigma", "free_length", "range_max",
        "range_resolution"},
       runLaserMap},
      {"disparity",
       "<Middlebury scene folder, or a folder of them> [--resolution R[,R...]]\n"
       "      [--input full,half,quarter] [--source gt,sgbm] [--frames N] [--warmup W]\n"
       "      [--repetitions K] [--jitter M] [--jitter_deg D] [--sigma S] [--block_size B]\n"
       "      [--threads T] [--clock cpu|wall] [--unknown_neighbour_occupancy P] [--rtabmap DIR]\n"
       "      [--parameter_set measured|table_i|fast_expansion] [--bundle_rays true|false]\n"
       "      [--method visibility|octomap] [--measured_grid_fraction F]\n"
       "      [--measured_grid_max_px P] [--measured_fuse_known 0|1]\n"
       "      [--picture PREFIX [--picture_scene S] [--picture_resolution R]]\n"
       "      Schauwecker & Zell's visibility-aware stereo integrator on ground-truth and\n"
       "      StereoSGBM disparity vs octomap::OcTree::insertPointCloud (plain, discretized) on\n"
       "      the same points; ratios are ours / octomap",
       {"folder",
        "resolution",
        "input",
        "source",
        "frames",
        "warmup",
        "repetitions",
        "jitter",
        "jitter_deg",
        "sigma",
        "block_size",
        "threads",
        "clock",
        "rtabmap",
        "picture",
        "picture_scene",
        "picture_resolution",
        "unknown_neighbour_occupancy",
        "parameter_set",
        "bundle_rays",
        "method",
        "measured_grid_fraction",
        "measured_grid_max_px",
        "measured_fuse_known"},
       runDisparity},
      {"disparity-artifacts",
       "[--part all|artifacts|fig5a|sweep|matrix] [--frames N] [--resolution R] [--fig5a_updates "
       "U]\n"
       "      [--unknown_neighbours prior|known_only|measured] [--unknown_neighbour_occupancy P] "
       "[--images "
       "DIR]\n"
       "      [--parameter_set table_i|fast_expansion|measured]\n"
       "      [--q_max Q] [--q_min Q] [--p_visible_occluded P] [--p_hit_invisible P]\n"
       "      Schauwecker & Zell Sec. IV-A on the simulated corridor with correlated disparity\n"
       "      errors: false-occupied voxels and surface coverage of the visibility method, the\n"
       "      OctoMap mode and OcTree::insertPointCloud on the same points; Fig. 5a's growth;\n"
       "      sweep: the last four (and --resolution) as comma lists, one line per combination;\n"
       "      matrix [--motions M,..] [--inputs full,half] [--resolution R,..] [--curves CSV]:\n"
       "      a moving camera (forward 0.03/0.1/0.2 m, turning 5 deg, sideways, standing per\n"
       "      frame), the set under test, Table I and the OctoMap mode after every frame;\n"
       "      [--noise_px S] [--patch_probability P] [--patch_px N] [--patch_offset_px O]\n"
       "      [--seed K] vary the matcher's errors (0.3 px, 0.3 of 12 px cells, 1.5 px, 7);\n"
       "      --motions aisle_curve_0.15,aisle_diagonal_0.09,aisle_fast_0.30,aisle_backward_0.10:\n"
       "      the check outside the matrix (a warehouse aisle, a 640x480 camera, other motions);\n"
       "      --motions office_loop_0.10,office_loop_0.25,office_zigzag_0.10,office_zigzag_0.20,\n"
       "      office_backward_0.10: a third (an office of thin furniture, an 848x480 camera)",
       {"part",
        "frames",
        "resolution",
        "fig5a_updates",
        "unknown_neighbours",
        "unknown_neighbour_occupancy",
        "images",
        "q_max",
        "q_min",
        "p_visible_occluded",
        "p_hit_invisible",
        "parameter_set",
        "motions",
        "inputs",
        "curves",
        "measured_window",
        "measured_step_px",
        "measured_grid_px",
        "measured_grid_fraction",
        "measured_grid_max_px",
        "measured_sigma_max_voxels",
        "measured_fuse_known",
        "measured_prior",
        "measured_inside",
        "measured_visibility",
        "clear_passed",
        "passed_sigmas",
        "noise_px",
        "patch_probability",
        "patch_px",
        "patch_offset_px",
        "seed"},
       runDisparityArtifacts},
      {"checkpoint",
       "<scratch folder> [--blocks N[,N...]] [--changed C[,C...]] [--repetitions K]\n"
       "      VoxelMap::checkpoint on maps of N full blocks after C blocks changed: the time\n"
       "      writers wait and the flush after it, beside writing the whole map as .ot",
       {"folder", "blocks", "changed", "repetitions"},
       runCheckpoint},
      {"spill",
       "[--length M] [--step S] [--resolution R] [--bound_mb B [--spill_folder F]]\n"
       "      [--return 1] [--width W --height H] [--csv PATH] [--save PREFIX [--save_liboctomap "
       "1]]\n"
       "      [--laser 0|1] [--layer_bound_mb L]\n"
       "      a depth camera along M metres of corridor with a room every 8 m into a map with\n"
       "      or without a memory bound, and a laser scanner into its 2D layer (bound L);\n"
       "      per frame integration time and resident memory; the save's time and peak memory\n"
       "      (streamed; and through liboctomap's OcTree)",
       {"length", "step", "resolution", "bound_mb", "spill_folder", "return", "width", "height",
        "csv", "save", "save_liboctomap", "laser", "layer_bound_mb"},
       runSpill},
      {"robot-budget",
       "[--seconds N] [--output DIR] [--launch_arg name:=value ...] [--script PATH]\n"
       "      [--dry_run 1]\n"
       "      the whole robot in the ROS graph (scripts/robot_budget.sh, with this build; needs\n"
       "      ROS): depth 640x480 at 30 Hz, disparity at 15 Hz and two lasers at 40 Hz from a\n"
       "      simulated recording at native rates into one manager, projected_map and markers\n"
       "      subscribed; per sensor frames sent, integrated and dropped, latency from the stamp\n"
       "      to the first projected_map that holds it (median, p99), the manager's CPU share;\n"
       "      robot_budget.csv / .txt / .png in DIR (default output/robot_budget). Launch\n"
       "      arguments: resolution, publish_rate, stereo_input, worker_threads, queue_size,\n"
       "      stereo_method, disparity, depth_threads, disparity_threads, disparity_queue_size",
       {"seconds", "output", "launch_arg", "script", "dry_run"},
       runRobotBudget},
      {"loop-closure",
       "[--resolution R] [--step M] [--laps L] [--drift_scale X] [--drift_seed K]\n"
       "      [--closure_radius M] [--correct_every N] [--submap_distance M]\n"
       "      [--keyframe_distance M] (the SLAM stand-in's keyframes: one every M of travel)\n"
       "      [--slip_x M] [--slip_y M] [--slip_yaw DEG] (the odometry slips after the first "
       "frame:\n"
       "      with --drift_scale 0 the corrections are that slip exactly, re-sampling alone)\n"
       "      [--stretch_x X] [--stretch_y Y] (the floor 40 x 25 m times X, Y; 1.5, 1.6: 60 x 40)\n"
       "      [--sensors depth,laser,stereo] [--evaluate_every N] [--curves CSV] [--grids PREFIX]\n"
       "      [--real_time 1] (frames at 5 Hz by the wall clock, not as fast as they are mapped)\n"
       "      [--config FILE ...] (default: the shipped depth, laser, disparity and map server\n"
       "      configs)\n"
       "      --carmen LOG [--carmen LOG ...] [--path_every N] [--max_scans N]: real laser logs\n"
       "      with corrected poses instead: odometry with the seeded drift, the corrected\n"
       "      trajectory as the path every N scans; laser layer IoU with the corrected poses'\n"
       "      a depth camera, two lasers and a stereo camera around the simulated building's\n"
       "      88 m corridor loop on drifting odometry, a graph-SLAM stand-in correcting the past\n"
       "      at loop closures; mapped without submaps, re-anchored by its path and by tf's\n"
       "      map -> odom, and with the true poses: false-occupied voxels, surface coverage and\n"
       "      projected_map's IoU with the true-pose map, mapper times, memory, correction time",
       {"resolution",      "step",           "laps",           "drift_scale",
        "drift_seed",      "closure_radius", "correct_every",  "keyframe_distance",
        "submap_distance", "sensors",        "evaluate_every", "curves",
        "grids",           "config",         "carmen",         "path_every",
        "max_scans",       "stretch_x",      "stretch_y",      "slip_x",
        "slip_y",          "slip_yaw",       "real_time"},
       runLoopClosure},
      {"dynamic",
       "[--events removed_box,person,door,chair] [--mappers depth,stereo,stereo_table_i,\n"
       "      stereo_octomap,point_cloud,laser] [--resolution 0.05,0.1] [--speed 0,0.5]\n"
       "      [--rate_hz R] [--frames_before N] [--frames_after N] [--noise_px P] [--curves CSV]\n"
       "      [--config FILE ...] (rate_hz: frames a second, default 15 for cameras, 10 for the "
       "laser)\n"
       "      an object leaves a sensor's view in the simulated corridor (a box taken away, a "
       "person\n"
       "      walking across at 1 m/s, a door opening, a chair moved), the sensor standing or "
       "moving: "
       "the\n"
       "      ghost voxels (laser cells) it leaves after 1, 3, 5 frames and the frames until "
       "fewer\n"
       "      than 5 % of its voxels are left, the corridor's coverage, ms per frame",
       {"events", "mappers", "resolution", "speed", "rate_hz", "frames_before", "frames_after",
        "noise_px", "curves", "config"},
       runDynamic},
  };
  return table;
}

void printUsage(std::ostream& out) {
  out << "usage: benchmark <workload> [options]\nworkloads:\n";
  for (const Workload& workload : workloads()) {
    out << "  " << workload.name << " " << workload.usage << "\n";
  }
}

int runMain(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    printUsage(argc < 2 ? std::cerr : std::cout);
    return argc < 2 ? kUsageExitCode : 0;
  }
  const std::string name = argv[1];
  for (const Workload& workload : workloads()) {
    if (name != workload.name) continue;
    try {
      // The workload's name stands in for argv[0]: CommandLine skips it. A first argument that
      // is not an option is the input folder ("benchmark depth <folder>"): --folder.
      std::vector<const char*> arguments(argv + 1, argv + argc);
      if (arguments.size() > 1 && std::string(arguments[1]).rfind("--", 0) != 0) {
        arguments.insert(arguments.begin() + 1, "--folder");
      }
      const CommandLine args(static_cast<int>(arguments.size()), arguments.data(),
                             workload.value_options, {});
      return workload.run(args);
    } catch (const UsageError& error) {
      std::cerr << "benchmark " << name << ": " << error.what() << "\n";
      printUsage(std::cerr);
      return kUsageExitCode;
    }
  }
  std::cerr << "benchmark: unknown workload '" << name << "'\n";
  printUsage(std::cerr);
  return kUsageExitCode;
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  try {
    return occupancy_fusion::runMain(argc, argv);
  } catch (const std::exception& error) {
    std::cerr << "benchmark: " << error.what() << "\n";
    return 1;
  }
}
