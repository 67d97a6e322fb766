// offline_mapper: maps a recording without a ROS master, with the same YAML parameters as the
// mapper nodelets, and writes the map files. See usage() below.
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "occupancy_fusion/mapping/map_saving.h"
#include "occupancy_fusion/mapping/mapping_session.h"
#include "occupancy_fusion/mapping/submap_files.h"
#include "occupancy_fusion/tools/command_line.h"
#include "occupancy_fusion/tools/file_readers.h"
#include "occupancy_fusion/tools/map_outputs.h"
#include "occupancy_fusion/tools/rosbag_reader.h"
#include "occupancy_fusion/tools/tool_main.h"
#include "occupancy_fusion/tools/voxel_picture.h"
#include "occupancy_fusion/tools/yaml_parameter_source.h"

namespace occupancy_fusion {
namespace {

const char* const kUsage =
    R"(usage: offline_mapper --config FILE.yaml --output-dir DIR INPUT... [options]

Maps recorded sensor data (no ROS master needed) into one map: a 3D voxel map (point clouds,
depth images, disparity images) and a 2D laser layer (laser scans) by the mapper nodelets' own
message conversions and mapping rules, so a bag gives the map the nodelets build from it live.
Writes DIR/NAME.ot, .bt (OctoMap), .pcd (every known voxel with its occupancy
probability), .pgm + .yaml (map_server files of the fused 2D view: the voxels within
occupancy_min_z..occupancy_max_z and the laser layer), .npy (per-column log-odds behind the 2D
view), .png (a picture of the 2D view, y up), .laser.npy + .laser.yaml (the laser layer, which
the MapServer's load_map resumes with the .ot) and NAME_voxels.png (the occupied voxels in 3D,
seen obliquely, coloured by height; only when some voxel is occupied): the MapServer's ~save_map
files, written by the same saver, and the rest for inspection; nothing when nothing was mapped.
A progress line (frames per sensor kind, elapsed time, rate) is printed every two seconds, and a
summary at the end.

Inputs (at least one; any mix, each repeatable):
  --bag FILE           rosbag; several bags are merged in time order and share their tf.
                       Poses come from /tf and /tf_static; a frame whose transform to frame_id
                       is not available is skipped and counted.
  --depth-folder DIR   depth images in the 7-Scenes layout (camera-intrinsics.txt,
                       [frames/]frame-NNNNNN.depth.png in mm, frame-NNNNNN.pose.txt
                       camera-to-world), world frame = map frame
  --middlebury-folder DIR  disparity maps in the Middlebury layout (calib.txt, disp0*.pfm,
                       optional pose0*.txt camera-to-world; without one the camera is at the
                       origin), or a folder of such scene folders
  --carmen FILE        CARMEN log (.gz accepted): FLASER lines with their corrected poses
Topics of the bags (default, when none is given: every topic of a supported type; an Image
topic counts when its first message is 16UC1, mono16 or 32FC1):
  --cloud-topic TOPIC      sensor_msgs/PointCloud2
  --depth-topic TOPIC      sensor_msgs/Image (16UC1 mm or 32FC1 m) with .../camera_info beside it
  --disparity-topic TOPIC  stereo_msgs/DisparityImage with .../camera_info or .../left/camera_info
  --scan-topic TOPIC       sensor_msgs/LaserScan
  --path-topic TOPIC       nav_msgs/Path of a SLAM system's keyframes, for the map to follow
                           (with the parameter reanchoring/source: path; never chosen by default)
Parameters and output:
  --config FILE        YAML parameters, as loaded by rosparam into a mapper nodelet; repeat
                       to merge several files as successive rosparam loads (later ones win),
                       e.g. point_cloud_mapper.yaml, depth_mapper.yaml, disparity_mapper.yaml,
                       laser_mapper.yaml, then map_server.yaml for the 2D band. Depth keys live
                       under depth/, stereo keys under stereo/, laser keys under laser/.
  --namespace NS       take the parameters from section NS of each file (e.g. a node name)
  --set KEY=VALUE      override one parameter, e.g. --set sensor_model/max_range=4 (repeatable)
  --output-dir DIR     where the map files go (created if needed)
  --load-map FILE      start from a saved map instead of an empty one: a .ot (every log-odds)
                       or .bt (labels) of the map's resolution, and the laser layer from the
                       .laser.yaml / .laser.npy beside it when present (as the MapServer's
                       load_map; what this tool and ~save_map write)
  --name NAME          base name of the map files (default: map)
  --carmen-max-scans N read at most N scans of each CARMEN log (default: all)
  --single-scan N      also write the grid of laser scan N alone (0-based, in reading order) in
                       its sensor's frame: NAME_scan.npy (log-ratios), .pgm + .yaml, .png; a
                       60 m x 30 m grid at the map's resolution, the sensor at the middle of
                       the lower long edge facing into it (Yguel et al.'s Table I setup)
  --voxel-picture-max-z Z  leave voxels above Z m out of NAME_voxels.png (e.g. a ceiling)
  --quiet              no progress lines
  --help               this text
Exit status: 0 done, 2 bad arguments, parameters or input files, 1 failure while mapping
(including a recording none of whose frames could be placed).
)";

struct Options {
  std::vector<std::string> config_paths;
  std::string config_namespace;
  std::vector<std::string> overrides;
  std::vector<std::string> bag_paths;
  RosbagTopics topics;
  std::vector<std::string> depth_folders;
  std::vector<std::string> middlebury_folders;
  std::vector<std::string> carmen_logs;
  int carmen_max_scans = 0;
  int single_scan = -1;              // none
  double voxel_picture_max_z = 1e9;  // m
  std::string output_dir;
  std::string name;
  std::string load_map;  // empty: start with an empty map
  bool quiet = false;
};

void requireExisting(const std::vector<std::string>& paths, bool folders) {
  for (const std::string& path : paths) {
    const bool exists =
        folders ? std::filesystem::is_directory(path) : std::filesystem::is_regular_file(path);
    if (!exists)
      throw UsageError(std::string(folders ? "no such folder: " : "no such file: ") + path);
  }
}

Options parseOptions(const CommandLine& line) {
  Options options;
  line.required("config");
  options.config_paths = line.values("config");
  options.config_namespace = line.value("namespace");
  options.overrides = line.values("set");
  options.bag_paths = line.values("bag");
  options.topics.clouds = line.values("cloud-topic");
  options.topics.depth_images = line.values("depth-topic");
  options.topics.disparity_images = line.values("disparity-topic");
  options.topics.scans = line.values("scan-topic");
  options.topics.paths = line.values("path-topic");
  options.depth_folders = line.values("depth-folder");
  options.middlebury_folders = line.values("middlebury-folder");
  options.carmen_logs = line.values("carmen");
  options.carmen_max_scans = line.intValue("carmen-max-scans", 0);
  options.single_scan = line.intValue("single-scan", -1);
  options.output_dir = line.required("output-dir");
  options.name = line.value("name", "map");
  options.load_map = line.value("load-map", "");
  options.quiet = line.has("quiet");
  options.voxel_picture_max_z = line.doubleValue("voxel-picture-max-z", 1e9);
  if (options.name.empty() || options.name.find('/') != std::string::npos) {
    throw UsageError("--name must be a plain file name, got '" + options.name + "'");
  }
  if (options.bag_paths.empty() && options.depth_folders.empty() &&
      options.middlebury_folders.empty() && options.carmen_logs.empty()) {
    throw UsageError("missing input: give --bag, --depth-folder, --middlebury-folder or --carmen");
  }
  if (options.bag_paths.empty() && !options.topics.empty()) {
    throw UsageError("topic options need a --bag");
  }
  if (options.carmen_max_scans < 0) throw UsageError("--carmen-max-scans must be >= 0");
  if (line.has("single-scan") && options.single_scan < 0) {
    throw UsageError("--single-scan must be >= 0");
  }
  requireExisting(options.config_paths, false);
  if (!options.load_map.empty()) requireExisting({options.load_map}, false);
  requireExisting(options.bag_paths, false);
  requireExisting(options.carmen_logs, false);
  requireExisting(options.depth_folders, true);
  requireExisting(options.middlebury_folders, true);
  return options;
}

// Prints, at most every two seconds, "frames done / total (integrated per sensor kind), elapsed,
// rate", so a long run shows how far it is and which sensors it is integrating.
class ProgressPrinter {
 public:
  ProgressPrinter(std::size_t total, const MappingSession* mapper, bool quiet)
      : total_(total), mapper_(mapper), quiet_(quiet) {}

  void operator()(std::size_t done) {
    const auto now = std::chrono::steady_clock::now();
    if (quiet_ || now - last_print_ < std::chrono::seconds(2)) return;
    last_print_ = now;
    const double elapsed = elapsedSeconds();
    std::ostringstream line;
    line << "offline_mapper: " << done << " / " << total_ << " frames (";
    const char* separator = "";
    for (const auto& [kind, count] : mapper_->statistics().frames_by_kind) {
      line << separator << kind << " " << count;
      separator = ", ";
    }
    line << "), " << std::fixed << std::setprecision(1) << elapsed << " s, "
         << (elapsed > 0 ? done / elapsed : 0.0) << " frames/s\n";
    std::cerr << line.str();
  }
  double elapsedSeconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::size_t total_;
  const MappingSession* mapper_;
  bool quiet_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_print_ = start_;
};

// checkpoint_period with spill_folder: the map resumed the store's last checkpoint, and is
// checkpointed to it that often (wall time) and at the end, as the MapServer does.
class Checkpoints {
 public:
  Checkpoints(MappingSession* mapper, bool quiet) : mapper_(mapper) {
    const VoxelMap& map = mapper_->map();
    period_ = map.config().checkpoint_period;
    const SpillStatus status = map.spillStatus();
    if (!(period_ > 0)) return;
    if (!status.checkpoints) {
      std::cerr << "offline_mapper: warning: checkpoint_period " << period_
                << " s but no checkpoints: "
                << (map.config().spill_folder.empty() ? "spill_folder is not set"
                                                      : status.last_error)
                << "\n";
      period_ = 0;
      return;
    }
    if (!quiet) {
      std::cerr << "offline_mapper: checkpoints to " << map.config().spill_folder << " every "
                << period_ << " s; resumed " << status.resumed_blocks << " blocks and "
                << mapper_->resumedLayerTiles() << " laser layer tiles"
                << (status.resumed_stamp.empty() ? " (no checkpoint there)"
                                                 : " of " + status.resumed_stamp)
                << "\n";
    }
  }
  void whenDue() {
    if (period_ > 0 &&
        std::chrono::steady_clock::now() - last_ >= std::chrono::duration<double>(period_)) {
      now();
    }
  }
  void now() {
    if (!(period_ > 0)) return;
    last_ = std::chrono::steady_clock::now();
    if (!mapper_->checkpoint(checkpointStampNow()).written) {
      std::cerr << "offline_mapper: warning: checkpoint failed: "
                << mapper_->map().spillStatus().last_error << "\n";
    }
  }

 private:
  MappingSession* mapper_;
  double period_ = 0;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

double peakResidentMebibytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

const char* measurementName(const std::string& kind) {
  if (kind == "point_cloud") return "points";
  if (kind == "laser") return "beams";
  return "pixels";
}

// The files written, in order (saveMap's, then the voxel picture), and what saveMap reported.
struct MapOutputs {
  std::vector<std::string> files;
  SavedMapFiles saved;
};

// One line per sensor kind (frames, skips with their reasons, time per frame).
void printKinds(const MappingStatistics& stats, std::ostream& text) {
  for (const auto& [kind, kind_stats] : stats.by_kind) {
    text << "  " << kind << ": " << kind_stats.frames << " integrated, " << kind_stats.skipped
         << " skipped, " << kind_stats.millisecondsPerFrame() << " ms per frame, "
         << kind_stats.measurements << " " << measurementName(kind) << "\n";
  }
  for (const auto& [reason, count] : stats.skipped_by_reason) {
    text << "    skipped " << count << ": " << reason
         << " (first: " << stats.first_skip_detail.at(reason) << ")\n";
  }
}

void printSummary(const std::vector<std::unique_ptr<InputReader>>& readers,
                  const MappingSession& mapper, const MapOutputs& outputs, double total_seconds) {
  const SavedMapFiles& saved = outputs.saved;
  const MappingStatistics& stats = mapper.statistics();
  std::ostringstream text;
  text << std::fixed << std::setprecision(1);
  text << "offline_mapper: summary\n";
  for (const auto& reader : readers) text << "  input: " << reader->description() << "\n";
  text << "  frames:";
  if (stats.frames_by_kind.empty()) text << " 0";
  for (const auto& [kind, count] : stats.frames_by_kind) text << " " << count << " " << kind;
  text << " integrated, " << stats.framesSkipped() << " skipped\n";
  printKinds(stats, text);
  const std::size_t frames = stats.framesIntegrated();
  text << "  time: " << total_seconds << " s in all, "
       << (frames > 0 ? 1000.0 * stats.integration_seconds / frames : 0.0)
       << " ms per integrated frame\n";
  std::size_t occupied = 0;
  mapper.map().forEachOccupiedVoxel([&](const VoxelIndex&, float) { ++occupied; });
  text << "  map: " << mapper.map().knownVoxelCount() << " voxels known, " << occupied
       << " occupied, " << mapper.laserLayer().knownCellCount() << " laser cells known, resolution "
       << std::setprecision(3) << mapper.map().resolution() << " m, " << std::setprecision(1)
       << (mapper.map().memoryBytes() + mapper.laserLayer().memoryBytes()) / (1024.0 * 1024.0)
       << " MiB map memory, " << peakResidentMebibytes() << " MiB peak resident\n";
  if (const MapReanchoring* reanchoring = mapper.reanchoring()) {
    const ReanchoringStatistics corrections = reanchoring->statistics();
    text << "  reanchoring (" << sourceName(reanchoring->config().source)
         << "): " << reanchoring->fusion().submaps().size() << " submaps, "
         << corrections.corrections << " corrections moved " << corrections.submaps_moved
         << " submaps and rebuilt " << corrections.blocks_rewritten << " blocks, "
         << std::setprecision(1) << reanchoring->fusion().memoryBytes() / (1024.0 * 1024.0)
         << " MiB of submaps\n";
  }
  const SpillStatus spill = mapper.map().spillStatus();
  if (spill.enabled) {
    const TileSpillStatus tiles = mapper.laserLayer().spillStatus();
    text << "  spill store: " << spill.spilled_blocks << " blocks and " << tiles.spilled_tiles
         << " laser tiles held by the store alone; written " << spill.blocks_written
         << " blocks and " << tiles.tiles_written << " tiles, paged in " << spill.blocks_paged_in
         << " blocks and " << tiles.tiles_paged_in << " tiles\n";
  }
  if (saved.grid_width == 0) {
    text << "  2D view: none, nothing was mapped (no .pgm, .yaml, .npy, .png)\n";
  } else {
    text << "  2D view: " << saved.grid_width << " x " << saved.grid_height << " cells";
    const FusedGridConfig& band = mapper.config().fused_grid;
    if (std::isinf(band.min_z) && std::isinf(band.max_z) && mapper.map().knownVoxelCount() > 0) {
      text << " (occupancy_min_z/occupancy_max_z unset: every height is projected, floor too)";
    }
    text << "\n";
  }
  if (saved.octomap_skipped_voxels > 0) {
    text << "  warning: " << saved.octomap_skipped_voxels
         << " voxels lie outside OctoMap's key range and are not in the .bt/.ot\n";
  }
  text << "  wrote:";
  if (outputs.files.empty()) text << " nothing (a map with nothing known is not saved)";
  for (const std::string& path : outputs.files) text << " " << path;
  std::cout << text.str() << "\n";
}

// Forwards every frame to the mapper and keeps a copy of laser scan number `wanted`.
class ScanPicker : public FrameConsumer {
 public:
  ScanPicker(FrameConsumer* next, int wanted) : next_(next), wanted_(wanted) {}

  void onPointCloud(const PointCloudFrame& frame) override { next_->onPointCloud(frame); }
  void onDepthImage(const DepthImageFrame& frame) override { next_->onDepthImage(frame); }
  void onDisparityImage(const DisparityFrame& frame) override { next_->onDisparityImage(frame); }
  void onLaserScan(const LaserScanFrame& frame) override {
    if (scans_seen_++ == wanted_) picked_ = frame;
    next_->onLaserScan(frame);
  }
  void onUnreadable(const FrameHeader& header, const std::string& why) override {
    next_->onUnreadable(header, why);
  }
  void onTrajectory(const std::vector<StampedPose>& keyframes, double stamp) override {
    next_->onTrajectory(keyframes, stamp);
  }

  int scansSeen() const { return scans_seen_; }
  const std::optional<LaserScanFrame>& picked() const { return picked_; }

 private:
  FrameConsumer* next_;
  int wanted_;
  int scans_seen_ = 0;
  std::optional<LaserScanFrame> picked_;
};

// NAME_voxels.png: the occupied voxels in 3D below --voxel-picture-max-z (none when no voxel is
// occupied).
void writeVoxelPicture(const VoxelMap& map, const Options& options, MapOutputs* outputs) {
  VoxelPictureConfig config;
  config.max_z = options.voxel_picture_max_z;
  const VoxelPicture picture = renderOccupiedVoxels(map, config);
  if (picture.voxels == 0) return;
  const std::string path =
      (std::filesystem::path(options.output_dir) / (options.name + "_voxels.png")).string();
  if (!cv::imwrite(path, picture.image, {cv::IMWRITE_PNG_COMPRESSION, 9})) {
    throw std::runtime_error("cannot write " + path);
  }
  outputs->files.push_back(path);
}

// Everything that can fail because of the user's input, before any mapping: UsageError.
struct Setup {
  Options options;
  std::unique_ptr<YamlParameterSource> parameters;
  MappingSessionConfig config;
  std::vector<std::unique_ptr<InputReader>> readers;
};

std::vector<std::unique_ptr<InputReader>> openReaders(const Options& options) {
  std::vector<std::unique_ptr<InputReader>> readers;
  if (!options.bag_paths.empty()) {
    readers.push_back(std::make_unique<RosbagReader>(options.bag_paths, options.topics));
  }
  for (const std::string& folder : options.depth_folders) {
    readers.push_back(std::make_unique<SevenScenesReader>(folder));
  }
  for (const std::string& folder : options.middlebury_folders) {
    readers.push_back(std::make_unique<MiddleburyReader>(folder));
  }
  CarmenReadConfig carmen;
  carmen.max_scans = static_cast<std::size_t>(options.carmen_max_scans);
  for (const std::string& log : options.carmen_logs) {
    readers.push_back(std::make_unique<CarmenReader>(log, carmen));
  }
  return readers;
}

Setup prepare(int argc, char** argv) {
  const CommandLine line(
      argc, argv,
      {"config", "namespace", "set", "bag", "cloud-topic", "depth-topic", "disparity-topic",
       "scan-topic", "path-topic", "depth-folder", "middlebury-folder", "carmen",
       "carmen-max-scans", "single-scan", "output-dir", "name", "voxel-picture-max-z", "load-map"},
      {"quiet", "help"});
  Setup setup;
  setup.options = parseOptions(line);
  try {
    setup.parameters = std::make_unique<YamlParameterSource>(
        YamlParameterSource::fromFiles(setup.options.config_paths, setup.options.config_namespace));
    for (const std::string& assignment : setup.options.overrides) {
      setup.parameters->addOverride(assignment);
    }
    setup.config = readMappingSessionConfig(*setup.parameters);
  } catch (const std::invalid_argument& error) {
    throw UsageError(std::string("bad parameters: ") + error.what());
  }
  std::error_code error;
  std::filesystem::create_directories(setup.options.output_dir, error);
  if (error || !std::filesystem::is_directory(setup.options.output_dir)) {
    throw UsageError("cannot create --output-dir " + setup.options.output_dir);
  }
  try {
    setup.readers = openReaders(setup.options);
  } catch (const std::invalid_argument& error) {
    throw UsageError(error.what());
  }
  return setup;
}

// Writes NAME_scan.* for --single-scan; false (after saying why) when there is no such scan.
bool writeSingleScan(const Setup& setup, const ScanPicker& picker) {
  if (setup.options.single_scan < 0) return true;
  if (!picker.picked()) {
    std::cerr << "offline_mapper: error: --single-scan " << setup.options.single_scan
              << ": the inputs hold " << picker.scansSeen() << " laser scans\n";
    return false;
  }
  SingleScanGridConfig grid;
  grid.resolution = setup.config.map.resolution;
  const LogOddsRaster raster = singleScanGrid(picker.picked()->scan, setup.config.laser, grid);
  const std::string prefix =
      (std::filesystem::path(setup.options.output_dir) / (setup.options.name + "_scan")).string();
  const std::vector<std::string> files =
      writeSingleScanOutputs(raster, setup.config.map.model.thresholdLogOdds(), prefix);
  std::cout << "offline_mapper: scan " << setup.options.single_scan << " ("
            << picker.picked()->header.source << ", " << methodName(setup.config.laser.method)
            << ") in its sensor frame: " << raster.width << " x " << raster.height
            << " cells, wrote";
  for (const std::string& file : files) std::cout << " " << file;
  std::cout << "\n";
  return true;
}

// --load-map: a file that cannot be resumed is a bad input file (exit 2), not a mapping failure.
void resume(const std::string& path, MappingSession* mapper) {
  ResumedMap resumed;
  try {
    resumed = mapper->resumeFrom(path);
  } catch (const std::runtime_error& error) {
    throw UsageError(std::string("--load-map: cannot resume: ") + error.what());
  }
  std::cout << "offline_mapper: resumed " << resumed.known_voxels << " voxels"
            << (resumed.labels_only ? " (labels only: a .bt file)" : "") << " and "
            << resumed.layer_cells << " laser layer cells from " << path
            << (resumed.layer_found ? "" : " (no laser layer files beside it)") << "\n";
}

int run(int argc, char** argv) {
  Setup setup = prepare(argc, argv);
  std::size_t total_frames = 0;
  for (const auto& reader : setup.readers) total_frames += reader->frameCount();
  MappingSession mapper(setup.config, nullptr, &std::cerr);
  if (!setup.options.load_map.empty()) resume(setup.options.load_map, &mapper);
  Checkpoints checkpoints(&mapper, setup.options.quiet);
  ProgressPrinter progress(total_frames, &mapper, setup.options.quiet);
  ScanPicker picker(&mapper, setup.options.single_scan);
  std::size_t frames_before = 0;
  for (const auto& reader : setup.readers) {
    if (!setup.options.quiet) std::cerr << "offline_mapper: " << reader->description() << "\n";
    mapper.setPoseSource(&reader->poses());
    reader->read(&picker, [&](std::size_t done) {
      progress(frames_before + done);
      checkpoints.whenDue();
    });
    frames_before += reader->frameCount();
  }
  checkpoints.now();
  MapOutputs outputs;
  if (mapper.map().knownVoxelCount() > 0 || mapper.laserLayer().knownCellCount() > 0) {
    MapSaveOptions save;
    save.band = mapper.config().fused_grid;
    save.inspection_files = true;
    const std::string prefix =
        (std::filesystem::path(setup.options.output_dir) / setup.options.name).string();
    outputs.saved = saveMap(mapper.map(), mapper.laserLayer(), prefix, save, &outputs.files);
    if (mapper.reanchoring() != nullptr) {
      writeSubmapFile(mapper.reanchoring(), submapFilePath(prefix));
      outputs.files.push_back(submapFilePath(prefix));
    }
  }
  writeVoxelPicture(mapper.map(), setup.options, &outputs);
  printSummary(setup.readers, mapper, outputs, progress.elapsedSeconds());
  for (const std::string& key : setup.parameters->unreadOverrides()) {
    std::cerr << "offline_mapper: warning: --set " << key
              << " was not read by anything (misspelt?)\n";
  }
  if (!writeSingleScan(setup, picker)) return kUsageExitCode;
  if (mapper.statistics().framesIntegrated() == 0) {
    std::cerr << "offline_mapper: failed: no frame could be integrated (see the skip reasons)\n";
    return 1;
  }
  return 0;
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  return occupancy_fusion::runTool("offline_mapper", occupancy_fusion::kUsage, argc, argv,
                                   occupancy_fusion::run);
}
