// simulate_recording: writes a rosbag of a simulated robot with a depth camera moving through
// one of the simulator's scenes, for offline_mapper, rosbag play and the demo. See kUsage.
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <ros/time.h>
#include <rosbag/exceptions.h>

#include "occupancy_fusion/tools/command_line.h"
#include "occupancy_fusion/tools/simulated_recording.h"

namespace occupancy_fusion {
namespace {

const char* const kUsage = R"(usage: simulate_recording --output OUT.bag [options]

Writes a deterministic rosbag of a robot moving through a simulated scene with a depth camera:
sensor_msgs/PointCloud2 on /cloud_in (frame camera_optical_frame), the robot's pose on /tf
(map -> odom -> base_link) and the camera mount on /tf_static (base_link -> camera_link ->
camera_optical_frame).

  --output FILE   the bag to write (overwritten)
  --scene NAME    room (default), corridor, box or spheres
  --frames N      number of frames (default 60)
  --rate HZ       frames per second (default 5)
  --help          this text
Exit status: 0 done, 2 bad arguments, 1 failure while writing.
)";

SimulatedRecordingConfig parseConfig(const CommandLine& line) {
  SimulatedRecordingConfig config;
  config.scene = line.value("scene", config.scene);
  config.frames = line.intValue("frames", config.frames);
  config.rate_hz = line.doubleValue("rate", config.rate_hz);
  if (config.frames < 1) throw UsageError("--frames must be at least 1");
  if (!(config.rate_hz > 0.0)) throw UsageError("--rate must be > 0");
  try {
    makeSimulatedWorld(config.scene, 1);  // checks the name before any file is written
  } catch (const std::invalid_argument& error) {
    throw UsageError(std::string("--scene: ") + error.what());
  }
  return config;
}

int run(int argc, char** argv) {
  const CommandLine line(argc, argv, {"output", "scene", "frames", "rate"}, {"help"});
  const SimulatedRecordingConfig config = parseConfig(line);
  const std::string output = line.required("output");
  std::vector<std::unique_ptr<SimulatedSensor>> sensors;
  sensors.push_back(std::make_unique<PointCloudCameraSensor>(PointCloudCameraConfig()));
  try {
    writeSimulatedRecording(config, sensors, output);
  } catch (const rosbag::BagException& error) {
    throw UsageError("cannot write --output " + output + ": " + error.what());
  }
  std::cout << "simulate_recording: wrote " << config.frames << " frames of scene '" << config.scene
            << "' at " << config.rate_hz << " Hz to " << output << "\n";
  return 0;
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  using namespace occupancy_fusion;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") {
      std::cout << kUsage;
      return 0;
    }
  }
  ros::Time::init();  // rosbag uses ros::Time; no master is contacted
  try {
    return run(argc, argv);
  } catch (const UsageError& error) {
    std::cerr << "simulate_recording: error: " << error.what()
              << "\n(simulate_recording --help for usage)\n";
    return kUsageExitCode;
  } catch (const std::exception& error) {
    std::cerr << "simulate_recording: failed: " << error.what() << "\n";
    return 1;
  }
}
