// benchmark disparity-artifacts: Schauwecker & Zell's map-quality claims (Sec. IV-A) on the
// simulator's corridor, where the ground truth is known.
//
// 1. Artifacts: a camera walks down the corridor at the paper's rate (3 cm per frame) and sees
//    disparity with correlated errors (patches of wrong disparity that persist over frames, as a
//    real matcher makes). The same points go into the visibility method, the OctoMap mode on the
//    same rays and liboctomap's OcTree::insertPointCloud. For each map: false-occupied voxels
//    (occupied, centre in ground-truth free space more than one voxel diagonal from any surface)
//    and coverage of the surface the trajectory sees (a sample counts when an occupied voxel lies
//    within one voxel of it). With --images, top views of the three maps.
// 2. Fig. 5a: one view down the corridor integrated again and again; after each update the
//    distance to the farthest occupied voxel (P(O) > 0.5), per voxel size.
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "occupancy_fusion/benchmarks/benchmark_harness.h"
#include "occupancy_fusion/eval/stereo_corridor.h"
#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/integrators/stereo/visibility_stereo_integrator.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/stereo_camera.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

using bench::Clock;
using bench::millisecondsSince;

// liboctomap's occupied leaves on the shared grid (pruned leaves expanded to the finest level).
OccupiedVoxelSet occupiedOf(const octomap::OcTree& tree, double resolution) {
  OccupiedVoxelSet occupied;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const int n = static_cast<int>(std::lround(it.getSize() / resolution));
    const octomap::point3d c = it.getCoordinate();
    const double half = 0.5 * it.getSize();
    for (int dx = 0; dx < n; ++dx) {
      for (int dy = 0; dy < n; ++dy) {
        for (int dz = 0; dz < n; ++dz) {
          const Eigen::Vector3d p(c.x() - half + (dx + 0.5) * resolution,
                                  c.y() - half + (dy + 0.5) * resolution,
                                  c.z() - half + (dz + 0.5) * resolution);
          occupied.add(voxelIndexOf(p, resolution));
        }
      }
    }
  }
  return occupied;
}

struct Run {
  std::string name;
  OccupiedVoxelSet occupied;
  double ms_per_frame = 0.0;
  double cache_hit_rate = -1.0;  // -1: not applicable
  StereoMapQuality quality;
};

Run mapWithIntegrator(const std::string& name, const VisibilityStereoConfig& config,
                      const std::vector<StereoFrame>& frames, double resolution) {
  StereoCorridorRun result = mapStereoCorridor(config, frames, resolution);
  Run run{name, std::move(result.occupied), 1e3 * result.seconds / frames.size(), 0.0, {}};
  run.cache_hit_rate =
      result.voxel_visits == 0 ? 0.0 : static_cast<double>(result.cache_hits) / result.voxel_visits;
  return run;
}

Run mapWithLiboctomap(const std::vector<StereoFrame>& frames, double resolution) {
  octomap::OcTree tree(resolution);  // liboctomap's defaults: hit 0.7, miss 0.4, clamp 0.12/0.97
  double seconds = 0.0;
  for (const StereoFrame& frame : frames) {
    octomap::Pointcloud cloud;
    cloud.reserve(frame.points.size());
    for (const Eigen::Vector3f& p : frame.points) cloud.push_back(p.x(), p.y(), p.z());
    const octomap::point3d origin(frame.origin.x(), frame.origin.y(), frame.origin.z());
    const auto start = Clock::now();
    tree.insertPointCloud(cloud, origin);
    seconds += 1e-3 * millisecondsSince(start);
  }
  return {"liboctomap", occupiedOf(tree, resolution), 1e3 * seconds / frames.size(), -1.0, {}};
}

// ---------------------------------------------------------------------------------------------
// Top views: every occupied voxel between 0.2 m and 2.3 m height (floor and ceiling cut off, as
// the paper's Fig. 3), one column per (x, y) cell: black where all its voxels are right, red
// where one is false-occupied; the ground-truth walls at camera height in grey, the trajectory
// in blue.

}  // namespace

cv::Mat stereoTopView(const std::string& title, const OccupiedVoxelSet& occupied,
                      const std::vector<bool>& is_false, const sim::Scene& scene, double resolution,
                      const std::vector<Eigen::Isometry3d>& poses, double camera_height) {
  constexpr double kMinX = -4.5, kMaxX = 17.0, kMinY = -4.0, kMaxY = 4.0;
  constexpr int kPixelsPerMetre = 40;
  const int width = static_cast<int>((kMaxX - kMinX) * kPixelsPerMetre);
  const int height = static_cast<int>((kMaxY - kMinY) * kPixelsPerMetre);
  cv::Mat image(height + 24, width, CV_8UC3, cv::Scalar(255, 255, 255));
  auto pixelOf = [&](double x, double y) {
    return cv::Point(static_cast<int>((x - kMinX) * kPixelsPerMetre),
                     24 + static_cast<int>((kMaxY - y) * kPixelsPerMetre));
  };
  const double cell = 1.0 / kPixelsPerMetre;
  for (double x = kMinX; x < kMaxX; x += cell) {
    for (double y = kMinY; y < kMaxY; y += cell) {
      if (scene.isOccupied({x + 0.5 * cell, y + 0.5 * cell, camera_height})) {
        image.at<cv::Vec3b>(pixelOf(x, y + cell)) = cv::Vec3b(200, 200, 200);
      }
    }
  }
  const int z_min = static_cast<int>(std::floor(0.2 / resolution));
  const int z_max = static_cast<int>(std::floor(2.3 / resolution));
  SpatialKeyMap<bool> columns;  // (x, y) -> has a false-occupied voxel
  std::size_t false_count = 0;
  for (std::size_t i = 0; i < occupied.voxels.size(); ++i) {
    const VoxelIndex& v = occupied.voxels[i];
    false_count += is_false[i] ? 1 : 0;
    if (v.z() < z_min || v.z() > z_max) continue;
    bool& wrong = columns[packKey(VoxelIndex(v.x(), v.y(), 0))];
    wrong = wrong || is_false[i];
  }
  for (const auto& [key, wrong] : columns) {
    const VoxelIndex v = unpackKey3(key);
    const cv::Point corner = pixelOf(v.x() * resolution, (v.y() + 1) * resolution);
    const int size = std::max(1, static_cast<int>(std::lround(resolution * kPixelsPerMetre)));
    cv::rectangle(image, cv::Rect(corner.x, corner.y, size, size),
                  wrong ? cv::Scalar(0, 0, 230) : cv::Scalar(40, 40, 40), cv::FILLED);
  }
  for (std::size_t k = 1; k < poses.size(); ++k) {
    cv::line(image, pixelOf(poses[k - 1].translation().x(), poses[k - 1].translation().y()),
             pixelOf(poses[k].translation().x(), poses[k].translation().y()),
             cv::Scalar(230, 90, 0), 2);
  }
  cv::circle(image, pixelOf(poses.back().translation().x(), poses.back().translation().y()), 4,
             cv::Scalar(230, 90, 0), cv::FILLED);
  char text[300];
  std::snprintf(text, sizeof(text), "%s: %zu occupied, %zu false-occupied", title.c_str(),
                occupied.voxels.size(), false_count);
  cv::putText(image, text, cv::Point(6, 17), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  return image;
}

namespace {

cv::Mat topView(const Run& run, const sim::Scene& scene, double resolution,
                const std::vector<Eigen::Isometry3d>& poses, double camera_height) {
  char title[200];
  std::snprintf(title, sizeof(title), "%s (coverage %.3f)", run.name.c_str(), run.quality.coverage);
  return stereoTopView(title, run.occupied, run.quality.is_false, scene, resolution, poses,
                       camera_height);
}

// ---------------------------------------------------------------------------------------------
// Fig. 5a

constexpr double kFig5aRange = 20.0;  // m: the whole corridor, up to its end wall

// Distance from the sensor to the farthest occupied voxel centre.
double farthestOccupied(const VoxelMap& map, const Eigen::Vector3d& origin) {
  double farthest = 0.0;
  map.forEachOccupiedVoxel([&](const VoxelIndex& index, float) {
    farthest = std::max(farthest, (map.centerOf(index) - origin).norm());
  });
  return farthest;
}

// Row k: the distance after update k + 1.
std::vector<double> mappedDistanceGrowth(VisibilityStereoConfig config, double resolution,
                                         int updates) {
  // Far pixels' noise makes disparities near 0, points kilometres away: cleared up to the
  // corridor's length, as octomap_server's max_range does.
  config.max_range = kFig5aRange;
  const sim::Scene scene = sim::makeCorridorScene();
  StereoCorridorSetup setup;
  setup.frames = 2;
  const sim::PinholeCamera camera = setup.camera();
  const Eigen::Isometry3d pose = setup.poses().front();
  // The exact disparity, the same image every update. (With white noise, pixels near the end
  // wall get disparities near 0 and sigma_z of kilometres: P(I_v) ~ 0.5 along their whole ray,
  // and the reduction's maximum over rays turns the voxels next to the sensor occupied.)
  const sim::DisparityNoise noise;
  const sim::DisparityImage image =
      sim::renderDisparity(scene, camera, setup.baseline, pose, kFig5aRange, noise, 0);
  const DisparityImageView view{image.width, image.height, image.disparity.data(), 0};
  const VisibilityStereoIntegrator integrator(config);
  VoxelMapConfig map_config;
  map_config.resolution = resolution;
  VoxelMap map(map_config);
  std::vector<double> distances;
  for (int k = 0; k < updates; ++k) {
    integrator.integrate(view, setup.stereo(), pose, &map);
    distances.push_back(farthestOccupied(map, pose.translation()));
  }
  return distances;
}

struct Curve {
  std::string label;
  std::vector<double> distances;
  cv::Scalar colour;
};

cv::Mat plotGrowth(const std::vector<Curve>& curves, int updates) {
  constexpr int kWidth = 640, kHeight = 400, kLeft = 60, kBottom = 40, kTop = 20, kRight = 20;
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const double max_distance = kFig5aRange;
  auto pixelOf = [&](double update, double distance) {
    const double u = kLeft + (kWidth - kLeft - kRight) * update / updates;
    const double v = kHeight - kBottom - (kHeight - kBottom - kTop) * distance / max_distance;
    return cv::Point(static_cast<int>(u), static_cast<int>(v));
  };
  const cv::Scalar black(0, 0, 0), grey(210, 210, 210);
  for (int d = 0; d <= 20; d += 5) {
    cv::line(image, pixelOf(0, d), pixelOf(updates, d), grey, 1);
    cv::putText(image, std::to_string(d), pixelOf(0, d) + cv::Point(-30, 5),
                cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
  }
  for (int k = 0; k <= updates; k += 20) {
    cv::putText(image, std::to_string(k), pixelOf(k, 0) + cv::Point(-8, 20),
                cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
  }
  cv::line(image, pixelOf(0, 0), pixelOf(updates, 0), black, 1);
  cv::line(image, pixelOf(0, 0), pixelOf(0, max_distance), black, 1);
  cv::putText(image, "updates of the same view", cv::Point(kWidth / 2 - 90, kHeight - 6),
              cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
  cv::putText(image, "m", cv::Point(10, kTop + 10), cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1,
              cv::LINE_AA);
  for (std::size_t c = 0; c < curves.size(); ++c) {
    const Curve& curve = curves[c];
    for (std::size_t k = 1; k < curve.distances.size(); ++k) {
      cv::line(image, pixelOf(k, curve.distances[k - 1]), pixelOf(k + 1, curve.distances[k]),
               curve.colour, 2, cv::LINE_AA);
    }
    const cv::Point legend(kLeft + 300, kHeight - kBottom - 20 - 18 * static_cast<int>(c));
    cv::line(image, legend, legend + cv::Point(20, 0), curve.colour, 2);
    cv::putText(image, curve.label, legend + cv::Point(26, 5), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                black, 1, cv::LINE_AA);
  }
  return image;
}

// ---------------------------------------------------------------------------------------------

// The visibility method's parameters from the command line, each over the defaults (with
// `lists`, the sweep's, the four swept parameters are left to runSweep).
VisibilityStereoConfig configFrom(const CommandLine& args, bool lists,
                                  const std::string& default_set = "table_i") {
  VisibilityStereoConfig config = visibilityStereoConfigFor(
      stereoParameterSetFromString(args.value("parameter_set", default_set)));
  config.unknown_neighbours = unknownNeighboursFromString(
      args.value("unknown_neighbours", toString(config.unknown_neighbours)));
  config.unknown_neighbour_occupancy =
      args.doubleValue("unknown_neighbour_occupancy", config.unknown_neighbour_occupancy);
  if (lists) return config;
  config.visibility_max = args.doubleValue("q_max", config.visibility_max);
  config.visibility_min = args.doubleValue("q_min", config.visibility_min);
  config.prob_visible_if_occluded =
      args.doubleValue("p_visible_occluded", config.prob_visible_if_occluded);
  config.prob_hit_invisible = args.doubleValue("p_hit_invisible", config.prob_hit_invisible);
  config.measured_surface.window_px =
      args.intValue("measured_window", config.measured_surface.window_px);
  config.measured_surface.step_px =
      args.doubleValue("measured_step_px", config.measured_surface.step_px);
  config.measured_surface.grid_step_px =
      args.intValue("measured_grid_px", config.measured_surface.grid_step_px);
  config.measured_surface.grid_footprint_fraction =
      args.doubleValue("measured_grid_fraction", config.measured_surface.grid_footprint_fraction);
  config.measured_surface.grid_max_step_px =
      args.intValue("measured_grid_max_px", config.measured_surface.grid_max_step_px);
  config.measured_sigma_max_voxels =
      args.doubleValue("measured_sigma_max_voxels", config.measured_sigma_max_voxels);
  config.passed_sigmas = args.doubleValue("passed_sigmas", config.passed_sigmas);
  for (const auto& [option, field] :
       {std::pair<const char*, bool*>{"measured_fuse_known", &config.measured_fuse_known},
        {"measured_prior", &config.measured_prior},
        {"measured_inside", &config.measured_inside},
        {"measured_visibility", &config.measured_visibility},
        {"clear_passed", &config.clear_passed}}) {
    *field = args.intValue(option, *field) != 0;
  }
  config.validate();
  return config;
}

// The option's numbers, or {fallback} when it is not given.
std::vector<double> numberList(const CommandLine& args, const std::string& option,
                               double fallback) {
  if (!args.has(option)) return {fallback};
  return bench::parseNumbers<double>(option, args.value(option));
}

void writeImage(const std::string& path, const cv::Mat& image) {
  if (!cv::imwrite(path, image)) throw UsageError("cannot write " + path);
  std::printf("wrote %s\n", path.c_str());
}

StereoCorridorSetup setupFrom(const CommandLine& args) {
  StereoCorridorSetup setup;
  setup.frames = args.intValue("frames", setup.frames);
  if (setup.frames < 2) throw UsageError("--frames must be at least 2");
  return setup;
}

std::string coverageBins(const StereoMapQuality& quality) {
  std::string text;
  for (int b = 0; b < kCoverageDistanceBins; ++b) {
    char item[64];
    std::snprintf(item, sizeof(item), "%scoverage_%d_%dm=%.3f", b == 0 ? "" : " ",
                  static_cast<int>(b * kCoverageBinWidth),
                  static_cast<int>((b + 1) * kCoverageBinWidth), quality.coverage_by_distance[b]);
    text += item;
  }
  return text;
}

void runArtifacts(const CommandLine& args, const VisibilityStereoConfig& visibility_config) {
  const StereoCorridorSetup setup = setupFrom(args);
  const double resolution = args.doubleValue("resolution", 0.2);
  if (!(resolution > 0)) throw UsageError("--resolution must be positive");
  const sim::Scene scene = sim::makeCorridorScene();
  const std::vector<Eigen::Isometry3d> poses = setup.poses();
  const std::vector<StereoFrame> input =
      renderStereoCorridor(scene, setup, VisibilityStereoIntegrator());
  const std::vector<SeenSurfaceSample> surface = seenSurface(scene, setup, resolution);
  VisibilityStereoConfig octomap_config = visibility_config;
  octomap_config.method = StereoIntegrationMethod::kOctomap;
  std::vector<Run> runs;
  runs.push_back(mapWithIntegrator("visibility", visibility_config, input, resolution));
  runs.push_back(mapWithIntegrator("octomap_mode", octomap_config, input, resolution));
  runs.push_back(mapWithLiboctomap(input, resolution));
  for (Run& run : runs) run.quality = evaluateStereoMap(scene, run.occupied, resolution, surface);
  const StereoMapQuality& reference = runs[1].quality;
  std::printf(
      "# corridor: %d frames, %.2f m voxels, %zu visible surface samples (by nearest "
      "view, 2 m bins: %zu %zu %zu %zu)\n",
      setup.frames, resolution, surface.size(), reference.samples_by_distance[0],
      reference.samples_by_distance[1], reference.samples_by_distance[2],
      reference.samples_by_distance[3]);
  for (const Run& run : runs) {
    std::printf(
        "disparity-artifacts method=%s frames=%d resolution=%.2f occupied=%zu "
        "false_occupied=%zu coverage=%.3f false_occupied_vs_octomap_mode=%.3f "
        "coverage_vs_octomap_mode=%.3f ms_per_frame=%.1f cache_hit_rate=%.3f %s\n",
        run.name.c_str(), setup.frames, resolution, run.quality.occupied,
        run.quality.false_occupied, run.quality.coverage,
        static_cast<double>(run.quality.false_occupied) /
            std::max<std::size_t>(1, reference.false_occupied),
        run.quality.coverage / std::max(1e-9, reference.coverage), run.ms_per_frame,
        run.cache_hit_rate, coverageBins(run.quality).c_str());
  }
  if (args.has("images")) {
    std::vector<cv::Mat> panels;
    for (const Run& run : runs) {
      panels.push_back(topView(run, scene, resolution, poses, setup.height));
    }
    cv::Mat stacked;
    cv::vconcat(panels, stacked);
    // Table I's picture keeps its name; another parameter set's name is appended.
    const std::string set = args.value("parameter_set", "table_i");
    writeImage(args.value("images") + "/disparity_artifacts_top" +
                   (set == "table_i" ? std::string() : "_" + set) + ".png",
               stacked);
  }
}

// The trade-off Sec. IV names (map expansion against map quality): the visibility method over a
// grid of q_max, q_min, P(V | C, V) and P(H | not V) per voxel size, each against the OctoMap
// mode on the same points. One line per configuration.
void runSweep(const CommandLine& args, const VisibilityStereoConfig& base) {
  const StereoCorridorSetup setup = setupFrom(args);
  const sim::Scene scene = sim::makeCorridorScene();
  const std::vector<StereoFrame> input =
      renderStereoCorridor(scene, setup, VisibilityStereoIntegrator());
  for (double resolution : numberList(args, "resolution", 0.2)) {
    if (!(resolution > 0)) throw UsageError("--resolution must be positive");
    const std::vector<SeenSurfaceSample> surface = seenSurface(scene, setup, resolution);
    VisibilityStereoConfig octomap_config = base;
    octomap_config.method = StereoIntegrationMethod::kOctomap;
    const StereoMapQuality reference = evaluateStereoMap(
        scene, mapStereoCorridor(octomap_config, input, resolution).occupied, resolution, surface);
    std::printf(
        "disparity-sweep method=octomap_mode frames=%d resolution=%.2f false_occupied=%zu "
        "coverage=%.3f %s\n",
        setup.frames, resolution, reference.false_occupied, reference.coverage,
        coverageBins(reference).c_str());
    for (double q_max : numberList(args, "q_max", base.visibility_max)) {
      for (double q_min : numberList(args, "q_min", base.visibility_min)) {
        for (double p_vc : numberList(args, "p_visible_occluded", base.prob_visible_if_occluded)) {
          for (double p_hi : numberList(args, "p_hit_invisible", base.prob_hit_invisible)) {
            VisibilityStereoConfig config = base;
            config.visibility_max = q_max;
            config.visibility_min = std::min(q_min, q_max);
            config.prob_visible_if_occluded = p_vc;
            config.prob_hit_invisible = p_hi;
            config.validate();
            const StereoMapQuality q = evaluateStereoMap(
                scene, mapStereoCorridor(config, input, resolution).occupied, resolution, surface);
            std::printf(
                "disparity-sweep method=visibility frames=%d resolution=%.2f q_max=%.3f "
                "q_min=%.3f p_visible_occluded=%.3f p_hit_invisible=%.3f false_occupied=%zu "
                "coverage=%.3f false_occupied_vs_octomap_mode=%.3f coverage_vs_octomap_mode=%.3f "
                "%s\n",
                setup.frames, resolution, q_max, config.visibility_min, p_vc, p_hi,
                q.false_occupied, q.coverage,
                static_cast<double>(q.false_occupied) /
                    std::max<std::size_t>(1, reference.false_occupied),
                q.coverage / std::max(1e-9, reference.coverage), coverageBins(q).c_str());
            std::fflush(stdout);
          }
        }
      }
    }
  }
}

void runFig5a(const CommandLine& args, const VisibilityStereoConfig& visibility_config) {
  const int updates = args.intValue("fig5a_updates", 100);
  if (updates < 1) throw UsageError("--fig5a_updates must be at least 1");
  const std::vector<double> resolutions{0.1, 0.2, 0.3};
  const cv::Scalar colours[] = {{200, 60, 0}, {0, 0, 220}, {0, 150, 0}};
  std::vector<Curve> curves;
  for (std::size_t r = 0; r < resolutions.size(); ++r) {
    char label[64];
    std::snprintf(label, sizeof(label), "visibility, %.1f m voxels", resolutions[r]);
    curves.push_back(
        {label, mappedDistanceGrowth(visibility_config, resolutions[r], updates), colours[r]});
  }
  VisibilityStereoConfig octomap_config = visibility_config;
  octomap_config.method = StereoIntegrationMethod::kOctomap;
  curves.push_back({"OctoMap mode, 0.2 m voxels",
                    mappedDistanceGrowth(octomap_config, 0.2, updates), cv::Scalar(120, 120, 120)});
  for (const Curve& curve : curves) {
    for (int k : {1, 2, 5, 10, 20, 40, 65, 100, 150, 200}) {
      if (k > updates) break;
      std::printf("disparity-fig5a curve=\"%s\" updates=%d mapped_distance_m=%.2f\n",
                  curve.label.c_str(), k, curve.distances[k - 1]);
    }
  }
  if (args.has("images")) {
    writeImage(args.value("images") + "/disparity_fig5a.png", plotGrowth(curves, updates));
  }
}

}  // namespace

int runDisparityMatrix(const CommandLine& args, const VisibilityStereoConfig& candidate,
                       const std::vector<double>& resolutions);  // benchmark_disparity_matrix.cpp

int runDisparityArtifacts(const CommandLine& args) {
  const std::string part = args.value("part", "all");
  // The matrix tests the mappers' default; the other parts were measured with Table I.
  const VisibilityStereoConfig config =
      configFrom(args, part == "sweep", part == "matrix" ? "measured" : "table_i");
  if (part != "all" && part != "artifacts" && part != "fig5a" && part != "sweep" &&
      part != "matrix") {
    throw UsageError("--part must be all, artifacts, fig5a, sweep or matrix");
  }
  if (part == "matrix") {
    return runDisparityMatrix(args, config, numberList(args, "resolution", 0.1));
  }
  if (part == "sweep") {
    runSweep(args, config);
    return 0;
  }
  if (part != "fig5a") runArtifacts(args, config);
  if (part != "artifacts") runFig5a(args, config);
  return 0;
}

}  // namespace occupancy_fusion
