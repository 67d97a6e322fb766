// benchmark spill: a long run through a building much larger than the map's memory bound. A
// depth camera moves along a corridor with a room every 8 m (alternately left and right, a door,
// an object inside; a pillar in every other segment), swinging its view into the rooms; the
// PyramidDepthIntegrator maps it into a VoxelMap with or without a bound (--bound_mb, with
// --spill_folder: evicted blocks spill to the store). Per frame (--csv): the integration time,
// the process's resident memory (anonymous, and file-backed: LMDB's mapped pages, which the
// system can drop), the map's own accounting and its blocks in memory and in the store. At the
// end the map is saved (--save PREFIX: PREFIX.ot, streamed from the blocks; with
// --save_liboctomap 1 also through liboctomap's OcTree, for comparison), so that a bounded run and
// an unbounded one can be compared byte for byte, and the save's peak memory is reported. The
// building is generated per frame around the camera (segments near it only), so rendering costs the
// same at the first metre and the thousandth. With --laser 1 (the default) a 270 deg scanner 0.3 m
// above the floor maps the same corridor into the 2D laser layer (bounded by --layer_bound_mb
// with the same store); its time per scan, memory and spilled tiles are reported, and --save
// writes PREFIX.laser.npy / .yaml as well.
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "occupancy_fusion/benchmarks/benchmark_harness.h"
#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"
#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"
#include "occupancy_fusion/map/layer_files.h"
#include "occupancy_fusion/map/map_checkpoints.h"
#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/map/octomap_conversion.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/laser_scanner.h"
#include "occupancy_fusion/sim/scene.h"
#include "occupancy_fusion/sim/trajectory.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

using bench::Clock;
using bench::millisecondsSince;

constexpr double kSegment = 8.0;       // m of corridor per room
constexpr double kHalfWidth = 1.2;     // m, the corridor's half width
constexpr double kHeight = 2.6;        // m
constexpr double kRoomDepth = 4.0;     // m
constexpr double kWall = 0.2;          // m, wall thickness
constexpr double kCameraHeight = 1.2;  // m

// A number in [0, 1) from a segment index and a salt: the same building on every run.
double hashed(long segment, int salt) {
  std::uint64_t x =
      static_cast<std::uint64_t>(segment) * 0x9e3779b97f4a7c15ULL + salt * 0xbf58476dULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  x ^= x >> 31;
  return static_cast<double>(x >> 11) / static_cast<double>(1ULL << 53);
}

sim::Box box(double x0, double y0, double z0, double x1, double y1, double z1) {
  return sim::Box::axisAligned({x0, y0, z0}, {x1, y1, z1});
}

// Segment k spans x in [8k, 8k + 8): floor, ceiling, both corridor walls, the room on side
// (-1)^k with its door, an object in the room, and in odd segments a pillar in the corridor.
void addSegment(long k, sim::Scene* scene) {
  const double x0 = kSegment * static_cast<double>(k), x1 = x0 + kSegment;
  const double side = k % 2 == 0 ? 1.0 : -1.0;
  const double far = kHalfWidth + kRoomDepth + 2 * kWall;
  scene->add(box(x0, -far, -kWall, x1, far, 0.0));               // floor
  scene->add(box(x0, -far, kHeight, x1, far, kHeight + kWall));  // ceiling
  // The plain wall on the other side.
  const double plain = -side * kHalfWidth;
  scene->add(box(x0, std::min(plain, plain - side * kWall), 0.0, x1,
                 std::max(plain, plain - side * kWall), kHeight));
  // The room's side: the corridor wall with a door 1.2 m wide at a hashed place.
  const double door = x0 + 1.0 + 4.5 * hashed(k, 1);
  const double wall_in = side * kHalfWidth, wall_out = side * (kHalfWidth + kWall);
  const double y_lo = std::min(wall_in, wall_out), y_hi = std::max(wall_in, wall_out);
  scene->add(box(x0, y_lo, 0.0, door, y_hi, kHeight));
  scene->add(box(door + 1.2, y_lo, 0.0, x1, y_hi, kHeight));
  scene->add(box(door, y_lo, 2.1, door + 1.2, y_hi, kHeight));  // above the door
  // The room: its back wall and the walls to the neighbouring rooms.
  const double back_in = side * (kHalfWidth + kWall + kRoomDepth), back_out = side * far;
  scene->add(box(x0, std::min(back_in, back_out), 0.0, x1, std::max(back_in, back_out), kHeight));
  const double room_lo = std::min(wall_out, back_in), room_hi = std::max(wall_out, back_in);
  scene->add(box(x0, room_lo, 0.0, x0 + kWall, room_hi, kHeight));
  // An object in the room: a cabinet or a table-sized block.
  const double size_x = 0.4 + 0.8 * hashed(k, 2), size_y = 0.4 + 0.8 * hashed(k, 3);
  const double height = 0.5 + 1.3 * hashed(k, 4);
  const double cx = x0 + 1.0 + (kSegment - 2.0 - size_x) * hashed(k, 5);
  const double cy = side * (kHalfWidth + kWall + 0.5 + (kRoomDepth - 1.0 - size_y) * hashed(k, 6));
  scene->add(box(cx, cy - size_y / 2, 0.0, cx + size_x, cy + size_y / 2, height));
  if (k % 2 == 1) {
    const double px = x0 + 1.0 + 6.0 * hashed(k, 7);
    scene->add(box(px, side * 0.7 - 0.15, 0.0, px + 0.3, side * 0.7 + 0.15, kHeight));
  }
}

sim::Scene buildingAround(double x, double max_range) {
  sim::Scene scene;
  const long first = static_cast<long>(std::floor((x - max_range) / kSegment));
  const long last = static_cast<long>(std::floor((x + max_range) / kSegment));
  for (long k = first; k <= last; ++k) addSegment(k, &scene);
  return scene;
}

// The camera at metre x of the corridor, 1.2 m high, its view swinging 55 deg to either side
// once per segment and tilted 8 deg down; looking back along the corridor when `back`.
Eigen::Isometry3d cameraAt(double x, bool back) {
  const double yaw =
      55.0 * M_PI / 180.0 * std::sin(2.0 * M_PI * x / kSegment) + (back ? M_PI : 0.0);
  const Eigen::Vector3d eye(x, 0.0, kCameraHeight);
  const Eigen::Vector3d view(std::cos(yaw), std::sin(yaw), -std::tan(8.0 * M_PI / 180.0));
  return sim::lookAt(eye, eye + view);
}

struct ResidentMemory {
  double anonymous_mb = 0, file_mb = 0;
};
ResidentMemory residentMemory() {
  ResidentMemory memory;
  std::ifstream status("/proc/self/status");
  std::string key;
  double kb = 0;
  std::string unit;
  while (status >> key) {
    if (key == "RssAnon:" && status >> kb >> unit) memory.anonymous_mb = kb / 1024.0;
    if (key == "RssFile:" && status >> kb >> unit) memory.file_mb = kb / 1024.0;
  }
  return memory;
}

// The largest anonymous resident memory while `work` runs, sampled every 5 ms on a thread of its
// own (the process's high-water mark would hold the run's peak, not the save's).
template <typename Work>
double peakAnonymousMbDuring(Work work) {
  std::atomic<bool> done{false};
  double peak = residentMemory().anonymous_mb;
  std::thread sampler([&] {
    while (!done.load()) {
      peak = std::max(peak, residentMemory().anonymous_mb);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  });
  try {
    work();
  } catch (...) {
    done = true;
    sampler.join();
    throw;
  }
  done = true;
  sampler.join();
  return std::max(peak, residentMemory().anonymous_mb);
}

// PREFIX.ot streamed from the blocks (what ~save_map and offline_mapper do), and with
// --save_liboctomap 1 also PREFIX.liboctomap.ot through liboctomap's OcTree (toOcTree, write),
// for the time and memory of both and whether their bytes agree.
void saveAndMeasure(const VoxelMap& map, const std::string& prefix, bool liboctomap_too) {
  const double before = residentMemory().anonymous_mb;
  auto start = Clock::now();
  const double streamed_peak = peakAnonymousMbDuring([&] { writeOt(map, prefix + ".ot"); });
  const double streamed_s = millisecondsSince(start) / 1000.0;
  std::printf(
      "saved %s.ot (streamed) in %.1f s, resident (anonymous) before %.1f MiB, peak during the "
      "save %.1f MiB\n",
      prefix.c_str(), streamed_s, before, streamed_peak);
  if (!liboctomap_too) return;
  start = Clock::now();
  const double tree_peak = peakAnonymousMbDuring([&] {
    const std::unique_ptr<octomap::OcTree> tree = toOcTree(map);
    std::ofstream out(prefix + ".liboctomap.ot", std::ios::binary);
    if (!tree->write(out)) throw std::runtime_error("liboctomap could not write the tree");
  });
  const double tree_s = millisecondsSince(start) / 1000.0;
  std::ifstream a(prefix + ".ot", std::ios::binary), b(prefix + ".liboctomap.ot", std::ios::binary);
  const bool same = std::equal(std::istreambuf_iterator<char>(a), std::istreambuf_iterator<char>(),
                               std::istreambuf_iterator<char>(b), std::istreambuf_iterator<char>());
  std::printf(
      "saved %s.liboctomap.ot (liboctomap OcTree) in %.1f s, peak during the save %.1f MiB; "
      "streamed / liboctomap: time %.2f, peak memory above the map %.3f; bytes %s\n",
      prefix.c_str(), tree_s, tree_peak, streamed_s / tree_s,
      (streamed_peak - before) / std::max(tree_peak - before, 1e-9), same ? "equal" : "DIFFERENT");
}

}  // namespace

int runSpill(const CommandLine& args) {
  const double length = args.doubleValue("length", 100.0);
  const double step = args.doubleValue("step", 0.1);
  const double resolution = args.doubleValue("resolution", 0.05);
  const double bound_mb = args.doubleValue("bound_mb", 0.0);
  // --return 1: the camera comes back the way it went, looking back: every block it wrote on the
  // way out is written again (paged in from the store under a bound).
  const bool comes_back = args.intValue("return", 0) != 0;
  if (!(length > 0) || !(step > 0) || !(resolution > 0) || !(bound_mb >= 0)) {
    throw UsageError("--length, --step and --resolution must be positive, --bound_mb >= 0");
  }
  const double max_range = 5.0;
  sim::PinholeCamera camera;
  camera.width = args.intValue("width", 320);
  camera.height = args.intValue("height", 240);
  camera.fx = camera.fy = 0.8 * camera.width;
  camera.cx = 0.5 * (camera.width - 1);
  camera.cy = 0.5 * (camera.height - 1);
  PyramidDepthConfig depth;  // a depth camera's centimetre noise, as benchmark depth
  depth.k = 0.05;
  depth.sigma = 0.05;
  depth.max_range = max_range;
  const PyramidDepthIntegrator integrator(depth);
  VoxelMapConfig config;
  config.resolution = resolution;
  config.max_memory_bytes = static_cast<std::size_t>(bound_mb * 1024.0 * 1024.0);
  config.spill_folder = args.value("spill_folder", "");
  const double layer_bound_mb = args.doubleValue("layer_bound_mb", 0.0);
  if (!(layer_bound_mb >= 0)) throw UsageError("--layer_bound_mb must be >= 0");
  config.layer_max_memory_bytes = static_cast<std::size_t>(layer_bound_mb * 1024.0 * 1024.0);
  VoxelMap map(config);
  if (config.max_memory_bytes > 0 && !config.spill_folder.empty() && !map.spillStatus().enabled) {
    throw UsageError("the spill store did not open: " + map.spillStatus().last_error);
  }
  const bool laser = args.intValue("laser", 1) != 0;
  GridLayer2D layer(laserLayerConfig(config));
  const MapCheckpoints layer_store(&map, &layer);  // gives the layer the map's store
  PolarLaserIntegrator laser_integrator;
  sim::LaserScanner scanner;
  scanner.angle_min = -0.75 * M_PI;
  scanner.angle_max = 0.75 * M_PI;
  scanner.range_max = max_range;  // the building exists this far around the camera
  scanner.noise_sigma = 0.01;
  std::FILE* csv = nullptr;
  if (args.has("csv")) {
    csv = std::fopen(args.value("csv").c_str(), "w");
    if (csv == nullptr) throw UsageError("cannot write " + args.value("csv"));
    std::fprintf(csv,
                 "frame,travelled_m,integrate_ms,rss_anon_mb,rss_file_mb,map_mb,blocks_in_memory,"
                 "blocks_spilled,laser_ms,layer_mb\n");
  }
  const int frames = static_cast<int>(length / step) * (comes_back ? 2 : 1);
  std::printf(
      "# spill: %d frames, %.0f m%s at %.2f m a frame, %dx%d depth camera, %.3f m voxels, "
      "bound %.1f MiB%s, threads %d\n",
      frames, length, comes_back ? " and back" : "", step, camera.width, camera.height, resolution,
      bound_mb, config.spill_folder.empty() ? "" : (", store " + config.spill_folder).c_str(),
      omp_get_max_threads());
  std::vector<double> times, laser_times;
  double peak_anon = 0;
  auto last_progress = Clock::now();
  for (int frame = 0; frame < frames; ++frame) {
    const double travelled = frame * step;
    const bool back = travelled >= length;
    const double x = back ? 2.0 * length - travelled : travelled;
    const sim::Scene scene = buildingAround(x, max_range + 1.0);
    const Eigen::Isometry3d pose = cameraAt(x, back);
    const sim::DepthImage image = sim::renderDepth(scene, camera, pose, max_range);
    const DepthImageView view{image.width, image.height, image.depth.data(), 0};
    const auto start = Clock::now();
    integrator.integrate(view, camera, pose, &map);
    const double ms = millisecondsSince(start);
    times.push_back(ms);
    double laser_ms = 0;
    if (laser) {
      const double heading = back ? M_PI : 0.0;
      const Eigen::Isometry3d scanner_pose =
          Eigen::Translation3d(x, 0.0, 0.3) * Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ());
      const LaserScan scan = toLaserScan(sim::renderScan(scene, scanner, scanner_pose, frame));
      const auto laser_start = Clock::now();
      laser_integrator.integrateIntoLayer(scan, Pose2D{x, 0.0, heading}, &layer);
      laser_ms = millisecondsSince(laser_start);
      laser_times.push_back(laser_ms);
    }
    const ResidentMemory memory = residentMemory();
    peak_anon = std::max(peak_anon, memory.anonymous_mb);
    const VoxelMap::StorageStats stats = map.storageStats();
    if (csv != nullptr) {
      std::fprintf(csv, "%d,%.2f,%.3f,%.1f,%.1f,%.1f,%zu,%zu,%.3f,%.2f\n", frame, travelled, ms,
                   memory.anonymous_mb, memory.file_mb, map.memoryBytes() / 1048576.0,
                   stats.dense_blocks + stats.sparse_blocks, stats.spilled_blocks, laser_ms,
                   layer.memoryBytes() / 1048576.0);
    }
    if (millisecondsSince(last_progress) > 10000) {
      last_progress = Clock::now();
      std::fprintf(stderr, "spill: %d / %d frames, %.0f m, resident %.0f MiB, map %.0f MiB\n",
                   frame + 1, frames, x, memory.anonymous_mb, map.memoryBytes() / 1048576.0);
    }
  }
  if (csv != nullptr) std::fclose(csv);
  std::vector<double> sorted = times;
  std::sort(sorted.begin(), sorted.end());
  double mean = 0;
  for (double t : times) mean += t / static_cast<double>(times.size());
  const SpillStatus status = map.spillStatus();
  std::printf(
      "spill length_m=%.0f bound_mb=%.1f frames=%d integrate_ms_mean=%.2f "
      "integrate_ms_median=%.2f integrate_ms_p99=%.2f peak_rss_anon_mb=%.1f "
      "map_mb=%.1f blocks=%zu spilled=%zu blocks_written=%zu paged_in=%zu "
      "read_ahead=%zu read_under_lock=%zu failures=%zu evicted=%zu known_voxels=%zu\n",
      length, bound_mb, frames, mean, sorted[sorted.size() / 2],
      sorted[std::min(sorted.size() - 1, sorted.size() * 99 / 100)], peak_anon,
      map.memoryBytes() / 1048576.0, map.blockCount(), status.spilled_blocks, status.blocks_written,
      status.blocks_paged_in, status.blocks_read_ahead, status.blocks_read_under_lock,
      status.failures, map.evictedBlockCount(), map.knownVoxelCount());
  if (laser) {
    double laser_mean = 0;
    for (double t : laser_times) laser_mean += t / static_cast<double>(laser_times.size());
    const TileSpillStatus tiles = layer.spillStatus();
    std::printf(
        "spill_layer bound_mb=%.2f laser_ms_mean=%.3f layer_mb=%.2f tiles=%zu spilled_tiles=%zu "
        "tiles_written=%zu tiles_paged_in=%zu failures=%zu known_cells=%zu\n",
        layer_bound_mb, laser_mean, layer.memoryBytes() / 1048576.0, layer.tileCount(),
        tiles.spilled_tiles, tiles.tiles_written, tiles.tiles_paged_in, tiles.failures,
        layer.knownCellCount());
  }
  if (args.has("save")) {
    saveAndMeasure(map, args.value("save"), args.intValue("save_liboctomap", 0) != 0);
    if (laser) writeLayerFiles(layer, args.value("save"));
  }
  return 0;
}

}  // namespace occupancy_fusion
