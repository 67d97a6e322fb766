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
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/integrators/visibility_stereo_integrator.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/stereo_camera.h"
#include "occupancy_fusion/sim/trajectory.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

using Clock = std::chrono::steady_clock;

constexpr double kBaseline = 0.12;      // m
constexpr double kMaxRange = 8.0;       // m, rendered depth limit of the artifacts run
constexpr double kStepPerFrame = 0.03;  // m, the paper's rate: 774 m in 26,000 frames
constexpr double kHeight = 1.2;         // m, camera height

sim::PinholeCamera corridorCamera() {
  sim::PinholeCamera camera;
  camera.width = 160;
  camera.height = 120;
  camera.fx = camera.fy = 131.25;
  camera.cx = 79.5;
  camera.cy = 59.5;
  return camera;
}

StereoCamera stereoOf(const sim::PinholeCamera& camera) {
  return {camera.fx, camera.fy, camera.cx, camera.cy, kBaseline};
}

sim::DisparityNoise correlatedNoise() {
  sim::DisparityNoise noise;
  noise.sigma_px = 0.3;
  noise.patch_probability = 0.3;
  noise.patch_size_px = 12;
  noise.patch_offset_px = 1.5;
  noise.patch_persistence_frames = 10;
  noise.seed = 7;
  return noise;
}

std::vector<Eigen::Isometry3d> corridorPoses(int frames) {
  const Eigen::Vector3d start(0.5, 0.0, kHeight);
  const Eigen::Vector3d end = start + Eigen::Vector3d(kStepPerFrame * frames, 0.0, 0.0);
  std::vector<Eigen::Isometry3d> poses;
  for (const Eigen::Isometry3d& body : sim::straightLinePath(start, end, frames, 0.0, 0.0)) {
    poses.push_back(body * sim::opticalFrameInBody());
  }
  return poses;
}

// One frame's points in the map frame, as every mapper of the run receives them.
struct Frame {
  Eigen::Vector3d origin;
  std::vector<Eigen::Vector3f> points;
  std::vector<float> sigmas;
};

std::vector<Frame> renderFrames(const sim::Scene& scene,
                                const std::vector<Eigen::Isometry3d>& poses,
                                const VisibilityStereoIntegrator& converter) {
  const sim::PinholeCamera camera = corridorCamera();
  std::vector<Frame> frames(poses.size());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const sim::DisparityImage image = sim::renderDisparity(
        scene, camera, kBaseline, poses[k], kMaxRange, correlatedNoise(), static_cast<int>(k));
    const DisparityImageView view{image.width, image.height, image.disparity.data(), 0};
    converter.disparityToMapPoints(view, stereoOf(camera), poses[k], &frames[k].points,
                                   &frames[k].sigmas, nullptr);
    frames[k].origin = poses[k].translation();
  }
  return frames;
}

// Surface samples that some pose sees directly (in its image, within range, not occluded).
std::vector<Eigen::Vector3d> visibleSurface(const sim::Scene& scene,
                                            const std::vector<Eigen::Isometry3d>& poses,
                                            double spacing) {
  const sim::PinholeCamera camera = corridorCamera();
  std::vector<Eigen::Vector3d> visible;
  for (const Eigen::Vector3d& sample : scene.sampleSurface(spacing)) {
    for (std::size_t k = 0; k < poses.size(); k += 4) {  // every 4th pose: 12 cm apart
      const Eigen::Vector3d p = poses[k].inverse() * sample;
      if (p.z() <= 0.1 || p.z() > kMaxRange) continue;
      const double u = camera.fx * p.x() / p.z() + camera.cx;
      const double v = camera.fy * p.y() / p.z() + camera.cy;
      if (u < 0 || v < 0 || u > camera.width - 1 || v > camera.height - 1) continue;
      const Eigen::Vector3d offset = sample - poses[k].translation();
      const double distance = offset.norm();
      const auto t = scene.castRay(poses[k].translation(), offset / distance, distance + 0.01);
      if (t && *t >= distance - 0.02) {
        visible.push_back(sample);
        break;
      }
    }
  }
  return visible;
}

// A finished map, as the evaluation sees it: its occupied voxels on the shared grid (index =
// floor(p / resolution), which liboctomap's keys follow too) and an occupancy test.
struct OccupiedVoxels {
  std::vector<VoxelIndex> voxels;
  SpatialKeySet keys;
  void add(const VoxelIndex& index) {
    if (keys.insert(packKey(index)).second) voxels.push_back(index);
  }
  bool contains(const VoxelIndex& index) const { return keys.count(packKey(index)) > 0; }
};

OccupiedVoxels occupiedOf(const VoxelMap& map) {
  OccupiedVoxels occupied;
  map.forEachOccupiedVoxel([&](const VoxelIndex& index, float) { occupied.add(index); });
  return occupied;
}

OccupiedVoxels occupiedOf(const octomap::OcTree& tree, double resolution) {
  OccupiedVoxels occupied;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    // A pruned leaf stands for size^3 voxels of the finest level.
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

struct Quality {
  std::size_t occupied = 0;
  std::size_t false_occupied = 0;
  double coverage = 0.0;
  std::vector<bool> is_false;  // per occupied voxel, for the pictures
};

Quality evaluate(const sim::Scene& scene, const OccupiedVoxels& map, double resolution,
                 const std::vector<Eigen::Vector3d>& surface) {
  Quality quality;
  const double tolerance = std::sqrt(3.0) * resolution;  // one voxel diagonal
  for (const VoxelIndex& index : map.voxels) {
    const Eigen::Vector3d center = (index.cast<double>().array() + 0.5) * resolution;
    const bool wrong = !scene.isOccupied(center) && scene.distanceToSurface(center) > tolerance;
    quality.is_false.push_back(wrong);
    quality.false_occupied += wrong ? 1 : 0;
  }
  quality.occupied = map.voxels.size();
  std::size_t covered = 0;
  for (const Eigen::Vector3d& sample : surface) {
    const VoxelIndex base = voxelIndexOf(sample, resolution);
    bool found = false;
    for (int dz = -1; dz <= 1 && !found; ++dz) {
      for (int dy = -1; dy <= 1 && !found; ++dy) {
        for (int dx = -1; dx <= 1 && !found; ++dx) {
          found = map.contains(base + VoxelIndex(dx, dy, dz));
        }
      }
    }
    covered += found ? 1 : 0;
  }
  quality.coverage = surface.empty() ? 0.0 : static_cast<double>(covered) / surface.size();
  return quality;
}

struct Run {
  std::string name;
  OccupiedVoxels occupied;
  double ms_per_frame = 0.0;
  double cache_hit_rate = -1.0;  // -1: not applicable
  Quality quality;
};

Run mapWithIntegrator(const std::string& name, const VisibilityStereoConfig& config,
                      const std::vector<Frame>& frames, double resolution) {
  const VisibilityStereoIntegrator integrator(config);
  VoxelMapConfig map_config;
  map_config.resolution = resolution;
  VoxelMap map(map_config);
  double seconds = 0.0;
  std::size_t visits = 0, hits = 0;
  for (const Frame& frame : frames) {
    const StereoIntegrationStats stats =
        integrator.integrate(frame.points, frame.sigmas, frame.origin, &map);
    seconds += stats.seconds;
    visits += stats.voxel_visits;
    hits += stats.cache_hits;
  }
  Run run{name, occupiedOf(map), 1e3 * seconds / frames.size(), 0.0, {}};
  run.cache_hit_rate = visits == 0 ? 0.0 : static_cast<double>(hits) / visits;
  return run;
}

Run mapWithLiboctomap(const std::vector<Frame>& frames, double resolution) {
  octomap::OcTree tree(resolution);  // liboctomap's defaults: hit 0.7, miss 0.4, clamp 0.12/0.97
  double seconds = 0.0;
  for (const Frame& frame : frames) {
    octomap::Pointcloud cloud;
    cloud.reserve(frame.points.size());
    for (const Eigen::Vector3f& p : frame.points) cloud.push_back(p.x(), p.y(), p.z());
    const octomap::point3d origin(frame.origin.x(), frame.origin.y(), frame.origin.z());
    const auto start = Clock::now();
    tree.insertPointCloud(cloud, origin);
    seconds += std::chrono::duration<double>(Clock::now() - start).count();
  }
  return {"liboctomap", occupiedOf(tree, resolution), 1e3 * seconds / frames.size(), -1.0, {}};
}

// ---------------------------------------------------------------------------------------------
// Top views: every occupied voxel between 0.2 m and 2.3 m height (floor and ceiling cut off, as
// the paper's Fig. 3), one column per (x, y) cell: black where all its voxels are right, red
// where one is false-occupied; the ground-truth walls at camera height in grey, the trajectory
// in blue.

cv::Mat topView(const Run& run, const sim::Scene& scene, double resolution,
                const std::vector<Eigen::Isometry3d>& poses) {
  constexpr double kMinX = -1.0, kMaxX = 13.0, kMinY = -4.0, kMaxY = 4.0;
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
      if (scene.isOccupied({x + 0.5 * cell, y + 0.5 * cell, kHeight})) {
        image.at<cv::Vec3b>(pixelOf(x, y + cell)) = cv::Vec3b(200, 200, 200);
      }
    }
  }
  const int z_min = static_cast<int>(std::floor(0.2 / resolution));
  const int z_max = static_cast<int>(std::floor(2.3 / resolution));
  SpatialKeyMap<bool> columns;  // (x, y) -> has a false-occupied voxel
  for (std::size_t i = 0; i < run.occupied.voxels.size(); ++i) {
    const VoxelIndex& v = run.occupied.voxels[i];
    if (v.z() < z_min || v.z() > z_max) continue;
    bool& wrong = columns[packKey(VoxelIndex(v.x(), v.y(), 0))];
    wrong = wrong || run.quality.is_false[i];
  }
  for (const auto& [key, wrong] : columns) {
    const VoxelIndex v = unpackKey3(key);
    const cv::Point corner = pixelOf(v.x() * resolution, (v.y() + 1) * resolution);
    const int size = static_cast<int>(std::lround(resolution * kPixelsPerMetre));
    cv::rectangle(image, cv::Rect(corner.x, corner.y, size, size),
                  wrong ? cv::Scalar(0, 0, 230) : cv::Scalar(40, 40, 40), cv::FILLED);
  }
  cv::line(image, pixelOf(poses.front().translation().x(), 0.0),
           pixelOf(poses.back().translation().x(), 0.0), cv::Scalar(230, 90, 0), 2);
  char title[200];
  std::snprintf(title, sizeof(title), "%s: %zu occupied, %zu false-occupied, coverage %.3f",
                run.name.c_str(), run.quality.occupied, run.quality.false_occupied,
                run.quality.coverage);
  cv::putText(image, title, cv::Point(6, 17), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  return image;
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
  const sim::PinholeCamera camera = corridorCamera();
  const Eigen::Isometry3d pose = corridorPoses(2).front();
  // The exact disparity, the same image every update. (With white noise, pixels near the end
  // wall get disparities near 0 and sigma_z of kilometres: P(I_v) ~ 0.5 along their whole ray,
  // and the reduction's maximum over rays turns the voxels next to the sensor occupied.)
  const sim::DisparityNoise noise;
  const sim::DisparityImage image =
      sim::renderDisparity(scene, camera, kBaseline, pose, kFig5aRange, noise, 0);
  const DisparityImageView view{image.width, image.height, image.disparity.data(), 0};
  const VisibilityStereoIntegrator integrator(config);
  VoxelMapConfig map_config;
  map_config.resolution = resolution;
  VoxelMap map(map_config);
  std::vector<double> distances;
  for (int k = 0; k < updates; ++k) {
    integrator.integrate(view, stereoOf(camera), pose, &map);
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

VisibilityStereoConfig configFrom(const CommandLine& args) {
  VisibilityStereoConfig config;
  config.unknown_neighbours = unknownNeighboursFromString(
      args.value("unknown_neighbours", toString(config.unknown_neighbours)));
  config.unknown_neighbour_occupancy =
      args.doubleValue("unknown_neighbour_occupancy", config.unknown_neighbour_occupancy);
  config.validate();
  return config;
}

void writeImage(const std::string& path, const cv::Mat& image) {
  if (!cv::imwrite(path, image)) throw UsageError("cannot write " + path);
  std::printf("wrote %s\n", path.c_str());
}

void runArtifacts(const CommandLine& args, const VisibilityStereoConfig& visibility_config) {
  const int frames = args.intValue("frames", 80);
  const double resolution = args.doubleValue("resolution", 0.2);
  if (frames < 2) throw UsageError("--frames must be at least 2");
  if (!(resolution > 0)) throw UsageError("--resolution must be positive");
  const sim::Scene scene = sim::makeCorridorScene();
  const std::vector<Eigen::Isometry3d> poses = corridorPoses(frames);
  const std::vector<Frame> input = renderFrames(scene, poses, VisibilityStereoIntegrator());
  const std::vector<Eigen::Vector3d> surface = visibleSurface(scene, poses, resolution);
  VisibilityStereoConfig octomap_config = visibility_config;
  octomap_config.method = StereoIntegrationMethod::kOctomap;
  std::vector<Run> runs;
  runs.push_back(mapWithIntegrator("visibility", visibility_config, input, resolution));
  runs.push_back(mapWithIntegrator("octomap_mode", octomap_config, input, resolution));
  runs.push_back(mapWithLiboctomap(input, resolution));
  for (Run& run : runs) run.quality = evaluate(scene, run.occupied, resolution, surface);
  const Quality& reference = runs[1].quality;
  std::printf("# corridor: %d frames, %.2f m voxels, %zu visible surface samples\n", frames,
              resolution, surface.size());
  for (const Run& run : runs) {
    std::printf(
        "disparity-artifacts method=%s frames=%d resolution=%.2f occupied=%zu "
        "false_occupied=%zu coverage=%.3f false_occupied_vs_octomap_mode=%.3f "
        "coverage_vs_octomap_mode=%.3f ms_per_frame=%.1f cache_hit_rate=%.3f\n",
        run.name.c_str(), frames, resolution, run.quality.occupied, run.quality.false_occupied,
        run.quality.coverage,
        static_cast<double>(run.quality.false_occupied) /
            std::max<std::size_t>(1, reference.false_occupied),
        run.quality.coverage / std::max(1e-9, reference.coverage), run.ms_per_frame,
        run.cache_hit_rate);
  }
  if (args.has("images")) {
    std::vector<cv::Mat> panels;
    for (const Run& run : runs) panels.push_back(topView(run, scene, resolution, poses));
    cv::Mat stacked;
    cv::vconcat(panels, stacked);
    writeImage(args.value("images") + "/disparity_artifacts_top.png", stacked);
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

int runDisparityArtifacts(const CommandLine& args) {
  const VisibilityStereoConfig config = configFrom(args);
  const std::string part = args.value("part", "all");
  if (part != "all" && part != "artifacts" && part != "fig5a") {
    throw UsageError("--part must be all, artifacts or fig5a");
  }
  if (part != "fig5a") runArtifacts(args, config);
  if (part != "artifacts") runFig5a(args, config);
  return 0;
}

}  // namespace occupancy_fusion
