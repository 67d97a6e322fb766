// benchmark disparity: Schauwecker & Zell's visibility-aware stereo integrator on real stereo
// pairs (Middlebury 2014 scene folders, optionally the rtabmap pairs), against
// octomap::OcTree::insertPointCloud (plain and discretize=true) on the same points, in the same
// run. Each scene is mapped from its ground-truth disparity and from OpenCV's StereoSGBM on
// im0/im1 (real matcher noise), at every resolution and input resolution; the same view is
// integrated --frames times (a camera standing still; --jitter moves it a little between frames).
#include <octomap/OcTree.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "occupancy_fusion/benchmarks/benchmark_harness.h"
#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/integrators/stereo/visibility_stereo_integrator.h"
#include "occupancy_fusion/map/occupancy_model.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/sensors/middlebury_folder.h"
#include "occupancy_fusion/tools/command_line.h"
#include "occupancy_fusion/tools/stereo_matching.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;
using bench::Clock;
using bench::millisecondsSince;
using bench::processCpuMilliseconds;
using bench::splitList;

// ---------------------------------------------------------------------------------------------
// Disparity from the images: OpenCV's semi-global matcher.

// SgbmSettings and sgbmDisparity: tools/stereo_matching.h (shared with make_demo_recording).

// How far the matcher's disparity is from the ground truth where both exist.
struct MatchQuality {
  double valid_fraction = 0.0;  // matched pixels / ground-truth pixels
  double bad2_fraction = 0.0;   // of pixels valid in both, error above 2 px (Middlebury's bad 2.0)
  double median_error = 0.0;    // px
};

MatchQuality compareDisparity(const std::vector<float>& matched, const std::vector<float>& truth) {
  std::size_t truth_count = 0, both = 0, bad = 0;
  std::vector<double> errors;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (!std::isfinite(truth[i])) continue;
    ++truth_count;
    if (!std::isfinite(matched[i])) continue;
    ++both;
    const double error = std::abs(matched[i] - truth[i]);
    bad += error > 2.0 ? 1 : 0;
    errors.push_back(error);
  }
  MatchQuality quality;
  quality.valid_fraction = truth_count == 0 ? 0.0 : static_cast<double>(both) / truth_count;
  quality.bad2_fraction = both == 0 ? 0.0 : static_cast<double>(bad) / both;
  quality.median_error = errors.empty() ? 0.0 : bench::median(errors);
  return quality;
}

// ---------------------------------------------------------------------------------------------
// One stereo view and the poses it is integrated from.

struct StereoView {
  std::string scene;
  std::string source;  // "gt" or "sgbm"
  int width = 0;
  int height = 0;
  std::vector<float> disparity;  // px, z = f * b / value, NaN = none
  StereoCamera camera;

  DisparityImageView view() const { return {width, height, disparity.data(), 0}; }
};

// Frame 0 at the identity; later frames moved by up to jitter_m along each axis and turned by up
// to jitter_deg about a random axis (0: the camera stands still). Same seed: same poses for both
// mappers.
std::vector<Eigen::Isometry3d> framePoses(int frames, double jitter_m, double jitter_deg) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Eigen::Isometry3d> poses(frames, Eigen::Isometry3d::Identity());
  for (int i = 1; i < frames; ++i) {
    const Eigen::Vector3d axis = Eigen::Vector3d(unit(random), unit(random), unit(random));
    const double angle = jitter_deg * M_PI / 180.0 * unit(random);
    if (axis.norm() > 1e-9)
      poses[i].linear() = Eigen::AngleAxisd(angle, axis.normalized()).matrix();
    poses[i].translation() = jitter_m * Eigen::Vector3d(unit(random), unit(random), unit(random));
  }
  return poses;
}

// ---------------------------------------------------------------------------------------------
// The two mappers on identical points.

struct MapRun {
  double ms_per_frame = 0.0;  // the clock chosen by --clock
  double wall_ms_per_frame = 0.0;
  double cpu_ms_per_frame = 0.0;
  std::size_t memory_bytes = 0;
  double cache_hit_rate = 0.0;
  std::size_t points_per_frame = 0;
  double voxel_visits_per_frame = 0.0;  // voxel steps of all rays (ours only)
  double rays_per_frame = 0.0;          // rays cast (ours only; fewer than points when bundled)
  // Ours only: wall ms a frame by stage (StereoIntegrationStats).
  double conversion_ms = 0.0, bundling_ms = 0.0, walk_ms = 0.0, write_ms = 0.0;
};

// P(O) of never-observed neighbours in Eq. 1 (--unknown_neighbour_occupancy); the core's default.
double g_unknown_neighbour_occupancy = VisibilityStereoConfig().unknown_neighbour_occupancy;
// The named parameter set (--parameter_set), the mappers' default (measured) by default.
StereoParameterSet g_parameter_set = StereoParameterSet::kMeasured;
// --bundle_rays (one ray per end voxel, VisibilityStereoConfig::bundle_rays) and --method
// (octomap: our OctoMap mode, whose bundled rays are liboctomap's discretize = true); the core's
// defaults.
bool g_bundle_rays = VisibilityStereoConfig().bundle_rays;
StereoIntegrationMethod g_method = VisibilityStereoConfig().method;
// --measured_grid_fraction (MeasuredSurfaceConfig::grid_footprint_fraction).
double g_grid_fraction = MeasuredSurfaceConfig().grid_footprint_fraction;
// --measured_grid_max_px (MeasuredSurfaceConfig::grid_max_step_px).
int g_grid_max_px = MeasuredSurfaceConfig().grid_max_step_px;
// --measured_fuse_known (VisibilityStereoConfig::measured_fuse_known).
bool g_fuse_known = VisibilityStereoConfig().measured_fuse_known;

VisibilityStereoConfig stereoConfig(double sigma_px, InputResolution input) {
  VisibilityStereoConfig config = visibilityStereoConfigFor(g_parameter_set);
  config.unknown_neighbour_occupancy = g_unknown_neighbour_occupancy;
  config.bundle_rays = g_bundle_rays;
  config.method = g_method;
  config.measured_surface.grid_footprint_fraction = g_grid_fraction;
  config.measured_surface.grid_max_step_px = g_grid_max_px;
  config.measured_fuse_known = g_fuse_known;
  config.disparity.disparity_sigma_px = sigma_px;
  config.disparity.input_resolution = input;
  return config;
}

MapRun runOurs(const StereoView& view, const std::vector<Eigen::Isometry3d>& poses,
               const VisibilityStereoIntegrator& integrator, VoxelMap* map) {
  MapRun run;
  std::size_t visits = 0, hits = 0, rays = 0;
  const double cpu_start = processCpuMilliseconds();
  const auto start = Clock::now();
  for (const Eigen::Isometry3d& pose : poses) {
    const StereoIntegrationStats stats = integrator.integrate(view.view(), view.camera, pose, map);
    visits += stats.voxel_visits;
    hits += stats.cache_hits;
    rays += stats.rays;
    run.points_per_frame = stats.points - stats.skipped_points;
    run.conversion_ms += 1e3 * stats.conversion_seconds / poses.size();
    run.bundling_ms += 1e3 * stats.bundling_seconds / poses.size();
    run.walk_ms += 1e3 * stats.walk_seconds / poses.size();
    run.write_ms += 1e3 * stats.write_seconds / poses.size();
  }
  run.wall_ms_per_frame = millisecondsSince(start) / poses.size();
  run.cpu_ms_per_frame = (processCpuMilliseconds() - cpu_start) / poses.size();
  run.memory_bytes = map->memoryBytes();
  run.cache_hit_rate = visits == 0 ? 0.0 : static_cast<double>(hits) / visits;
  run.voxel_visits_per_frame = static_cast<double>(visits) / poses.size();
  run.rays_per_frame = static_cast<double>(rays) / poses.size();
  return run;
}

// The points our integrator casts rays to (same conversion, same sub-sampling), per frame.
std::vector<octomap::Pointcloud> octomapClouds(const StereoView& view,
                                               const std::vector<Eigen::Isometry3d>& poses,
                                               const VisibilityStereoIntegrator& integrator) {
  std::vector<octomap::Pointcloud> clouds;
  for (const Eigen::Isometry3d& pose : poses) {
    std::vector<Eigen::Vector3f> points;
    std::vector<float> sigmas;
    std::size_t pixels = 0;
    integrator.disparityToMapPoints(view.view(), view.camera, pose, &points, &sigmas, &pixels);
    octomap::Pointcloud cloud;
    cloud.reserve(points.size());
    for (const Eigen::Vector3f& p : points) cloud.push_back(p.x(), p.y(), p.z());
    clouds.push_back(std::move(cloud));
  }
  return clouds;
}

MapRun runOctomap(const std::vector<octomap::Pointcloud>& clouds,
                  const std::vector<Eigen::Isometry3d>& poses, bool discretize,
                  octomap::OcTree* tree) {
  MapRun run;
  // liboctomap inserts on this thread alone (see benchmark.cpp's runOctomap).
  const double cpu_start = bench::threadCpuMilliseconds();
  const auto start = Clock::now();
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    const Eigen::Vector3d o = poses[i].translation();
    tree->insertPointCloud(clouds[i], octomap::point3d(o.x(), o.y(), o.z()), -1.0, false,
                           discretize);
  }
  run.wall_ms_per_frame = millisecondsSince(start) / clouds.size();
  run.cpu_ms_per_frame = (bench::threadCpuMilliseconds() - cpu_start) / clouds.size();
  run.memory_bytes = tree->memoryUsage();
  run.points_per_frame = clouds.empty() ? 0 : clouds.front().size();
  return run;
}

// The floor of any method that walks every voxel of every ray: the voxel traversal alone
// (RayTraversal from the sensor to each point, nothing else), on one thread, process CPU time.
struct WalkOnly {
  double cpu_ms_per_frame = 0.0;
  double steps_per_frame = 0.0;
  // The same for one ray per end voxel, to its farthest point (the default's bundled rays): the
  // floor of a method that walks them, as Eq. 3 does.
  double bundled_cpu_ms_per_frame = 0.0;
  double bundled_steps_per_frame = 0.0;
};

// The farthest point of each end voxel's points, by the voxel's first point.
std::vector<Eigen::Vector3d> farthestOfEndVoxels(const octomap::Pointcloud& cloud,
                                                 const Eigen::Vector3d& origin, double resolution) {
  std::vector<Eigen::Vector3d> farthest;
  SpatialKeyMap<std::size_t> of_voxel;
  for (const octomap::point3d& p : cloud) {
    const Eigen::Vector3d point(p.x(), p.y(), p.z());
    const auto [it, inserted] =
        of_voxel.try_emplace(packKey(voxelIndexOf(point, resolution)), farthest.size());
    if (inserted) {
      farthest.push_back(point);
    } else if ((point - origin).squaredNorm() > (farthest[it->second] - origin).squaredNorm()) {
      farthest[it->second] = point;
    }
  }
  return farthest;
}

WalkOnly timeWalkOnly(const std::vector<octomap::Pointcloud>& clouds,
                      const std::vector<Eigen::Isometry3d>& poses, double resolution) {
  std::size_t steps = 0;  // counted by the walk, so the walk cannot be optimised away
  const double cpu_start = processCpuMilliseconds();
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    const Eigen::Vector3d origin = poses[i].translation();
    for (const octomap::point3d& p : clouds[i]) {
      RayTraversal ray(origin, Eigen::Vector3d(p.x(), p.y(), p.z()), resolution);
      for (++steps; ray.beforeEnd(); ++steps) ray.stepTowardsEnd();
    }
  }
  WalkOnly walk;
  walk.cpu_ms_per_frame = (processCpuMilliseconds() - cpu_start) / clouds.size();
  walk.steps_per_frame = static_cast<double>(steps) / clouds.size();
  std::vector<std::vector<Eigen::Vector3d>> ends;
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    ends.push_back(farthestOfEndVoxels(clouds[i], poses[i].translation(), resolution));
  }
  steps = 0;
  const double bundled_start = processCpuMilliseconds();
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    for (const Eigen::Vector3d& end : ends[i]) {
      RayTraversal ray(poses[i].translation(), end, resolution);
      for (++steps; ray.beforeEnd(); ++steps) ray.stepTowardsEnd();
    }
  }
  walk.bundled_cpu_ms_per_frame = (processCpuMilliseconds() - bundled_start) / clouds.size();
  walk.bundled_steps_per_frame = static_cast<double>(steps) / clouds.size();
  return walk;
}

// ---------------------------------------------------------------------------------------------
// Map quality: occupied voxels on and off the true surface.

// The voxels holding the ground-truth points of the view at the identity pose, each with its
// 26 neighbours (one voxel of slack for discretisation).
SpatialKeySet trueSurface(const StereoView& truth, const VoxelMap& grid) {
  DisparityConversionConfig config;
  const StereoPoints points = disparityToPoints(truth.view(), truth.camera, config);
  SpatialKeySet surface;
  for (const Eigen::Vector3f& p : points.points) {
    const VoxelIndex center = grid.indexOf(p.cast<double>());
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx)
          surface.insert(packKey(VoxelIndex(center + VoxelIndex(dx, dy, dz))));
      }
    }
  }
  return surface;
}

// Occupied voxel centres of the tree at its finest resolution (pruned leaves expanded).
std::vector<Eigen::Vector3d> occupiedCenters(const octomap::OcTree& tree) {
  std::vector<Eigen::Vector3d> centers;
  const double resolution = tree.getResolution();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const int cells = static_cast<int>(std::lround(it.getSize() / resolution));
    const Eigen::Vector3d corner = Eigen::Vector3d(it.getX(), it.getY(), it.getZ()) -
                                   Eigen::Vector3d::Constant(0.5 * it.getSize());
    for (int z = 0; z < cells; ++z) {
      for (int y = 0; y < cells; ++y) {
        for (int x = 0; x < cells; ++x) {
          centers.push_back(corner + resolution * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5));
        }
      }
    }
  }
  return centers;
}

std::vector<Eigen::Vector3d> occupiedCenters(const VoxelMap& map) {
  std::vector<Eigen::Vector3d> centers;
  map.forEachOccupiedVoxel(
      [&](const VoxelIndex& index, float) { centers.push_back(map.centerOf(index)); });
  return centers;
}

// What the map holds after the run, to see where its memory goes, and a checksum of its
// contents (FNV-1a over the known voxels' keys and log-odds bits, in key order) so that two
// builds can be shown to produce the same map bit for bit.
struct MapContents {
  std::size_t blocks = 0;
  std::size_t known_voxels = 0;
  std::size_t occupied_voxels = 0;
  std::size_t all_free_blocks = 0;  // blocks whose known voxels are all free
  std::uint64_t checksum = 0;
  VoxelMap::StorageStats storage;  // dense and sparse blocks, their bytes, table, change log
  const char* block_storage = "";  // the map's VoxelMapConfig::block_storage
};

MapContents mapContents(const VoxelMap& map) {
  MapContents contents;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> voxels;
  map.forEachBlock([&](const BlockIndex&, const VoxelBlock& block) {
    ++contents.blocks;
    bool any_occupied = false;
    for (float value : block.log_odds) {
      any_occupied = any_occupied ||
                     (VoxelBlock::isKnown(value) && map.classify(value) == Occupancy::kOccupied);
    }
    contents.all_free_blocks += any_occupied ? 0 : 1;
  });
  map.forEachKnownVoxel([&](const VoxelIndex& index, float value) {
    std::uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    voxels.emplace_back(packKey(index), bits);
    ++contents.known_voxels;
    contents.occupied_voxels += map.classify(value) == Occupancy::kOccupied ? 1 : 0;
  });
  std::sort(voxels.begin(), voxels.end());
  std::uint64_t hash = 1469598103934665603ull;
  const auto mix = [&hash](std::uint64_t word) {
    for (int byte = 0; byte < 8; ++byte) {
      hash = (hash ^ ((word >> (8 * byte)) & 0xff)) * 1099511628211ull;
    }
  };
  for (const auto& [key, bits] : voxels) {
    mix(key);
    mix(bits);
  }
  contents.checksum = hash;
  contents.storage = map.storageStats();
  contents.block_storage = map.config().block_storage == BlockStorage::kHybrid ? "hybrid" : "dense";
  return contents;
}

// Coverage: the fraction of the voxels holding ground-truth points of the view that have an
// occupied voxel within one voxel (the slack of trueSurface). Counts each surface voxel once, so a
// surface mapped thicker does not count more.
double surfaceCoverage(const StereoView& truth, const std::vector<Eigen::Vector3d>& occupied,
                       const VoxelMap& grid) {
  SpatialKeySet near_occupied;
  for (const Eigen::Vector3d& c : occupied) {
    const VoxelIndex center = grid.indexOf(c);
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx)
          near_occupied.insert(packKey(VoxelIndex(center + VoxelIndex(dx, dy, dz))));
      }
    }
  }
  SpatialKeySet truth_voxels;
  const StereoPoints points =
      disparityToPoints(truth.view(), truth.camera, DisparityConversionConfig{});
  for (const Eigen::Vector3f& p : points.points) {
    truth_voxels.insert(packKey(grid.indexOf(p.cast<double>())));
  }
  std::size_t covered = 0;
  for (const std::uint64_t key : truth_voxels) covered += near_occupied.count(key);
  return truth_voxels.empty() ? 0.0 : static_cast<double>(covered) / truth_voxels.size();
}

std::size_t countOffSurface(const std::vector<Eigen::Vector3d>& centers,
                            const SpatialKeySet& surface, const VoxelMap& grid) {
  std::size_t off = 0;
  for (const Eigen::Vector3d& c : centers) off += surface.count(packKey(grid.indexOf(c))) ? 0 : 1;
  return off;
}

// ---------------------------------------------------------------------------------------------
// Pictures: occupied voxels seen from the camera (front) and from above (top), coloured by depth.

cv::Mat drawViews(const std::vector<Eigen::Vector3d>& centers, double resolution,
                  const StereoCamera& camera, int width, int height, double z_min, double z_max,
                  const std::string& title) {
  const double scale = 0.5;  // picture px per image px (front view)
  const int front_w = static_cast<int>(width * scale), front_h = static_cast<int>(height * scale);
  const int top_h = front_h;
  cv::Mat canvas(front_h + top_h + 24, front_w, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::Mat front_depth(front_h, front_w, CV_64F, cv::Scalar(std::numeric_limits<double>::max()));
  std::vector<const Eigen::Vector3d*> order;
  for (const Eigen::Vector3d& c : centers) order.push_back(&c);
  std::sort(order.begin(), order.end(),
            [](const Eigen::Vector3d* a, const Eigen::Vector3d* b) { return a->z() > b->z(); });
  const auto colorOf = [&](double z) {
    const double t = std::clamp((z - z_min) / (z_max - z_min), 0.0, 1.0);
    cv::Mat value(1, 1, CV_8UC1, cv::Scalar(static_cast<int>(255 * t)));
    cv::Mat color;
    cv::applyColorMap(value, color, cv::COLORMAP_TURBO);
    const cv::Vec3b bgr = color.at<cv::Vec3b>(0, 0);
    return cv::Scalar(bgr[0], bgr[1], bgr[2]);
  };
  cv::Mat front = canvas(cv::Rect(0, 24, front_w, front_h));
  cv::Mat top = canvas(cv::Rect(0, 24 + front_h, front_w, top_h));
  cv::rectangle(top, cv::Rect(0, 0, front_w, top_h), cv::Scalar(235, 235, 235), cv::FILLED);
  // Top view: x across as in the front view (the field of view at z_max), depth from z_min
  // (bottom) to z_max (top).
  const double x_lo = -camera.cx / camera.fx * z_max;
  const double x_hi = (width - 1 - camera.cx) / camera.fx * z_max;
  const double x_scale = front_w / (x_hi - x_lo);
  const double z_scale = top_h / (z_max - z_min + 0.5);
  for (const Eigen::Vector3d* c : order) {  // far to near: near voxels drawn last, on top
    if (!(c->z() > 0.0)) continue;
    const cv::Scalar color = colorOf(c->z());
    const double u = (camera.fx * c->x() / c->z() + camera.cx) * scale;
    const double v = (camera.fy * c->y() / c->z() + camera.cy) * scale;
    const double half = 0.5 * resolution * camera.fx / c->z() * scale;
    cv::rectangle(front, cv::Point2d(u - half, v - half), cv::Point2d(u + half, v + half), color,
                  cv::FILLED);
    const double tx = (c->x() - x_lo) * x_scale;
    const double ty = top_h - (c->z() - z_min + 0.25) * z_scale;
    const double th = std::max(1.0, 0.5 * resolution * x_scale);
    cv::rectangle(top, cv::Point2d(tx - th, ty - th), cv::Point2d(tx + th, ty + th), color,
                  cv::FILLED);
  }
  cv::putText(canvas, title, cv::Point(4, 17), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0),
              1, cv::LINE_AA);
  cv::putText(top, "top view (depth up)", cv::Point(4, 14), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  return canvas;
}

// ---------------------------------------------------------------------------------------------
// The workload.

struct Options {
  std::vector<double> resolutions;
  std::vector<InputResolution> inputs;
  std::vector<std::string> sources;
  int frames = 5;
  int warmup = 0;  // untimed frames before the timed ones
  int repetitions = 3;
  double jitter_m = 0.0;
  double jitter_deg = 0.0;
  double sigma_px = 0.5;
  SgbmSettings sgbm;
  std::string picture;  // output file prefix; empty: none
  std::string picture_scene;
  double picture_resolution = 0.05;
  int threads = 1;
  bool cpu_clock = true;  // --clock cpu (process CPU time) or wall
};

struct CaseResult {
  std::string scene, source;
  double resolution = 0.0;
  InputResolution input = InputResolution::kFull;
  MapRun ours, plain, discretized;
  std::size_t ours_occupied = 0, octomap_occupied = 0;
  std::size_t ours_off_surface = 0, octomap_off_surface = 0;
  double ours_coverage = 0.0, octomap_coverage = 0.0;  // surfaceCoverage
  MapContents contents;
  std::size_t octomap_nodes = 0, octomap_leaves = 0;
  WalkOnly walk_only;
  // Ours / liboctomap plain per timed frame, both on the same frame back to back (--clock).
  std::vector<double> paired_ratios;
};

// Frames run one at a time, as one run of them all: times and counts averaged per frame, the map's
// memory and the points of the last.
MapRun perFrameMean(const std::vector<MapRun>& frames) {
  MapRun mean;
  double visits = 0.0, hits = 0.0;
  for (const MapRun& f : frames) {
    mean.wall_ms_per_frame += f.wall_ms_per_frame / frames.size();
    mean.cpu_ms_per_frame += f.cpu_ms_per_frame / frames.size();
    mean.voxel_visits_per_frame += f.voxel_visits_per_frame / frames.size();
    mean.rays_per_frame += f.rays_per_frame / frames.size();
    mean.conversion_ms += f.conversion_ms / frames.size();
    mean.bundling_ms += f.bundling_ms / frames.size();
    mean.walk_ms += f.walk_ms / frames.size();
    mean.write_ms += f.write_ms / frames.size();
    visits += f.voxel_visits_per_frame;
    hits += f.cache_hit_rate * f.voxel_visits_per_frame;
  }
  if (!frames.empty()) {
    mean.memory_bytes = frames.back().memory_bytes;
    mean.points_per_frame = frames.back().points_per_frame;
  }
  mean.cache_hit_rate = visits > 0 ? hits / visits : 0.0;
  return mean;
}

CaseResult runCase(const StereoView& view, const StereoView& truth, double resolution,
                   InputResolution input, const Options& options) {
  const VisibilityStereoIntegrator integrator(stereoConfig(options.sigma_px, input));
  const std::vector<Eigen::Isometry3d> poses =
      framePoses(options.frames, options.jitter_m, options.jitter_deg);
  const std::vector<octomap::Pointcloud> clouds = octomapClouds(view, poses, integrator);
  VoxelMapConfig map_config;
  map_config.resolution = resolution;
  map_config.block_storage = BlockStorage::kHybrid;  // as config/disparity_mapper.yaml
  CaseResult result;
  result.scene = view.scene;
  result.source = view.source;
  result.resolution = resolution;
  result.input = input;
  std::vector<double> ours_ms, plain_ms, discretized_ms;
  std::vector<double> wall_ms[3], cpu_ms[3];
  for (int r = 0; r < options.repetitions; ++r) {
    // Interleaved, so that the load of a shared machine falls on all three alike.
    omp_set_num_threads(options.threads);  // insertPointCloud resets it
    VoxelMap map(map_config);
    octomap::OcTree plain_tree = bench::makeOctomapTree(resolution);
    octomap::OcTree discretized_tree = bench::makeOctomapTree(resolution);
    // Untimed frames first: the visibility method maps unknown space a few voxels deeper per
    // frame (the paper's Fig. 5a), so its cost per frame grows until the view is mapped.
    for (int w = 0; w < options.warmup; ++w) {
      const std::vector<Eigen::Isometry3d> one{poses[w % poses.size()]};
      const std::vector<octomap::Pointcloud> cloud{clouds[w % clouds.size()]};
      runOurs(view, one, integrator, &map);
      runOctomap(cloud, one, false, &plain_tree);
      runOctomap(cloud, one, true, &discretized_tree);
      omp_set_num_threads(options.threads);
    }
    // Frame by frame, ours then liboctomap's two modes on the same frame: each frame's ratio
    // comes from runs milliseconds apart (a shared machine's speed drifts by tens of percent
    // within a run).
    std::vector<MapRun> ours_frames, plain_frames, discretized_frames;
    for (std::size_t f = 0; f < poses.size(); ++f) {
      const std::vector<Eigen::Isometry3d> one{poses[f]};
      const std::vector<octomap::Pointcloud> cloud{clouds[f]};
      ours_frames.push_back(runOurs(view, one, integrator, &map));
      plain_frames.push_back(runOctomap(cloud, one, false, &plain_tree));
      discretized_frames.push_back(runOctomap(cloud, one, true, &discretized_tree));
      omp_set_num_threads(options.threads);
      const auto ms = [&](const MapRun& run) {
        return options.cpu_clock ? run.cpu_ms_per_frame : run.wall_ms_per_frame;
      };
      result.paired_ratios.push_back(ms(ours_frames.back()) / ms(plain_frames.back()));
    }
    result.ours = perFrameMean(ours_frames);
    result.plain = perFrameMean(plain_frames);
    result.discretized = perFrameMean(discretized_frames);
    for (MapRun* run : {&result.ours, &result.plain, &result.discretized}) {
      run->ms_per_frame = options.cpu_clock ? run->cpu_ms_per_frame : run->wall_ms_per_frame;
      const int peer = run == &result.ours ? 0 : run == &result.plain ? 1 : 2;
      wall_ms[peer].push_back(run->wall_ms_per_frame);
      cpu_ms[peer].push_back(run->cpu_ms_per_frame);
    }
    ours_ms.push_back(result.ours.ms_per_frame);
    plain_ms.push_back(result.plain.ms_per_frame);
    discretized_ms.push_back(result.discretized.ms_per_frame);
    if (r + 1 == options.repetitions) {
      const SpatialKeySet surface = trueSurface(truth, map);
      const std::vector<Eigen::Vector3d> ours_occupied = occupiedCenters(map);
      const std::vector<Eigen::Vector3d> octomap_occupied = occupiedCenters(plain_tree);
      result.ours_occupied = ours_occupied.size();
      result.octomap_occupied = octomap_occupied.size();
      result.ours_off_surface = countOffSurface(ours_occupied, surface, map);
      result.octomap_off_surface = countOffSurface(octomap_occupied, surface, map);
      result.ours_coverage = surfaceCoverage(truth, ours_occupied, map);
      result.octomap_coverage = surfaceCoverage(truth, octomap_occupied, map);
      result.contents = mapContents(map);
      result.octomap_nodes = plain_tree.size();
      result.octomap_leaves = plain_tree.getNumLeafNodes();
      result.walk_only = timeWalkOnly(clouds, poses, resolution);
    }
  }
  result.ours.ms_per_frame = bench::median(ours_ms);
  result.plain.ms_per_frame = bench::median(plain_ms);
  result.discretized.ms_per_frame = bench::median(discretized_ms);
  result.ours.wall_ms_per_frame = bench::median(wall_ms[0]);
  result.plain.wall_ms_per_frame = bench::median(wall_ms[1]);
  result.discretized.wall_ms_per_frame = bench::median(wall_ms[2]);
  result.ours.cpu_ms_per_frame = bench::median(cpu_ms[0]);
  result.plain.cpu_ms_per_frame = bench::median(cpu_ms[1]);
  result.discretized.cpu_ms_per_frame = bench::median(cpu_ms[2]);
  return result;
}

void printCase(const char* prefix, const CaseResult& c) {
  std::printf(
      "%sscene=%s source=%s resolution=%g input=%s points=%zu ms_per_frame=%.2f "
      "octomap_ms_per_frame=%.2f octomap_discretize_ms_per_frame=%.2f time_ratio=%.3f "
      "time_ratio_discretize=%.3f memory_kb=%.0f octomap_memory_kb=%.0f memory_ratio=%.3f "
      "cache_hit_rate=%.3f occupied=%zu off_surface=%zu octomap_occupied=%zu "
      "octomap_off_surface=%zu coverage=%.3f octomap_coverage=%.3f wall_ms_per_frame=%.2f "
      "octomap_wall_ms_per_frame=%.2f paired_time_ratio=%.3f\n",
      prefix, c.scene.c_str(), c.source.c_str(), c.resolution, toString(c.input).c_str(),
      c.ours.points_per_frame, c.ours.ms_per_frame, c.plain.ms_per_frame,
      c.discretized.ms_per_frame, c.ours.ms_per_frame / c.plain.ms_per_frame,
      c.ours.ms_per_frame / c.discretized.ms_per_frame, c.ours.memory_bytes / 1024.0,
      c.plain.memory_bytes / 1024.0,
      static_cast<double>(c.ours.memory_bytes) / c.plain.memory_bytes, c.ours.cache_hit_rate,
      c.ours_occupied, c.ours_off_surface, c.octomap_occupied, c.octomap_off_surface,
      c.ours_coverage, c.octomap_coverage, c.ours.wall_ms_per_frame, c.plain.wall_ms_per_frame,
      bench::median(c.paired_ratios));
  // Where the memory goes: dense blocks against the octree's (pruned) nodes.
  const MapContents& m = c.contents;
  // The blocks alone, without the hash table and VoxelMap's change log (which memoryBytes()
  // includes and which grows with every frame's written blocks, up to its cap): the part
  // comparable with OcTree::memoryUsage(), which counts the tree's nodes only.
  const double block_storage = static_cast<double>(m.storage.block_bytes);
  std::printf(
      "%smap scene=%s source=%s resolution=%g input=%s blocks=%zu block_bytes=%zu "
      "known_voxels=%zu known_per_block=%.1f occupied_voxels=%zu all_free_blocks=%zu "
      "octomap_nodes=%zu octomap_leaves=%zu block_storage=%s dense_blocks=%zu sparse_blocks=%zu "
      "sparse_bricks=%zu block_storage_kb=%.1f block_storage_ratio=%.3f table_kb=%.1f "
      "change_log_kb=%.1f "
      "voxel_visits_per_frame=%.0f rays_per_frame=%.0f walk_only_cpu_ms_per_frame=%.2f "
      "walk_only_steps_per_frame=%.0f "
      "checksum=%016llx\n",
      prefix, c.scene.c_str(), c.source.c_str(), c.resolution, toString(c.input).c_str(), m.blocks,
      sizeof(VoxelBlock), m.known_voxels,
      m.blocks == 0 ? 0.0 : static_cast<double>(m.known_voxels) / m.blocks, m.occupied_voxels,
      m.all_free_blocks, c.octomap_nodes, c.octomap_leaves, m.block_storage, m.storage.dense_blocks,
      m.storage.sparse_blocks, m.storage.sparse_bricks, block_storage / 1024.0,
      block_storage / c.plain.memory_bytes, m.storage.table_bytes / 1024.0,
      m.storage.change_log_bytes / 1024.0, c.ours.voxel_visits_per_frame, c.ours.rays_per_frame,
      c.walk_only.cpu_ms_per_frame, c.walk_only.steps_per_frame,
      static_cast<unsigned long long>(m.checksum));
  // Per CPU beside wall, and where our frame's wall time goes.
  const MapRun& ours = c.ours;
  std::printf("%stime scene=%s source=%s resolution=%g input=%s", prefix, c.scene.c_str(),
              c.source.c_str(), c.resolution, toString(c.input).c_str());
  std::printf(" cpu_ms_per_frame=%.2f octomap_cpu_ms_per_frame=%.2f", ours.cpu_ms_per_frame,
              c.plain.cpu_ms_per_frame);
  std::printf(" octomap_discretize_cpu_ms_per_frame=%.2f cpu_ratio=%.3f cpu_ratio_discretize=%.3f",
              c.discretized.cpu_ms_per_frame, ours.cpu_ms_per_frame / c.plain.cpu_ms_per_frame,
              ours.cpu_ms_per_frame / c.discretized.cpu_ms_per_frame);
  std::printf(" wall_ms_per_frame=%.2f octomap_discretize_wall_ms_per_frame=%.2f",
              ours.wall_ms_per_frame, c.discretized.wall_ms_per_frame);
  std::printf(" wall_ratio_discretize=%.3f",
              ours.wall_ms_per_frame / c.discretized.wall_ms_per_frame);
  std::printf(" stage_ms conversion=%.2f bundling=%.2f walks=%.2f writing=%.2f", ours.conversion_ms,
              ours.bundling_ms, ours.walk_ms, ours.write_ms);
  std::printf(" bundled_walk_only_cpu_ms_per_frame=%.2f bundled_walk_only_steps_per_frame=%.0f\n",
              c.walk_only.bundled_cpu_ms_per_frame, c.walk_only.bundled_steps_per_frame);
  std::fflush(stdout);
}

StereoView groundTruthView(const MiddleburyFolder& folder, const std::string& scene) {
  const MiddleburyFrame frame = folder.frame(0);
  StereoView view;
  view.scene = scene;
  view.source = "gt";
  view.width = frame.width;
  view.height = frame.height;
  view.disparity = frame.disparity;
  view.camera = folder.camera();
  return view;
}

StereoView sgbmView(const MiddleburyFolder& folder, const std::string& scene,
                    const SgbmSettings& settings) {
  const std::string left = folder.leftImagePath(0), right = folder.rightImagePath(0);
  if (left.empty() || right.empty()) throw std::runtime_error(scene + ": no im0/im1 for SGBM");
  StereoView view;
  view.scene = scene;
  view.source = "sgbm";
  view.camera = folder.camera();
  SgbmSettings scene_settings = settings;
  // Cover the scene's search range (calib.txt's ndisp) from 0, in steps of 16 as SGBM wants.
  const int ndisp = folder.calibration().ndisp;
  if (ndisp > 0) scene_settings.num_disparities = 16 * ((ndisp + 15) / 16);
  view.disparity =
      sgbmDisparity(left, right, scene_settings, static_cast<float>(folder.calibration().doffs),
                    &view.width, &view.height);
  return view;
}

void drawPicture(const StereoView& view, const StereoView& truth, const Options& options) {
  const VisibilityStereoIntegrator integrator(
      stereoConfig(options.sigma_px, InputResolution::kFull));
  const std::vector<Eigen::Isometry3d> poses =
      framePoses(options.frames + options.warmup, 0.0, 0.0);
  VoxelMapConfig map_config;
  map_config.resolution = options.picture_resolution;
  map_config.block_storage = BlockStorage::kHybrid;
  VoxelMap map(map_config);
  runOurs(view, poses, integrator, &map);
  octomap::OcTree tree = bench::makeOctomapTree(options.picture_resolution);
  runOctomap(octomapClouds(view, poses, integrator), poses, false, &tree);
  // Depth range of the true surface, for the colour scale.
  const StereoPoints points = disparityToPoints(truth.view(), truth.camera, {});
  std::vector<double> depths;
  for (const Eigen::Vector3f& p : points.points) depths.push_back(p.z());
  std::sort(depths.begin(), depths.end());
  const double z_min = depths[depths.size() / 100], z_max = depths[depths.size() * 99 / 100];
  const std::vector<Eigen::Vector3d> ours = occupiedCenters(map);
  const std::vector<Eigen::Vector3d> octomap = occupiedCenters(tree);
  char ours_title[160], octomap_title[160];
  std::snprintf(ours_title, sizeof(ours_title), "visibility method: %zu occupied, %.0f KB",
                ours.size(), map.memoryBytes() / 1024.0);
  std::snprintf(octomap_title, sizeof(octomap_title), "liboctomap: %zu occupied, %.0f KB",
                octomap.size(), tree.memoryUsage() / 1024.0);
  cv::Mat left_panel = drawViews(ours, options.picture_resolution, view.camera, view.width,
                                 view.height, z_min, z_max, ours_title);
  cv::Mat right_panel = drawViews(octomap, options.picture_resolution, view.camera, view.width,
                                  view.height, z_min, z_max, octomap_title);
  cv::Mat picture;
  cv::hconcat(
      std::vector<cv::Mat>{left_panel, cv::Mat(left_panel.rows, 6, CV_8UC3, cv::Scalar(90, 90, 90)),
                           right_panel},
      picture);
  const std::string path = options.picture + "_" + view.scene + "_" + view.source + ".png";
  if (!cv::imwrite(path, picture, {cv::IMWRITE_PNG_COMPRESSION, 9})) {
    throw std::runtime_error("cannot write " + path);
  }
  std::printf("# picture %s: %s, %g m, %zu frames standing still, depth colours %.2f-%.2f m\n",
              path.c_str(), view.source.c_str(), options.picture_resolution, poses.size(), z_min,
              z_max);
}

// The rtabmap pairs: left/<id>.jpg, right/<id>.jpg, stereo_left.yaml, stereo_right.yaml.
void runRtabmap(const std::string& folder, const Options& options) {
  cv::FileStorage left_yaml((fs::path(folder) / "stereo_left.yaml").string(),
                            cv::FileStorage::READ);
  cv::FileStorage right_yaml((fs::path(folder) / "stereo_right.yaml").string(),
                             cv::FileStorage::READ);
  if (!left_yaml.isOpened() || !right_yaml.isOpened()) {
    throw std::runtime_error(folder + ": cannot read stereo_left.yaml / stereo_right.yaml");
  }
  // camera_info-style YAML: rows, cols and a flat "data" list (no OpenCV matrix type tag).
  std::vector<double> K, P_right;
  left_yaml["camera_matrix"]["data"] >> K;
  right_yaml["projection_matrix"]["data"] >> P_right;
  if (K.size() != 9 || P_right.size() != 12) {
    throw std::runtime_error(folder + ": expected a 3x3 camera_matrix and a 3x4 projection_matrix");
  }
  StereoCamera camera;
  camera.fx = K[0];
  camera.fy = K[4];
  camera.cx = K[2];
  camera.cy = K[5];
  camera.baseline = -P_right[3] / P_right[0];  // Tx = -fx * B
  std::vector<std::string> ids;
  for (const fs::directory_entry& entry : fs::directory_iterator(fs::path(folder) / "left")) {
    if (entry.path().extension() == ".jpg") ids.push_back(entry.path().stem().string());
  }
  std::sort(ids.begin(), ids.end());
  std::printf("# rtabmap pairs: fx=%.2f B=%.4f m, StereoSGBM 96 disparities (depth from %.2f m)\n",
              camera.fx, camera.baseline, camera.fx * camera.baseline / 95.0);
  SgbmSettings settings = options.sgbm;
  settings.num_disparities = 96;
  for (const std::string& id : ids) {
    StereoView view;
    view.scene = "rtabmap_" + id;
    view.source = "sgbm";
    view.camera = camera;
    view.disparity = sgbmDisparity((fs::path(folder) / "left" / (id + ".jpg")).string(),
                                   (fs::path(folder) / "right" / (id + ".jpg")).string(), settings,
                                   0.0f, &view.width, &view.height);
    for (double resolution : options.resolutions) {
      for (InputResolution input : options.inputs) {
        // No ground truth: the matched view stands in for the surface (off_surface counts 0).
        printCase("rtabmap ", runCase(view, view, resolution, input, options));
      }
    }
  }
}

}  // namespace

int runDisparity(const CommandLine& args) {
  Options options;
  options.resolutions =
      bench::parsePositiveList<double>("resolution", args.value("resolution", "0.1,0.2"));
  for (const std::string& name : splitList("input", args.value("input", "full,half,quarter"))) {
    options.inputs.push_back(inputResolutionFromString(name));
  }
  options.sources = splitList("source", args.value("source", "gt,sgbm"));
  for (const std::string& source : options.sources) {
    if (source != "gt" && source != "sgbm") throw UsageError("--source takes gt and sgbm");
  }
  options.frames = args.intValue("frames", 5);
  options.repetitions = args.intValue("repetitions", 3);
  options.warmup = args.intValue("warmup", 0);
  if (options.warmup < 0) throw UsageError("--warmup must not be negative");
  options.jitter_m = args.doubleValue("jitter", 0.0);
  options.jitter_deg = args.doubleValue("jitter_deg", 0.0);
  options.sigma_px = args.doubleValue("sigma", 0.5);
  g_parameter_set = stereoParameterSetFromString(args.value("parameter_set", "measured"));
  g_grid_fraction = args.doubleValue("measured_grid_fraction", g_grid_fraction);
  g_grid_max_px = args.intValue("measured_grid_max_px", g_grid_max_px);
  g_fuse_known = args.intValue("measured_fuse_known", g_fuse_known) != 0;
  g_unknown_neighbour_occupancy =
      args.doubleValue("unknown_neighbour_occupancy", g_unknown_neighbour_occupancy);
  const std::string bundle = args.value("bundle_rays", g_bundle_rays ? "true" : "false");
  if (bundle != "true" && bundle != "false") throw UsageError("--bundle_rays takes true or false");
  g_bundle_rays = bundle == "true";
  g_method = stereoIntegrationMethodFromString(args.value("method", toString(g_method)));
  options.sgbm.block_size = args.intValue("block_size", 5);
  options.picture = args.value("picture", "");
  options.picture_scene = args.value("picture_scene", "Motorcycle");
  options.picture_resolution = args.doubleValue("picture_resolution", 0.05);
  // One thread by default: liboctomap's insertPointCloud runs on one (Debian's build).
  options.threads = args.intValue("threads", 1);
  const std::string clock = args.value("clock", "cpu");
  if (clock != "cpu" && clock != "wall") throw UsageError("--clock takes cpu or wall");
  options.cpu_clock = clock == "cpu";
  if (options.frames < 1 || options.repetitions < 1 || options.threads < 1) {
    throw UsageError("--frames, --repetitions and --threads must be at least 1");
  }
  if (options.sgbm.block_size < 1 || options.sgbm.block_size % 2 == 0) {
    throw UsageError("--block_size must be odd");
  }

  std::printf(
      "# disparity: %d timed frames per case after %d untimed (jitter %g m, %g deg), median of %d "
      "repetitions, "
      "sigma_d=%g px, unknown_neighbour_occupancy=%g, threads=%d (liboctomap: 1), SGBM block %d, "
      "clock=%s\n",
      options.frames, options.warmup, options.jitter_m, options.jitter_deg, options.repetitions,
      options.sigma_px, g_unknown_neighbour_occupancy, options.threads, options.sgbm.block_size,
      options.cpu_clock ? "cpu" : "wall");
  std::vector<CaseResult> results;
  for (const std::string& scene_path : findMiddleburyScenes(args.required("folder"))) {
    const MiddleburyFolder folder(scene_path);
    const std::string scene = fs::path(scene_path).filename().string();
    const StereoView truth = groundTruthView(folder, scene);
    for (const std::string& source : options.sources) {
      const StereoView view = source == "gt" ? truth : sgbmView(folder, scene, options.sgbm);
      if (source == "sgbm") {
        const MatchQuality quality = compareDisparity(view.disparity, truth.disparity);
        std::printf(
            "# %s sgbm: %.1f %% of the ground-truth pixels matched, bad2=%.1f %%, median "
            "error %.2f px\n",
            scene.c_str(), 100 * quality.valid_fraction, 100 * quality.bad2_fraction,
            quality.median_error);
      }
      if (!options.picture.empty() && scene == options.picture_scene) {
        drawPicture(view, truth, options);
      }
      for (double resolution : options.resolutions) {
        for (InputResolution input : options.inputs) {
          results.push_back(runCase(view, truth, resolution, input, options));
          printCase("# ", results.back());
        }
      }
    }
  }
  if (args.has("rtabmap")) runRtabmap(args.value("rtabmap"), options);

  // Summary: per source, resolution and input, over the scenes (total time and memory).
  for (const std::string& source : options.sources) {
    for (double resolution : options.resolutions) {
      for (InputResolution input : options.inputs) {
        double ours_ms = 0, plain_ms = 0, discretized_ms = 0, ours_mem = 0, octomap_mem = 0;
        std::vector<double> paired;
        int scenes = 0;
        for (const CaseResult& c : results) {
          if (c.source != source || c.resolution != resolution || c.input != input) continue;
          ours_ms += c.ours.ms_per_frame;
          plain_ms += c.plain.ms_per_frame;
          discretized_ms += c.discretized.ms_per_frame;
          ours_mem += c.ours.memory_bytes;
          octomap_mem += c.plain.memory_bytes;
          paired.insert(paired.end(), c.paired_ratios.begin(), c.paired_ratios.end());
          ++scenes;
        }
        if (scenes == 0) continue;
        std::printf(
            "disparity resolution=%g input=%s ms_per_frame=%.2f octomap_ms_per_frame=%.2f "
            "time_ratio=%.3f memory_ratio=%.3f source=%s scenes=%d "
            "octomap_discretize_ms_per_frame=%.2f time_ratio_discretize=%.3f threads=%d clock=%s "
            "warmup=%d bundle_rays=%s method=%s paired_time_ratio=%.3f\n",
            resolution, toString(input).c_str(), ours_ms / scenes, plain_ms / scenes,
            ours_ms / plain_ms, ours_mem / octomap_mem, source.c_str(), scenes,
            discretized_ms / scenes, ours_ms / discretized_ms, options.threads,
            options.cpu_clock ? "cpu" : "wall", options.warmup, g_bundle_rays ? "true" : "false",
            toString(g_method).c_str(), bench::median(paired));
      }
    }
  }
  return 0;
}

}  // namespace occupancy_fusion
