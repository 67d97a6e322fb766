// offline_mapper: maps a recording without a ROS master, with the same YAML parameters as the
// mapper nodelets, and writes the map files. See usage() below.
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <ros/time.h>

#include "occupancy_fusion/tools/command_line.h"
#include "occupancy_fusion/tools/map_outputs.h"
#include "occupancy_fusion/tools/recording_mapper.h"
#include "occupancy_fusion/tools/rosbag_reader.h"
#include "occupancy_fusion/tools/yaml_parameter_source.h"

namespace occupancy_fusion {
namespace {

const char* const kUsage =
    R"(usage: offline_mapper --config FILE.yaml --bag IN.bag --output-dir DIR [options]

Maps the point clouds of a rosbag (no ROS master needed) into one 3D voxel map and writes
DIR/NAME.bt, .ot (OctoMap), .pcd (every known voxel with its occupancy probability), .pgm + .yaml
(map_server files of the fused 2D view over occupancy_min_z..occupancy_max_z), .npy (per-column
log-odds behind the 2D view) and .png (a picture of the 2D view).
Poses come from the bag's /tf and /tf_static; a cloud whose transform to frame_id is not
available is skipped and counted.

  --config FILE        YAML parameters, as loaded by rosparam into a mapper nodelet; repeat
                       to merge several files as successive rosparam loads (later ones win),
                       e.g. point_cloud_mapper.yaml, then map_server.yaml for the 2D band
  --namespace NS       take the parameters from section NS of each file (e.g. a node name)
  --set KEY=VALUE      override one parameter, e.g. --set sensor_model/max_range=4 (repeatable)
  --bag FILE           input rosbag
  --cloud-topic TOPIC  sensor_msgs/PointCloud2 topic to map (repeatable; default: all of them)
  --output-dir DIR     where the map files go (created if needed)
  --name NAME          base name of the map files (default: map)
  --quiet              no progress lines
  --help               this text
Exit status: 0 done, 2 bad arguments, parameters or input files, 1 failure while mapping
(including a recording none of whose frames could be placed).
)";

struct Options {
  std::vector<std::string> config_paths;
  std::string config_namespace;
  std::vector<std::string> overrides;
  std::string bag_path;
  std::vector<std::string> cloud_topics;
  std::string output_dir;
  std::string name;
  bool quiet = false;
};

Options parseOptions(const CommandLine& line) {
  Options options;
  line.required("config");
  options.config_paths = line.values("config");
  options.config_namespace = line.value("namespace");
  options.overrides = line.values("set");
  options.bag_path = line.required("bag");
  options.cloud_topics = line.values("cloud-topic");
  options.output_dir = line.required("output-dir");
  options.name = line.value("name", "map");
  options.quiet = line.has("quiet");
  if (options.name.empty() || options.name.find('/') != std::string::npos) {
    throw UsageError("--name must be a plain file name, got '" + options.name + "'");
  }
  std::vector<std::string> inputs = options.config_paths;
  inputs.push_back(options.bag_path);
  for (const std::string& path : inputs) {
    if (!std::filesystem::is_regular_file(path)) throw UsageError("no such file: " + path);
  }
  return options;
}

// Prints "frames done / total, elapsed" at most every two seconds.
class ProgressPrinter {
 public:
  ProgressPrinter(std::size_t total, bool quiet) : total_(total), quiet_(quiet) {}

  void operator()(std::size_t done) {
    const auto now = std::chrono::steady_clock::now();
    if (quiet_ || now - last_print_ < std::chrono::seconds(2)) return;
    last_print_ = now;
    std::cerr << "offline_mapper: " << done << " / " << total_ << " frames, " << std::fixed
              << std::setprecision(1) << elapsedSeconds() << " s\n";
  }
  double elapsedSeconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::size_t total_;
  bool quiet_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_print_ = start_;
};

double peakResidentMebibytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

void printSummary(const InputReader& reader, const RecordingMapper& mapper,
                  const MapOutputs& outputs, double total_seconds) {
  const RecordingStatistics& stats = mapper.statistics();
  std::ostringstream text;
  text << std::fixed << std::setprecision(1);
  text << "offline_mapper: summary\n  input: " << reader.description() << "\n  frames:";
  if (stats.frames_by_kind.empty()) text << " 0";
  for (const auto& [kind, count] : stats.frames_by_kind) text << " " << count << " " << kind;
  text << " integrated, " << stats.framesSkipped() << " skipped\n";
  for (const auto& [reason, count] : stats.skipped_by_reason) {
    text << "    skipped " << count << ": " << reason
         << " (first: " << stats.first_skip_detail.at(reason) << ")\n";
  }
  const std::size_t frames = stats.framesIntegrated();
  text << "  time: " << total_seconds << " s in all, "
       << (frames > 0 ? 1000.0 * stats.integration_seconds / frames : 0.0)
       << " ms per integrated frame (" << stats.points << " points)\n";
  std::size_t occupied = 0;
  mapper.map().forEachOccupiedVoxel([&](const VoxelIndex&, float) { ++occupied; });
  text << "  map: " << mapper.map().knownVoxelCount() << " voxels known, " << occupied
       << " occupied, resolution " << std::setprecision(3) << mapper.map().resolution() << " m, "
       << std::setprecision(1) << mapper.map().memoryBytes() / (1024.0 * 1024.0)
       << " MiB map memory, " << peakResidentMebibytes() << " MiB peak resident\n";
  if (outputs.grid_width == 0) {
    text << "  2D view: none, nothing was mapped (no .pgm, .yaml, .npy, .png)\n";
  } else {
    text << "  2D view: " << outputs.grid_width << " x " << outputs.grid_height << " cells";
    const FusedGridConfig& band = mapper.config().fused_grid;
    if (std::isinf(band.min_z) && std::isinf(band.max_z)) {
      text << " (occupancy_min_z/occupancy_max_z unset: every height is projected, floor too)";
    }
    text << "\n";
  }
  if (outputs.octomap_skipped_voxels > 0) {
    text << "  warning: " << outputs.octomap_skipped_voxels
         << " voxels lie outside OctoMap's key range and are not in the .bt/.ot\n";
  }
  text << "  wrote:";
  for (const std::string& path : outputs.files) text << " " << path;
  std::cout << text.str() << "\n";
}

// Everything that can fail because of the user's input, before any mapping: UsageError.
struct Setup {
  Options options;
  std::unique_ptr<YamlParameterSource> parameters;
  RecordingMapperConfig config;
  std::unique_ptr<RosbagReader> reader;
};

Setup prepare(int argc, char** argv) {
  const CommandLine line(argc, argv,
                         {"config", "namespace", "set", "bag", "cloud-topic", "output-dir", "name"},
                         {"quiet", "help"});
  Setup setup;
  setup.options = parseOptions(line);
  try {
    setup.parameters = std::make_unique<YamlParameterSource>(
        YamlParameterSource::fromFiles(setup.options.config_paths, setup.options.config_namespace));
    for (const std::string& assignment : setup.options.overrides) {
      setup.parameters->addOverride(assignment);
    }
    setup.config = readRecordingMapperConfig(*setup.parameters);
  } catch (const std::invalid_argument& error) {
    throw UsageError(std::string("bad parameters: ") + error.what());
  }
  std::error_code error;
  std::filesystem::create_directories(setup.options.output_dir, error);
  if (error || !std::filesystem::is_directory(setup.options.output_dir)) {
    throw UsageError("cannot create --output-dir " + setup.options.output_dir);
  }
  try {
    setup.reader =
        std::make_unique<RosbagReader>(setup.options.bag_path, setup.options.cloud_topics);
  } catch (const std::invalid_argument& error) {
    throw UsageError(error.what());
  }
  return setup;
}

int run(int argc, char** argv) {
  Setup setup = prepare(argc, argv);
  ProgressPrinter progress(setup.reader->frameCount(), setup.options.quiet);
  if (!setup.options.quiet) std::cerr << "offline_mapper: " << setup.reader->description() << "\n";
  RecordingMapper mapper(setup.config, &setup.reader->poses(), &std::cerr);
  setup.reader->read(&mapper, [&](std::size_t done) { progress(done); });
  const MapOutputs outputs = writeMapOutputs(mapper, setup.options.output_dir, setup.options.name);
  printSummary(*setup.reader, mapper, outputs, progress.elapsedSeconds());
  for (const std::string& key : setup.parameters->unreadOverrides()) {
    std::cerr << "offline_mapper: warning: --set " << key
              << " was not read by anything (misspelt?)\n";
  }
  if (mapper.statistics().framesIntegrated() == 0) {
    std::cerr << "offline_mapper: failed: no frame could be integrated (see the skip reasons)\n";
    return 1;
  }
  return 0;
}

bool wantsHelp(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") return true;
  }
  return false;
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  using namespace occupancy_fusion;
  if (wantsHelp(argc, argv)) {
    std::cout << kUsage;
    return 0;
  }
  ros::Time::init();  // rosbag and tf2 use ros::Time; no master is contacted
  try {
    return run(argc, argv);
  } catch (const UsageError& error) {
    std::cerr << "offline_mapper: error: " << error.what()
              << "\n(offline_mapper --help for usage)\n";
    return kUsageExitCode;
  } catch (const std::exception& error) {
    std::cerr << "offline_mapper: failed: " << error.what() << "\n";
    return 1;
  }
}
