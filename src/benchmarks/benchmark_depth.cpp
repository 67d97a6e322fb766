// benchmark depth: the pyramidal depth integrator (Pirker et al.) on a recorded depth sequence
// in the 7-Scenes layout, against octomap::OcTree::insertPointCloud on the same frames.
#include <octomap/OcTree.h>
#include <omp.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "occupancy_fusion/benchmarks/benchmark_harness.h"
#include "occupancy_fusion/benchmarks/peer_mappers.h"
#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"
#include "occupancy_fusion/map/occupancy_model.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/sensors/seven_scenes_folder.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

using bench::Clock;
using bench::millisecondsSince;
using bench::processCpuMilliseconds;

// The frame's valid pixels as world points, the way a point-cloud mapper would receive them.
octomap::Pointcloud worldPoints(const SevenScenesFrame& frame, const CameraIntrinsics& camera) {
  octomap::Pointcloud cloud;
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const float z = frame.depth[static_cast<std::size_t>(v) * camera.width + u];
      if (!(z > 0.0f)) continue;
      const Eigen::Vector3d p = frame.T_world_camera * (camera.pixelRay(u, v) * z);
      cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                      static_cast<float>(p.z()));
    }
  }
  return cloud;
}

// The map's occupied voxels seen by a virtual pinhole camera: `view` is the first frame's pose
// pulled back 1.5 m along its optical axis. Each voxel is a z-buffered square of its projected
// size, coloured by its height along the view's image-up axis and darkened with distance.
cv::Mat renderOccupied(const VoxelMap& map, const CameraIntrinsics& camera,
                       const Eigen::Isometry3d& first_pose) {
  Eigen::Isometry3d view = first_pose;
  view.translation() -= 1.5 * first_pose.linear().col(2);
  const Eigen::Isometry3d T_view_map = view.inverse();
  std::vector<Eigen::Vector3d> points;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    if (map.classify(log_odds) == Occupancy::kOccupied) {
      points.push_back(T_view_map * map.centerOf(index));
    }
  });
  double y_min = std::numeric_limits<double>::infinity(), y_max = -y_min;
  for (const Eigen::Vector3d& p : points)
    y_min = std::min(y_min, p.y()), y_max = std::max(y_max, p.y());
  cv::Mat depth(camera.height, camera.width, CV_32F, cv::Scalar(1e9f));
  cv::Mat height(camera.height, camera.width, CV_8U, cv::Scalar(0));
  for (const Eigen::Vector3d& p : points) {
    if (p.z() <= 0.1) continue;
    const Eigen::Vector2d uv = camera.project(p);
    const int half =
        std::max(1, static_cast<int>(0.5 * camera.fx * map.resolution() / p.z() + 0.5));
    const int u0 = std::max(0, static_cast<int>(uv.x()) - half);
    const int u1 = std::min(camera.width - 1, static_cast<int>(uv.x()) + half);
    const int v0 = std::max(0, static_cast<int>(uv.y()) - half);
    const int v1 = std::min(camera.height - 1, static_cast<int>(uv.y()) + half);
    // Image y points down: high voxels (small y) get the high end of the colour map.
    const auto level =
        static_cast<std::uint8_t>(255.0 * (y_max - p.y()) / std::max(y_max - y_min, 1e-6));
    for (int v = v0; v <= v1; ++v) {
      for (int u = u0; u <= u1; ++u) {
        if (p.z() < depth.at<float>(v, u)) {
          depth.at<float>(v, u) = static_cast<float>(p.z());
          height.at<std::uint8_t>(v, u) = level;
        }
      }
    }
  }
  cv::Mat image;
  cv::applyColorMap(height, image, cv::COLORMAP_JET);
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const float z = depth.at<float>(v, u);
      cv::Vec3b& pixel = image.at<cv::Vec3b>(v, u);
      if (z > 1e8f) {
        pixel = cv::Vec3b(255, 255, 255);
        continue;
      }
      const double shade = std::clamp(1.3 - 0.25 * z, 0.35, 1.0);
      for (int c = 0; c < 3; ++c) pixel[c] = static_cast<std::uint8_t>(pixel[c] * shade);
    }
  }
  return image;
}

// A sum over voxels of a mixed hash of (index, log-odds bits): equal for bit-identical maps
// whatever the iteration order, so code changes that must not change results can be checked.
std::uint64_t mapHash(const VoxelMap& map) {
  std::uint64_t sum = 0;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &log_odds, sizeof(bits));
    std::uint64_t h = bits;
    for (int axis = 0; axis < 3; ++axis) {
      h = (h ^ static_cast<std::uint32_t>(index[axis])) * 0x9E3779B97F4A7C15ULL;
      h ^= h >> 29;
    }
    sum += h;
  });
  return sum;
}

struct OursResult {
  double median_ms = 0.0;
  double updates_per_second = 0.0;
  double memory_mb = 0.0;
  // The whole run's CPU (every thread) over its frames. A frame's own CPU reading misses most of
  // the other threads' time: the kernel adds a running thread's time to the process clock at its
  // ticks and switches, and a 1-3 ms frame often sees none (half the true CPU at 0.08 m).
  double cpu_ms = 0.0;
  std::uint64_t map_hash = 0;  // of every voxel's index and log-odds bits, order-free
};

// image_path: when not empty, the final map's occupied voxels are rendered there (PNG).
OursResult runOurs(const std::vector<SevenScenesFrame>& frames, const CameraIntrinsics& camera,
                   const PyramidDepthIntegrator& integrator, double resolution,
                   const std::string& image_path) {
  VoxelMapConfig map_config;
  map_config.resolution = resolution;
  VoxelMap map(map_config);
  std::vector<double> frame_ms;
  double total_ms = 0.0;
  std::size_t updates = 0;
  const double run_cpu_start = processCpuMilliseconds();
  for (const SevenScenesFrame& frame : frames) {
    const auto start = Clock::now();
    const DepthIntegrationStats stats =
        integrator.integrate(frame.view(camera), camera, frame.T_world_camera, &map);
    frame_ms.push_back(millisecondsSince(start));
    total_ms += frame_ms.back();
    // Skipped no-ops (clamped free in front of every surface) are updates of the method too.
    updates += stats.voxels_updated + stats.voxels_unchanged;
  }
  if (!image_path.empty() &&
      !cv::imwrite(image_path, renderOccupied(map, camera, frames.front().T_world_camera))) {
    throw UsageError("cannot write --image " + image_path);
  }
  const double cpu_ms =
      (processCpuMilliseconds() - run_cpu_start) / static_cast<double>(frames.size());
  return {bench::median(frame_ms), updates / (total_ms * 1e-3), map.memoryBytes() * 1e-6, cpu_ms,
          mapHash(map)};
}

// A cloud for the peers (benchmarks/peer_mappers.h).
std::vector<Eigen::Vector3f> eigenCloud(const octomap::Pointcloud& cloud) {
  std::vector<Eigen::Vector3f> result;
  result.reserve(cloud.size());
  for (const octomap::point3d& p : cloud) result.emplace_back(p.x(), p.y(), p.z());
  return result;
}

// `count` frame numbers of `total`, evenly spread from the first.
std::vector<std::size_t> spreadOver(int count, std::size_t total) {
  std::vector<std::size_t> result;
  for (int i = 0; i < count; ++i) result.push_back(i * total / count);
  return result;
}

// Median milliseconds per insertPointCloud call and the tree's memory.
std::pair<double, double> runOctomap(const std::vector<octomap::Pointcloud>& clouds,
                                     const std::vector<Eigen::Vector3d>& origins, double resolution,
                                     bool discretize) {
  octomap::OcTree tree = bench::makeOctomapTree(resolution);
  std::vector<double> frame_ms;
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    const octomap::point3d origin(origins[i].x(), origins[i].y(), origins[i].z());
    const auto start = Clock::now();
    tree.insertPointCloud(clouds[i], origin, -1.0, false, discretize);
    frame_ms.push_back(millisecondsSince(start));
  }
  return {bench::median(frame_ms), tree.memoryUsage() * 1e-6};
}

}  // namespace

int runDepth(const CommandLine& args) {
  const SevenScenesFolder folder(args.required("folder"));
  const std::vector<double> resolutions = bench::parsePositiveList<double>(
      "resolution", args.value("resolution", "0.02,0.04,0.08,0.16"));
  const int frame_limit = args.intValue("frames", static_cast<int>(folder.size()));
  const int octomap_frames = args.intValue("octomap-frames", 2);
  const int peer_frames = args.intValue("peer-frames", frame_limit);
  const std::string image_path = args.value("image", "");
  if (frame_limit < 1 || octomap_frames < 0 || peer_frames < 0) {
    throw UsageError("--frames must be >= 1, --octomap-frames and --peer-frames >= 0");
  }
  // A Kinect's noise is centimetres at 1-3 m: the paper's k = sigma = 0.6 shape, scaled.
  PyramidDepthConfig config;
  config.k = args.doubleValue("k", 0.05);
  config.sigma = args.doubleValue("sigma", 0.05);
  config.sigma_quadratic = args.doubleValue("sigma_quadratic", 0.0);
  config.method = depthMethodFromString(args.value("method", "pyramid"));
  config.finer_layers = args.intValue("finer_layers", 0);
  config.clear_passed = args.intValue("clear_passed", 0) != 0;  // not the paper unless 0
  const PyramidDepthIntegrator integrator(config);

  const CameraIntrinsics& camera = folder.camera();
  std::vector<SevenScenesFrame> frames;
  for (std::size_t i = 0; i < std::min<std::size_t>(folder.size(), frame_limit); ++i) {
    frames.push_back(folder.frame(i));
  }
  // liboctomap is slow at fine resolutions: every step-th frame, spread over the sequence. The
  // peers take every frame by default, as a camera streams them (consecutive frames overlap, so
  // most of a frame's voxels are in the map already).
  const int octomap_count = std::min<int>(octomap_frames, static_cast<int>(frames.size()));
  std::vector<octomap::Pointcloud> clouds;
  std::vector<Eigen::Vector3d> origins;
  for (std::size_t f : spreadOver(octomap_count, frames.size())) {
    clouds.push_back(worldPoints(frames[f], camera));
    origins.push_back(frames[f].T_world_camera.translation());
  }
  // No clouds for peers that are not compiled in.
  const int peer_count = bench::compiledPeers().empty()
                             ? 0
                             : std::min<int>(peer_frames, static_cast<int>(frames.size()));
  const std::vector<std::size_t> peer_cloud_frames = spreadOver(peer_count, frames.size());
  std::vector<std::vector<Eigen::Vector3f>> peer_clouds;
  std::vector<Eigen::Vector3d> peer_origins;
  for (std::size_t f : peer_cloud_frames) {
    peer_clouds.push_back(eigenCloud(worldPoints(frames[f], camera)));
    peer_origins.push_back(frames[f].T_world_camera.translation());
  }
  std::string peers;
  for (const std::string& name : bench::compiledPeers()) peers += (peers.empty() ? "" : ",") + name;
  std::printf(
      "# peers on the same clouds: %s\n",
      peers.empty() ? "none (configure with -DBONXAI_ROOT / -DUFOMAP_ROOT)" : peers.c_str());
  const int threads = omp_get_max_threads();
  std::printf(
      "# %zu frames of %dx%d, fx=%g; method=%s k=%g sigma=%g sigma_quadratic=%g "
      "finer_layers=%d threads=%d; octomap on %d of the frames (--octomap-frames), the peers "
      "on %zu (--peer-frames), max_range unlimited\n",
      frames.size(), camera.width, camera.height, camera.fx, toString(config.method).c_str(),
      config.k, config.sigma, config.sigma_quadratic, config.finer_layers, threads, octomap_count,
      peer_clouds.size());
  std::fflush(stdout);

  std::vector<std::string> summary;
  for (double resolution : resolutions) {
    omp_set_num_threads(threads);  // insertPointCloud may have changed it
    // The picture shows the first (finest) resolution's map.
    const OursResult ours = runOurs(frames, camera, integrator, resolution,
                                    resolution == resolutions.front() ? image_path : "");
    std::pair<double, double> plain{0.0, 0.0}, discretized{0.0, 0.0};
    if (octomap_count > 0) {
      plain = runOctomap(clouds, origins, resolution, false);
      discretized = runOctomap(clouds, origins, resolution, true);
    }
    std::string peer_fields;
    if (!peer_clouds.empty()) {
      omp_set_num_threads(threads);  // for ours in the pairs, after liboctomap
      // Paired: the frame each peer cloud came from, into a map of ours that sees only those.
      std::unique_ptr<VoxelMap> paired_map;
      const bench::PairedInsert paired = [&](std::size_t i) {
        if (i == 0 || paired_map == nullptr) {
          VoxelMapConfig map_config;
          map_config.resolution = resolution;
          paired_map = std::make_unique<VoxelMap>(map_config);
        }
        const SevenScenesFrame& frame = frames[peer_cloud_frames[i]];
        const auto start = Clock::now();
        integrator.integrate(frame.view(camera), camera, frame.T_world_camera, paired_map.get());
        return millisecondsSince(start);
      };
      for (const bench::PeerRun& peer :
           bench::runPeers(peer_clouds, peer_origins, resolution, paired)) {
        char field[300];
        std::snprintf(field, sizeof(field),
                      " %s_ms_per_frame=%.2f speedup_%s=%.1f paired_speedup_%s=%.1f "
                      "%s_memory_mb=%.1f %s_cpu_ms_per_frame=%.2f cpu_ratio_%s=%.3f",
                      peer.name.c_str(), peer.median_ms, peer.name.c_str(),
                      peer.median_ms / ours.median_ms, peer.name.c_str(), 1.0 / peer.paired_ratio,
                      peer.name.c_str(), peer.memory_mb, peer.name.c_str(), peer.cpu_ms,
                      peer.name.c_str(), ours.cpu_ms / peer.cpu_ms);
        peer_fields += field;
      }
      omp_set_num_threads(threads);
    }
    char line[1024];
    std::snprintf(line, sizeof(line),
                  "depth resolution=%g frames=%zu ms_per_frame=%.2f octomap_ms_per_frame=%.1f "
                  "speedup=%.1f memory_mb=%.1f octomap_discretize_ms_per_frame=%.1f "
                  "speedup_discretize=%.1f octomap_frames=%d octomap_memory_mb=%.1f "
                  "voxel_updates_per_s=%.3g threads=%d cpu_ms_per_frame=%.2f map_hash=%016llx",
                  resolution, frames.size(), ours.median_ms, plain.first,
                  plain.first / ours.median_ms, ours.memory_mb, discretized.first,
                  discretized.first / ours.median_ms, octomap_count, plain.second,
                  ours.updates_per_second, threads, ours.cpu_ms,
                  static_cast<unsigned long long>(ours.map_hash));
    std::string full_line = line + peer_fields;
    std::printf("# %s\n", full_line.c_str());
    std::fflush(stdout);
    summary.push_back(full_line);
  }
  for (const std::string& line : summary) std::printf("%s\n", line.c_str());
  return 0;
}

}  // namespace occupancy_fusion
