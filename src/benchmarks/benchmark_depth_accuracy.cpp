// benchmark depth-accuracy: Pirker et al. Sec. 5.1. The BOX and SPHERES scenes seen by the
// paper's synthetic camera (400 x 400, f = 400, principal point (200, 200)) from the 181 views
// of its 4-degree sweep about the camera's x and y axes, mapped by the pyramid, Andert's scheme
// and the ideal model; scored against the scenes' analytic ground truth (eval/surface_accuracy).
// Diagnostics: scores after every N views, the observed point set taken from a different view
// subset than the one integrated, unclamped log-odds, and a per-point CSV.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "occupancy_fusion/benchmarks/benchmark_harness.h"
#include "occupancy_fusion/eval/surface_accuracy.h"
#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/trajectory.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

using bench::Clock;
using bench::millisecondsSince;

struct View {
  int sweep_index = 0;
  Eigen::Isometry3d T_world_camera;
  sim::DepthImage image;

  PosedDepthView posed() const {
    return {T_world_camera, {image.width, image.height, image.depth.data()}};
  }
};

// `count` of the sweep's 181 poses, evenly spaced (all of them when count = 181), rendered.
std::vector<View> renderViews(const sim::Scene& scene, const sim::PinholeCamera& camera,
                              const Eigen::Vector3d& position, int count, double max_range) {
  const std::vector<Eigen::Isometry3d> sweep = sim::rotationSweep(position);
  std::vector<View> views;
  for (int i = 0; i < count; ++i) {
    const int index = static_cast<int>(static_cast<std::size_t>(i) * sweep.size() / count);
    views.push_back(
        {index, sweep[index], sim::renderDepth(scene, camera, sweep[index], max_range)});
  }
  return views;
}

// A true surface point is observed when some view measured the surface there (its depth
// within half a voxel of the point's own).
std::vector<bool> observedBy(const std::vector<Eigen::Vector3d>& samples,
                             const std::vector<View>& views, const CameraIntrinsics& camera,
                             double tolerance) {
  std::vector<char> seen(samples.size(), 0);
  const long count = static_cast<long>(samples.size());
#pragma omp parallel for schedule(dynamic, 1024)
  for (long i = 0; i < count; ++i) {
    for (const View& view : views) {
      if (observesSurfacePoint(view.posed(), camera, samples[i], tolerance)) {
        seen[i] = 1;
        break;
      }
    }
  }
  return std::vector<bool>(seen.begin(), seen.end());
}

std::vector<Eigen::Vector3d> selected(const std::vector<Eigen::Vector3d>& samples,
                                      const std::vector<bool>& keep) {
  std::vector<Eigen::Vector3d> points;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (keep[i]) points.push_back(samples[i]);
  }
  return points;
}

// Ground-truth free: outside every solid and farther than one voxel diagonal from a surface
// (a voxel nearer than that may hold surface).
FreeSpaceScores scoreFree(const sim::Scene& scene, const VoxelMap& map) {
  const double diagonal = std::sqrt(3.0) * map.resolution();
  return scoreFreeSpace(map, [&](const Eigen::Vector3d& c) {
    return !scene.isOccupied(c) && scene.distanceToSurface(c) > diagonal;
  });
}

double percent(std::size_t part, std::size_t whole) {
  return 100.0 * static_cast<double>(part) / static_cast<double>(std::max<std::size_t>(whole, 1));
}

// Outward surface normal at a visible surface point: the gradient of the distance to the
// surface just in front of it (towards the camera), where it is outside every solid.
Eigen::Vector3d surfaceNormal(const sim::Scene& scene, const Eigen::Vector3d& point,
                              const Eigen::Vector3d& camera_center) {
  const Eigen::Vector3d q = point + 2e-3 * (camera_center - point).normalized();
  constexpr double h = 1e-5;
  Eigen::Vector3d gradient;
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d step = h * Eigen::Vector3d::Unit(axis);
    gradient[axis] = scene.distanceToSurface(q + step) - scene.distanceToSurface(q - step);
  }
  return gradient.normalized();
}

// Largest depth jump between the point's pixel and the pixels up to two away: a silhouette
// where the point lies next to a farther (or missing) background.
double depthJumpAround(const View& view, const CameraIntrinsics& camera,
                       const Eigen::Vector3d& point) {
  const Eigen::Vector2d uv = camera.project(view.T_world_camera.inverse() * point);
  const int u = static_cast<int>(std::lround(uv.x()));
  const int v = static_cast<int>(std::lround(uv.y()));
  const float center = view.image.at(u, v);
  double jump = 0.0;
  for (int dv = -2; dv <= 2; ++dv) {
    for (int du = -2; du <= 2; ++du) {
      const int uu = u + du, vv = v + dv;
      if (uu < 0 || vv < 0 || uu >= camera.width || vv >= camera.height) continue;
      const float other = view.image.at(uu, vv);
      jump = std::max(jump, std::isnan(other) ? 1e3 : std::abs(double(other) - center));
    }
  }
  return jump;
}

// One row per observed surface point: where it lies, how the views saw it, how the map scores
// it, and the increments the views gave its own voxel (the sign decides its label).
void writePointsCsv(const std::string& path, const sim::Scene& scene, const VoxelMap& map,
                    const std::vector<View>& views, const CameraIntrinsics& camera,
                    const PyramidDepthIntegrator& integrator,
                    const std::vector<Eigen::Vector3d>& points,
                    const std::vector<bool>& in_reference_set) {
  const std::size_t n = points.size();
  std::vector<int> observing(n, 0), positive(n, 0), negative(n, 0);
  std::vector<double> min_border(n, 1e9), max_jump(n, 0.0), sum(n, 0.0);
  const double tolerance = 0.5 * map.resolution();
  for (const View& view : views) {
    const DepthFrame frame =
        integrator.prepare(view.posed().depth, camera, view.T_world_camera, map.resolution());
#pragma omp parallel for schedule(dynamic, 256)
    for (long i = 0; i < static_cast<long>(n); ++i) {
      const Eigen::Vector3d& p = points[i];
      // Points behind the camera get nothing (and the ideal would scan the whole image).
      if ((frame.T_camera_map * p).z() <= 0.0) continue;
      if (const std::optional<float> delta =
              integrator.voxelLogOdds(frame, map.centerOf(map.indexOf(p)))) {
        sum[i] += *delta;
        positive[i] += *delta > 0.0f;
        negative[i] += *delta <= 0.0f;
      }
      if (!observesSurfacePoint(view.posed(), camera, p, tolerance)) continue;
      ++observing[i];
      const Eigen::Vector2d uv = camera.project(view.T_world_camera.inverse() * p);
      const double border = std::min(
          {uv.x() + 0.5, uv.y() + 0.5, camera.width - 0.5 - uv.x(), camera.height - 0.5 - uv.y()});
      min_border[i] = std::min(min_border[i], border);
      max_jump[i] = std::max(max_jump[i], depthJumpAround(view, camera, p));
    }
  }
  std::ofstream out(path);
  out << "x,y,z,range,incidence_deg,views_observing,min_border_px,max_depth_jump,"
         "dist_iso,near_occupied,voxel_log_odds,views_positive,views_negative,"
         "unclamped_sum,in_reference_set\n";
  const Eigen::Vector3d center = views.front().T_world_camera.translation();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = points[i];
    const Eigen::Vector3d to_camera = (center - p).normalized();
    const double incidence =
        std::acos(std::clamp(surfaceNormal(scene, p, center).dot(to_camera), -1.0, 1.0)) * 180.0 /
        M_PI;
    const std::optional<float> own = map.logOdds(map.indexOf(p));
    out << p.x() << ',' << p.y() << ',' << p.z() << ',' << (center - p).norm() << ',' << incidence
        << ',' << observing[i] << ',' << min_border[i] << ',' << max_jump[i] << ','
        << distanceToIsoSurface(map, p) << ',' << occupiedWithinOneVoxel(map, p) << ','
        << (own ? *own : std::nanf("")) << ',' << positive[i] << ',' << negative[i] << ',' << sum[i]
        << ',' << in_reference_set[i] << '\n';
  }
}

struct RunOptions {
  double resolution = 0.02;
  bool clamp = true;
  int score_every = 0;     // print scores after every N integrated views (0: only at the end)
  std::string points_csv;  // prefix of the per-point CSV files (empty: none)
  // "frustum": integrate() over the whole frustum; "surface": only the voxels the surface
  // scores read (the shell around the observed points), so the ideal model fits the time
  // budget; "auto": surface for the ideal, frustum otherwise.
  std::string region = "auto";
};

// The voxels distanceToIsoSurface and occupiedWithinOneVoxel read for these points: within
// three voxels (two, plus the neighbour along an axis) of each point's voxel, per axis.
std::vector<VoxelIndex> surfaceShell(const VoxelMap& map,
                                     const std::vector<Eigen::Vector3d>& points) {
  std::vector<VoxelIndex> shell;
  constexpr int kReach = 3;
  for (const Eigen::Vector3d& point : points) {
    const VoxelIndex center = map.indexOf(point);
    for (int dz = -kReach; dz <= kReach; ++dz) {
      for (int dy = -kReach; dy <= kReach; ++dy) {
        for (int dx = -kReach; dx <= kReach; ++dx) shell.push_back(center + VoxelIndex(dx, dy, dz));
      }
    }
  }
  const auto less = [](const VoxelIndex& a, const VoxelIndex& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  std::sort(shell.begin(), shell.end(), less);
  shell.erase(std::unique(shell.begin(), shell.end()), shell.end());
  return shell;
}

// One view applied to the shell voxels only: each gets voxelLogOdds, the increment integrate()
// gives it (the two agree bit for bit), so the shell holds what a full integration would.
void integrateShell(const PyramidDepthIntegrator& integrator, const View& view,
                    const CameraIntrinsics& camera, const std::vector<VoxelIndex>& shell,
                    VoxelMap* map) {
  const DepthFrame frame =
      integrator.prepare(view.posed().depth, camera, view.T_world_camera, map->resolution());
  // integrate() evaluates only the frame's candidate blocks; outside them no voxel changes
  // (and the ideal model would scan the whole image for voxels behind the camera).
  std::vector<BlockIndex> candidates = integrator.candidateBlocks(frame);
  const auto less = [](const BlockIndex& a, const BlockIndex& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  std::sort(candidates.begin(), candidates.end(), less);
  std::vector<float> deltas(shell.size(), std::numeric_limits<float>::quiet_NaN());
#pragma omp parallel for schedule(dynamic, 256)
  for (long i = 0; i < static_cast<long>(shell.size()); ++i) {
    if (!std::binary_search(candidates.begin(), candidates.end(), VoxelMap::blockOf(shell[i]),
                            less)) {
      continue;
    }
    if (const std::optional<float> delta =
            integrator.voxelLogOdds(frame, map->centerOf(shell[i]))) {
      deltas[i] = *delta;
    }
  }
  std::vector<VoxelUpdate> updates;
  for (std::size_t i = 0; i < shell.size(); ++i) {
    if (!std::isnan(deltas[i])) updates.push_back({shell[i], deltas[i]});
  }
  map->applyUpdates(updates);
}

void printScores(const char* scene_name, const std::string& method, int views_integrated,
                 const SurfaceScores& surface, const FreeSpaceScores& free, double ms_per_view,
                 double cpu_s, bool shell_only) {
  // Shell-only runs hold no free space to score.
  char free_text[96];
  if (shell_only) {
    std::snprintf(free_text, sizeof(free_text), "free_voxels=n/a free_labelled_free=n/a");
  } else {
    std::snprintf(free_text, sizeof(free_text), "free_voxels=%zu free_labelled_free=%.3f%%",
                  free.voxels, percent(free.labelled_free, free.voxels));
  }
  std::printf(
      "depth-accuracy scene=%s method=%s region=%s views=%d surface_points=%zu "
      "surface_within_one_voxel_of_iso=%.2f%% surface_within_one_voxel_of_occupied=%.2f%% "
      "%s ms_per_view=%.0f cpu_s=%.1f\n",
      scene_name, method.c_str(), shell_only ? "surface" : "frustum", views_integrated,
      surface.points, percent(surface.near_iso, surface.points),
      percent(surface.near_occupied, surface.points), free_text, ms_per_view, cpu_s);
  std::fflush(stdout);
}

void mapAndScore(const char* scene_name, const sim::Scene& scene, const std::vector<View>& views,
                 const CameraIntrinsics& camera, const PyramidDepthConfig& config,
                 const RunOptions& options, const std::vector<Eigen::Vector3d>& samples,
                 const std::vector<bool>& observed, const std::vector<bool>& reference) {
  const PyramidDepthIntegrator integrator(config);
  VoxelMapConfig map_config;
  map_config.resolution = options.resolution;
  if (!options.clamp) {  // Eq. 3 as the paper writes it: plain sums of log-odds
    map_config.model.clamp_min = 1e-30;
    map_config.model.clamp_max = 1.0 - 1e-7;
  }
  VoxelMap map(map_config);
  const std::vector<Eigen::Vector3d> points = selected(samples, observed);
  const std::string method = toString(config.method);
  double integrate_ms = 0.0;
  const double cpu_start_ms = bench::processCpuMilliseconds();
  const bool shell_only = options.region == "surface" ||
                          (options.region == "auto" && config.method == DepthMethod::kIdeal);
  const std::vector<VoxelIndex> shell =
      shell_only ? surfaceShell(map, points) : std::vector<VoxelIndex>();
  const auto scoreFreeIfFull = [&]() {
    return shell_only ? FreeSpaceScores() : scoreFree(scene, map);
  };
  for (std::size_t i = 0; i < views.size(); ++i) {
    const auto start = Clock::now();
    if (shell_only) {
      integrateShell(integrator, views[i], camera, shell, &map);
    } else {
      integrator.integrate(views[i].posed().depth, camera, views[i].T_world_camera, &map);
    }
    integrate_ms += millisecondsSince(start);
    const int done = static_cast<int>(i) + 1;
    if (options.score_every > 0 && done % options.score_every == 0 && done < int(views.size())) {
      printScores(scene_name, method, done, scoreSurfacePoints(map, points), scoreFreeIfFull(),
                  integrate_ms / done, 1e-3 * (bench::processCpuMilliseconds() - cpu_start_ms),
                  shell_only);
    }
  }
  const double cpu_s = 1e-3 * (bench::processCpuMilliseconds() - cpu_start_ms);
  printScores(scene_name, method, static_cast<int>(views.size()), scoreSurfacePoints(map, points),
              scoreFreeIfFull(), integrate_ms / std::max<std::size_t>(views.size(), 1), cpu_s,
              shell_only);
  if (!options.points_csv.empty()) {
    const std::string path = options.points_csv + "_" + scene_name + "_" + method + ".csv";
    std::vector<bool> reference_of_points;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      if (observed[i]) reference_of_points.push_back(reference[i]);
    }
    writePointsCsv(path, scene, map, views, camera, integrator, points, reference_of_points);
    std::printf("# per-point rows written to %s\n", path.c_str());
  }
}

}  // namespace

int runDepthAccuracy(const CommandLine& args) {
  RunOptions options;
  options.resolution = args.doubleValue("resolution", 0.02);
  const int view_count = args.intValue("views", 181);
  // The observed surface points are those some view of this subset measured (default: the
  // integrated views themselves).
  const int observe_count = args.intValue("observe_views", view_count);
  const double max_range = args.doubleValue("max_range", 15.0);
  options.score_every = args.intValue("score_every", 0);
  options.points_csv = args.value("points_csv", "");
  const std::string clamp = args.value("clamp", "on");
  options.region = args.value("region", "auto");
  if (options.region != "auto" && options.region != "frustum" && options.region != "surface") {
    throw UsageError("--region takes auto, frustum or surface");
  }
  if (!(options.resolution > 0.0) || view_count < 1 || view_count > 181 || observe_count < 1 ||
      observe_count > 181 || options.score_every < 0 || (clamp != "on" && clamp != "off")) {
    throw UsageError(
        "--resolution must be > 0, --views and --observe_views in [1, 181], --score_every >= 0, "
        "--clamp on or off");
  }
  options.clamp = clamp == "on";
  PyramidDepthConfig config;
  // Noise-free renderings: the paper's k = sigma shape at one voxel's width. Eq. 7 crosses
  // p = 0.5 in front of a surface at sqrt(2 ln((A + 0.2) / 0.2)) sigma, A = k / (sigma
  // sqrt(2 pi)): 1.48 sigma for k = sigma, so the iso-surface lies within a voxel of the true
  // surface only while sigma is at most about two thirds of a voxel. k defaults to sigma (the
  // same shape at any scale).
  config.sigma = args.doubleValue("sigma", 0.02);
  config.k = args.doubleValue("k", config.sigma);
  config.sigma_quadratic = args.doubleValue("sigma_quadratic", 0.0);
  config.unknown_behind_sigmas = args.doubleValue("unknown_behind_sigmas", 3.0);
  config.finer_layers = args.intValue("finer_layers", 0);       // not the paper unless 0
  config.clear_passed = args.intValue("clear_passed", 0) != 0;  // nor unless 0
  config.max_range = max_range;
  const CameraIntrinsics camera = sim::pirkerSyntheticCamera();
  std::printf(
      "# %d of the sweep's 181 views (observed points from %d), %dx%d f=%g c=(%g, %g); "
      "resolution=%g k=%g sigma=%g sigma_quadratic=%g unknown_behind_sigmas=%g finer_layers=%d "
      "clamp=%s threads=%d\n",
      view_count, observe_count, camera.width, camera.height, camera.fx, camera.cx, camera.cy,
      options.resolution, config.k, config.sigma, config.sigma_quadratic,
      config.unknown_behind_sigmas, config.finer_layers, clamp.c_str(), omp_get_max_threads());
  std::fflush(stdout);
  for (const std::string& scene_name : args.listValue("scenes", "box,spheres")) {
    if (scene_name != "box" && scene_name != "spheres") {
      throw UsageError("--scenes takes box and/or spheres, not '" + scene_name + "'");
    }
    const bool box = scene_name == "box";
    const sim::Scene scene = box ? sim::makeBoxScene() : sim::makeSpheresScene();
    const Eigen::Vector3d position =
        box ? sim::boxSceneCameraPosition() : sim::spheresSceneCameraPosition();
    const std::vector<View> views = renderViews(scene, camera, position, view_count, max_range);
    const std::vector<Eigen::Vector3d> samples = scene.sampleSurface(options.resolution);
    const double tolerance = 0.5 * options.resolution;
    const std::vector<bool> observed =
        observe_count == view_count
            ? observedBy(samples, views, camera, tolerance)
            : observedBy(samples, renderViews(scene, camera, position, observe_count, max_range),
                         camera, tolerance);
    // For the CSV: whether the other subset (the integrated views) observed each point too.
    const std::vector<bool> reference =
        observe_count == view_count ? observed : observedBy(samples, views, camera, tolerance);
    for (const std::string& method : args.listValue("methods", "pyramid,andert,ideal")) {
      config.method = depthMethodFromString(method);
      mapAndScore(scene_name.c_str(), scene, views, camera, config, options, samples, observed,
                  reference);
    }
  }
  return 0;
}

}  // namespace occupancy_fusion
