// simulate_recording: writes a rosbag of a simulated robot with its sensors (point-cloud camera,
// depth camera, stereo camera, two laser scanners) moving through one of the simulator's scenes,
// for offline_mapper, rosbag play and the demo. See kUsage.
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <rosbag/exceptions.h>

#include "occupancy_fusion/tools/command_line.h"
#include "occupancy_fusion/tools/simulated_recording.h"
#include "occupancy_fusion/tools/tool_main.h"

namespace occupancy_fusion {
namespace {

const char* const kUsage = R"(usage: simulate_recording --output OUT.bag [options]

Writes a deterministic rosbag of a robot moving through a simulated scene with its sensors, the
robot's pose on /tf (map -> odom -> base_link) and the sensor mounts on /tf_static (latched on
playback, as a recorded static_transform_publisher). Sensors:
  cloud      sensor_msgs/PointCloud2 on /cloud_in (frame camera_optical_frame)
  depth      sensor_msgs/Image 16UC1 (mm) on /camera/depth/image with /camera/depth/camera_info
             (frame depth_camera_optical_frame)
  disparity  stereo_msgs/DisparityImage on /stereo/disparity with /stereo/left/camera_info
             (frame stereo_left_optical_frame; 0.12 m baseline, 0.1 px white noise)
  scan       sensor_msgs/LaserScan from two scanners: /scan_front (frame laser_front) and
             /scan_rear (frame laser_rear, facing backward, mounted upside down)

  --output FILE   the bag to write (overwritten)
  --scene NAME    room (default), corridor, box, spheres or building (a 40 x 25 m floor: the robot
                  drives its 88 m corridor loop, counter-clockwise from the south corridor)
  --frames N      number of frames (default 60; building: the whole loop path, or its first N)
  --rate HZ       frames per second (default 5)
  --step M        building: metres between frames (default 0.2)
  --laps L        building: laps of the loop (default 1.25: back at the start once, then on)
  --drift SEED    drifting odometry (seeded) and a graph-SLAM stand-in: odom -> base_link is the
                  odometry (about 0.5 m and 4 deg off after a lap), map -> odom the stand-in's,
                  which corrects the past at loop closures (the robot within 1.5 m of a keyframe
                  20 m of travel back); nav_msgs/Path of its keyframes (one a metre, poses of
                  base_link in map) on /slam/path at every correction and every --path-every
                  frames as it grows, and the true path on /ground_truth/path at the end (both
                  latched). Without it odometry is exact and map -> odom fixed.
  --drift-scale X  multiplies the odometry errors (default 1; 0: exact odometry)
  --path-every N  frames between /slam/path messages as the path grows (default 10)
  --sensors LIST  comma-separated sensor kinds (default: cloud,depth,disparity,scan)
  --disparity-patches P  chance in [0, 1] of a patch of wrong disparity in each 24 x 24 px cell,
                  persisting over 10 frames, as a real matcher's correlated errors (default 0)
  --image-size WxH  the depth and stereo cameras' images (default 160x120; same field of view)
  --every LIST    per sensor kind, every how many frames it writes, e.g. depth=4,disparity=8,scan=3
                  with --rate 120: depth 30 Hz, disparity 15 Hz, scans 40 Hz (default: every frame)
  --help          this text
Exit status: 0 done, 2 bad arguments, 1 failure while writing.
)";

// --drift and its options: the drifting odometry and the SLAM stand-in.
void parseDrift(const CommandLine& line, SimulatedRecordingConfig* config) {
  if (!line.has("drift")) {
    if (line.has("drift-scale") || line.has("path-every")) {
      throw UsageError("--drift-scale and --path-every need --drift SEED");
    }
    return;
  }
  const int seed = line.intValue("drift", 0);
  if (seed < 0) throw UsageError("--drift SEED must be >= 0");
  config->drift = true;
  config->odometry_drift.seed = static_cast<unsigned>(seed);
  const double scale = line.doubleValue("drift-scale", 1.0);
  if (!(scale >= 0.0)) throw UsageError("--drift-scale must be >= 0");
  config->odometry_drift = config->odometry_drift.scaled(scale);
  config->path_every = line.intValue("path-every", config->path_every);
  if (config->path_every < 1) throw UsageError("--path-every must be at least 1");
}

SimulatedRecordingConfig parseConfig(const CommandLine& line) {
  SimulatedRecordingConfig config;
  config.scene = line.value("scene", config.scene);
  config.rate_hz = line.doubleValue("rate", config.rate_hz);
  if (!(config.rate_hz > 0.0)) throw UsageError("--rate must be > 0");
  if (config.scene == "building") {
    config.loop.step_m = line.doubleValue("step", config.loop.step_m);
    config.loop.laps = line.doubleValue("laps", config.loop.laps);
    if (!(config.loop.step_m > 0.0)) throw UsageError("--step must be > 0");
    if (!(config.loop.laps > 0.0) || config.loop.laps > 100.0) {
      throw UsageError("--laps must be > 0 and at most 100");
    }
    config.frames = loopPathFrames(config.loop);
  } else if (line.has("step") || line.has("laps")) {
    throw UsageError("--step and --laps are for --scene building");
  }
  config.frames = line.intValue("frames", config.frames);
  if (config.frames < 1) throw UsageError("--frames must be at least 1");
  parseDrift(line, &config);
  try {
    // Checks the name (and that the building's loop has the frames) before any file is written.
    makeSimulatedWorld(config.scene, config.scene == "building" ? config.frames : 1, config.loop);
  } catch (const std::invalid_argument& error) {
    throw UsageError(std::string("--scene / --frames: ") + error.what());
  }
  return config;
}

std::vector<std::unique_ptr<SimulatedSensor>> parseSensors(const CommandLine& line) {
  const std::vector<std::string> kinds = line.listValue("sensors", "cloud,depth,disparity,scan");
  if (kinds.empty()) throw UsageError("--sensors: give at least one sensor kind");
  SimulatedSensorOptions options;
  options.disparity_patch_probability = line.doubleValue("disparity-patches", 0.0);
  const std::string size = line.value("image-size", "");
  if (!size.empty()) {
    char separator = 0;
    std::istringstream parsed(size);
    if (!(parsed >> options.image_width >> separator >> options.image_height) || separator != 'x' ||
        !parsed.eof() || options.image_width < 1 || options.image_height < 1) {
      throw UsageError("--image-size must be WIDTHxHEIGHT in pixels, e.g. 640x480, not '" + size +
                       "'");
    }
  }
  for (const std::string& entry : line.listValue("every", "")) {
    const std::size_t equals = entry.find('=');
    int every = 0;
    try {
      every = equals == std::string::npos ? 0 : std::stoi(entry.substr(equals + 1));
    } catch (const std::exception&) {
    }
    if (every < 1) throw UsageError("--every: '" + entry + "' is not KIND=N with N >= 1");
    options.every[entry.substr(0, equals)] = every;
  }
  try {
    return makeSimulatedSensors(kinds, options);
  } catch (const std::invalid_argument& error) {
    throw UsageError(std::string("--sensors / --disparity-patches / --image-size / --every: ") +
                     error.what());
  }
}

int run(int argc, char** argv) {
  const CommandLine line(
      argc, argv,
      {"output", "scene", "frames", "rate", "sensors", "disparity-patches", "image-size", "every",
       "step", "laps", "drift", "drift-scale", "path-every"},
      {"help"});
  const SimulatedRecordingConfig config = parseConfig(line);
  const std::string output = line.required("output");
  const std::vector<std::unique_ptr<SimulatedSensor>> sensors = parseSensors(line);
  try {
    writeSimulatedRecording(config, sensors, output);
  } catch (const rosbag::BagException& error) {
    throw UsageError("cannot write --output " + output + ": " + error.what());
  }
  std::cout << "simulate_recording: wrote " << config.frames << " frames of scene '" << config.scene
            << "' at " << config.rate_hz << " Hz" << (config.drift ? " with drift" : "") << " to "
            << output << "\n";
  return 0;
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  return occupancy_fusion::runTool("simulate_recording", occupancy_fusion::kUsage, argc, argv,
                                   occupancy_fusion::run);
}
