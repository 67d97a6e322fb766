// benchmark depth-accuracy: Pirker et al. Sec. 5.1. The BOX and SPHERES scenes seen by the
// paper's synthetic camera (400 x 400, f = 400, principal point (200, 200)) from the 181 views
// of its 4-degree sweep about the camera's x and y axes, mapped by the pyramid, Andert's scheme
// and the ideal model; scored against the scenes' analytic ground truth.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "occupancy_fusion/integrators/pyramid_depth_integrator.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/trajectory.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

using Clock = std::chrono::steady_clock;

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

struct View {
  Eigen::Isometry3d T_world_camera;
  sim::DepthImage image;
};

// `count` of the sweep's 181 poses, evenly spaced (all of them when count = 181), rendered.
std::vector<View> renderViews(const sim::Scene& scene, const sim::PinholeCamera& camera,
                              const Eigen::Vector3d& position, int count, double max_range) {
  const std::vector<Eigen::Isometry3d> sweep = sim::rotationSweep(position);
  std::vector<View> views;
  for (int i = 0; i < count; ++i) {
    const Eigen::Isometry3d& pose = sweep[static_cast<std::size_t>(i) * sweep.size() / count];
    views.push_back({pose, sim::renderDepth(scene, camera, pose, max_range)});
  }
  return views;
}

// A surface point is visible when some view's depth at its pixel matches the point's own.
bool isVisible(const Eigen::Vector3d& point, const std::vector<View>& views,
               const CameraIntrinsics& camera, double tolerance) {
  for (const View& view : views) {
    const Eigen::Vector3d p = view.T_world_camera.inverse() * point;
    if (p.z() <= 0.0) continue;
    const Eigen::Vector2d uv = camera.project(p);
    const int u = static_cast<int>(std::lround(uv.x()));
    const int v = static_cast<int>(std::lround(uv.y()));
    if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) continue;
    if (std::abs(view.image.at(u, v) - p.z()) < tolerance) return true;
  }
  return false;
}

struct Scores {
  std::size_t surface_points = 0;
  std::size_t surface_near_iso = 0;
  std::size_t surface_near_occupied = 0;
  std::size_t free_voxels = 0;
  std::size_t free_labelled_free = 0;
  double ms_per_view = 0.0;
};

// An occupied voxel (p > 0.5) lies in the 3 x 3 x 3 voxels around the point's voxel (the unit
// test's criterion).
bool occupiedNear(const VoxelMap& map, const Eigen::Vector3d& point) {
  const VoxelIndex center = map.indexOf(point);
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const std::optional<float> value = map.logOdds(center + VoxelIndex(dx, dy, dz));
        if (value && *value > 0.0f) return true;
      }
    }
  }
  return false;
}

// Distance from the point to the nearest place where the p = 0.5 iso-surface crosses the line
// between two axis-neighbouring voxel centres of opposite label (p > 0.5 against p <= 0.5,
// unknown read as p = 0.5), the crossing placed by linear interpolation of the log-odds
// (zero at p = 0.5) between the two centres. Centres within two voxels of the point's voxel
// are searched, so any crossing nearer than one voxel is found. Infinity when there is none.
double distanceToIsoSurface(const VoxelMap& map, const Eigen::Vector3d& point) {
  const VoxelIndex center = map.indexOf(point);
  const double resolution = map.resolution();
  constexpr int kReach = 2;
  double nearest = std::numeric_limits<double>::infinity();
  for (int dz = -kReach; dz <= kReach; ++dz) {
    for (int dy = -kReach; dy <= kReach; ++dy) {
      for (int dx = -kReach; dx <= kReach; ++dx) {
        const VoxelIndex a = center + VoxelIndex(dx, dy, dz);
        const float la = map.logOdds(a).value_or(0.0f);
        for (int axis = 0; axis < 3; ++axis) {
          const VoxelIndex b = a + VoxelIndex::Unit(axis);
          const float lb = map.logOdds(b).value_or(0.0f);
          if ((la > 0.0f) == (lb > 0.0f)) continue;
          // la and lb differ in sign (or one is 0), so la - lb != 0.
          const double fraction = static_cast<double>(la) / (static_cast<double>(la) - lb);
          const Eigen::Vector3d crossing =
              map.centerOf(a) + fraction * resolution * Eigen::Vector3d::Unit(axis);
          nearest = std::min(nearest, (crossing - point).norm());
        }
      }
    }
  }
  return nearest;
}

Scores score(const sim::Scene& scene, const VoxelMap& map, const std::vector<View>& views,
             const CameraIntrinsics& camera) {
  Scores scores;
  const double resolution = map.resolution();
  const std::vector<Eigen::Vector3d> samples = scene.sampleSurface(resolution);
  std::size_t visible = 0, near_iso = 0, near_occupied = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : visible, near_iso, near_occupied)
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!isVisible(samples[i], views, camera, 0.5 * resolution)) continue;
    ++visible;
    near_iso += distanceToIsoSurface(map, samples[i]) <= resolution;
    near_occupied += occupiedNear(map, samples[i]);
  }
  scores.surface_points = visible;
  scores.surface_near_iso = near_iso;
  scores.surface_near_occupied = near_occupied;
  // Ground-truth free: outside every solid and farther than one voxel diagonal from a surface
  // (a voxel nearer than that may hold surface).
  const double diagonal = std::sqrt(3.0) * resolution;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    const Eigen::Vector3d c = map.centerOf(index);
    if (scene.isOccupied(c) || scene.distanceToSurface(c) <= diagonal) return;
    ++scores.free_voxels;
    scores.free_labelled_free += map.classify(log_odds) == Occupancy::kFree;
  });
  return scores;
}

Scores mapAndScore(const sim::Scene& scene, const std::vector<View>& views,
                   const CameraIntrinsics& camera, const PyramidDepthConfig& config,
                   double resolution) {
  const PyramidDepthIntegrator integrator(config);
  VoxelMapConfig map_config;
  map_config.resolution = resolution;
  VoxelMap map(map_config);
  const auto start = Clock::now();
  for (const View& view : views) {
    const DepthImageView depth{camera.width, camera.height, view.image.depth.data()};
    integrator.integrate(depth, camera, view.T_world_camera, &map);
  }
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  Scores scores = score(scene, map, views, camera);
  scores.ms_per_view = ms / std::max<std::size_t>(views.size(), 1);
  return scores;
}

}  // namespace

int runDepthAccuracy(const CommandLine& args) {
  const double resolution = args.doubleValue("resolution", 0.02);
  const int view_count = args.intValue("views", 181);
  const double max_range = args.doubleValue("max_range", 15.0);
  if (!(resolution > 0.0) || view_count < 1 || view_count > 181) {
    throw UsageError("--resolution must be > 0 and --views in [1, 181]");
  }
  PyramidDepthConfig config;
  // Noise-free renderings: the paper's k = sigma shape at one voxel's width. Eq. 7 crosses
  // p = 0.5 in front of a surface at sqrt(2 ln((A + 0.2) / 0.2)) sigma, A = k / (sigma
  // sqrt(2 pi)): 1.48 sigma for k = sigma, so the iso-surface lies within a voxel of the true
  // surface only while sigma is at most about two thirds of a voxel. k defaults to sigma (the
  // same shape at any scale).
  config.sigma = args.doubleValue("sigma", 0.02);
  config.k = args.doubleValue("k", config.sigma);
  config.max_range = max_range;
  const CameraIntrinsics camera = sim::pirkerSyntheticCamera();
  std::printf(
      "# %d of the sweep's 181 views, %dx%d f=%g c=(%g, %g); resolution=%g k=%g sigma=%g "
      "threads=%d\n",
      view_count, camera.width, camera.height, camera.fx, camera.cx, camera.cy, resolution,
      config.k, config.sigma, omp_get_max_threads());
  std::fflush(stdout);
  for (const std::string& scene_name : splitList(args.value("scenes", "box,spheres"))) {
    if (scene_name != "box" && scene_name != "spheres") {
      throw UsageError("--scenes takes box and/or spheres, not '" + scene_name + "'");
    }
    const bool box = scene_name == "box";
    const sim::Scene scene = box ? sim::makeBoxScene() : sim::makeSpheresScene();
    const std::vector<View> views = renderViews(
        scene, camera, box ? sim::boxSceneCameraPosition() : sim::spheresSceneCameraPosition(),
        view_count, max_range);
    for (const std::string& method : splitList(args.value("methods", "pyramid,andert,ideal"))) {
      config.method = depthMethodFromString(method);
      const Scores s = mapAndScore(scene, views, camera, config, resolution);
      std::printf(
          "depth-accuracy scene=%s method=%s views=%d resolution=%g surface_points=%zu "
          "surface_within_one_voxel_of_iso=%.2f%% surface_within_one_voxel_of_occupied=%.2f%% "
          "free_voxels=%zu free_labelled_free=%.3f%% "
          "ms_per_view=%.0f\n",
          scene_name.c_str(), method.c_str(), view_count, resolution, s.surface_points,
          100.0 * s.surface_near_iso / std::max<std::size_t>(s.surface_points, 1),
          100.0 * s.surface_near_occupied / std::max<std::size_t>(s.surface_points, 1),
          s.free_voxels, 100.0 * s.free_labelled_free / std::max<std::size_t>(s.free_voxels, 1),
          s.ms_per_view);
      std::fflush(stdout);
    }
  }
  return 0;
}

}  // namespace occupancy_fusion
