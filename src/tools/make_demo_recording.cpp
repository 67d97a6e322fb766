// make_demo_recording: writes the demo's rosbag from the bundled real recordings (a CARMEN laser
// log, Middlebury stereo pairs matched here with StereoSGBM) and a simulated depth camera, all
// placed in one map frame. See kUsage.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>
#include <Eigen/Geometry>

#include "occupancy_fusion/sensors/carmen_log.h"
#include "occupancy_fusion/sensors/middlebury_folder.h"
#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/trajectory.h"
#include "occupancy_fusion/tools/command_line.h"
#include "occupancy_fusion/tools/ros_conversions.h"
#include "occupancy_fusion/tools/simulated_recording.h"
#include "occupancy_fusion/tools/stereo_matching.h"
#include "occupancy_fusion/tools/tool_main.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

const char* const kUsage =
    R"(usage: make_demo_recording --output OUT.bag --carmen LOG --stereo DIR... [options]

Writes the demo's rosbag: real laser scans and real stereo disparity, plus a simulated depth
camera, in one map frame (REP-105), for offline_mapper and roslaunch occupancy_fusion demo.launch.
  laser      every FLASER line of the CARMEN log (.gz accepted) as sensor_msgs/LaserScan on /scan
             (frame laser), restamped at --rate; the log's corrected pose as /tf map -> odom
             (identity) -> base_link; /tf_static base_link -> laser (identity: the log's pose is
             the laser's). Readings at or above 49.9 m (the logs' no-returns) lie above
             range_max.
  stereo     each --stereo folder (Middlebury layout: calib.txt, im0.png, im1.png) matched with
             OpenCV's StereoSGBM into stereo_msgs/DisparityImage on /stereo/disparity with
             /stereo/left/camera_info (frame stereo_<n>_optical_frame, n = 0, 1, ...; disparity in
             the ROS convention d + doffs), --stereo-frames times, spread over the recording.
             Camera n stands still on /tf_static at x = 6 + 5 n m, y = 9 m, 1.2 m up, looking
             along +y, level: north of the laser log's building, clear of it (the pairs were
             recorded elsewhere; the map only places them side by side).
  depth      the simulator's room (8 m x 6 m) centred at x = -2 m, y = 14 m, seen by a simulated
             depth camera (160 x 120, 16UC1 mm) on a robot turning in it: /camera/depth/image with
             /camera/depth/camera_info (frame depth_camera_optical_frame), /tf map -> sim_base_link,
             /tf_static sim_base_link -> depth_camera_link -> depth_camera_optical_frame.

  --output FILE        the bag to write (overwritten)
  --carmen FILE        CARMEN log
  --stereo DIR         Middlebury scene folder (repeatable)
  --rate HZ            laser scans per second in the bag (default 10)
  --stereo-frames N    disparity frames per stereo folder (default 2)
  --depth-frames N     simulated depth frames (default 40; 0: no depth camera)
  --help               this text
Exit status: 0 done, 2 bad arguments or input files, 1 failure while writing.
)";

constexpr double kStartTime = 1000.0;  // s, stamp of the first scan
const Eigen::Vector3d kFirstStereoStation(6.0, 9.0, 1.2);
constexpr double kStereoStationSpacing = 5.0;  // m along x
const Eigen::Vector3d kRoomCentre(-2.0, 14.0, 0.0);

struct Options {
  std::string output;
  std::string carmen;
  std::vector<std::string> stereo_folders;
  double rate_hz = 10.0;
  int stereo_frames = 2;
  int depth_frames = 40;
};

Options parseOptions(const CommandLine& line) {
  Options options;
  options.output = line.required("output");
  options.carmen = line.required("carmen");
  options.stereo_folders = line.values("stereo");
  options.rate_hz = line.doubleValue("rate", options.rate_hz);
  options.stereo_frames = line.intValue("stereo-frames", options.stereo_frames);
  options.depth_frames = line.intValue("depth-frames", options.depth_frames);
  if (!(options.rate_hz > 0.0)) throw UsageError("--rate must be > 0");
  if (options.stereo_frames < 1) throw UsageError("--stereo-frames must be at least 1");
  if (options.depth_frames < 0) throw UsageError("--depth-frames must be >= 0");
  if (options.stereo_folders.empty()) throw UsageError("missing --stereo");
  if (!fs::is_regular_file(options.carmen)) throw UsageError("no such file: " + options.carmen);
  for (const std::string& folder : options.stereo_folders) {
    for (const char* file : {"calib.txt", "im0.png", "im1.png"}) {
      if (!fs::is_regular_file(fs::path(folder) / file)) {
        throw UsageError("--stereo " + folder + ": no " + file);
      }
    }
  }
  return options;
}

ros::Time stampAt(double seconds_from_start) { return ros::Time(kStartTime + seconds_from_start); }

tf2_msgs::TFMessage tfMessage(const std::vector<geometry_msgs::TransformStamped>& transforms) {
  tf2_msgs::TFMessage message;
  message.transforms = transforms;
  return message;
}

// The scans, restamped at `rate_hz`, the first half a period after the static transforms.
void writeLaser(const std::vector<CarmenLaserScan>& scans, double rate_hz, rosbag::Bag* bag) {
  for (std::size_t k = 0; k < scans.size(); ++k) {
    const CarmenLaserScan& carmen = scans[k];
    const ros::Time stamp = stampAt((k + 0.5) / rate_hz);
    const Eigen::Isometry3d T_odom_base = Eigen::Translation3d(carmen.x, carmen.y, 0.0) *
                                          Eigen::AngleAxisd(carmen.theta, Eigen::Vector3d::UnitZ());
    bag->write("/tf", stamp,
               tfMessage({transformMessage(Eigen::Isometry3d::Identity(), "map", "odom", stamp),
                          transformMessage(T_odom_base, "odom", "base_link", stamp)}));
    sensor_msgs::LaserScan message;
    message.header.frame_id = "laser";
    message.header.stamp = stamp;
    message.angle_min = static_cast<float>(carmen.scan.angle_min);
    message.angle_increment = static_cast<float>(carmen.scan.angle_increment);
    message.angle_max = static_cast<float>(carmen.scan.angle(carmen.scan.beamCount() - 1));
    message.range_min = static_cast<float>(carmen.scan.range_min);
    message.range_max = static_cast<float>(carmen.scan.range_max);
    message.ranges = carmen.scan.ranges;
    bag->write("/scan", stamp, message);
  }
}

// Camera n's optical frame in the map: level, looking along +y (optical z = map +y, optical x =
// map +x, optical y = map -z).
Eigen::Isometry3d stereoStation(std::size_t n) {
  Eigen::Matrix3d R_map_optical;
  R_map_optical.col(0) = Eigen::Vector3d::UnitX();
  R_map_optical.col(1) = -Eigen::Vector3d::UnitZ();
  R_map_optical.col(2) = Eigen::Vector3d::UnitY();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = R_map_optical;
  pose.translation() = kFirstStereoStation + Eigen::Vector3d(kStereoStationSpacing * n, 0, 0);
  return pose;
}

// One SGBM disparity message of a Middlebury folder, in the ROS convention (d + doffs).
stereo_msgs::DisparityImage matchedDisparity(const std::string& folder, const std::string& frame,
                                             sensor_msgs::CameraInfo* info) {
  const MiddleburyCalibration calibration =
      readMiddleburyCalibration((fs::path(folder) / "calib.txt").string());
  SgbmSettings settings;
  // Cover the scene's search range (calib.txt's ndisp) from 0, in steps of 16 as SGBM wants.
  if (calibration.ndisp > 0) settings.num_disparities = 16 * ((calibration.ndisp + 15) / 16);
  int width = 0, height = 0;
  const std::vector<float> disparity = sgbmDisparity(
      (fs::path(folder) / "im0.png").string(), (fs::path(folder) / "im1.png").string(), settings,
      static_cast<float>(calibration.doffs), &width, &height);
  const StereoCamera camera = calibration.camera();
  *info = cameraInfoMessage(camera.leftIntrinsics(width, height), frame, ros::Time());
  // Matched values lie in [doffs, doffs + num_disparities): that is the published range.
  return disparityMessage(disparity, width, height, camera, calibration.doffs,
                          calibration.doffs + settings.num_disparities, frame, ros::Time());
}

// Returns the cameras' static poses.
std::vector<geometry_msgs::TransformStamped> writeStereo(const Options& options, double duration,
                                                         rosbag::Bag* bag) {
  std::vector<geometry_msgs::TransformStamped> stations;
  const std::size_t count = options.stereo_folders.size();
  const int total = static_cast<int>(count) * options.stereo_frames;
  int written = 0;
  for (std::size_t n = 0; n < count; ++n) {
    const std::string frame = "stereo_" + std::to_string(n) + "_optical_frame";
    stations.push_back(transformMessage(stereoStation(n), "map", frame, stampAt(0)));
    sensor_msgs::CameraInfo info;
    stereo_msgs::DisparityImage disparity =
        matchedDisparity(options.stereo_folders[n], frame, &info);
    for (int i = 0; i < options.stereo_frames; ++i, ++written) {
      // Spread over the recording, half a period after a scan so stamps never coincide.
      const ros::Time stamp = stampAt(duration * (written + 0.5) / total);
      info.header.stamp = disparity.header.stamp = disparity.image.header.stamp = stamp;
      bag->write("/stereo/left/camera_info", stamp, info);
      bag->write("/stereo/disparity", stamp, disparity);
    }
  }
  return stations;
}

// Returns the camera's static mount.
std::vector<geometry_msgs::TransformStamped> writeDepth(int frames, double duration,
                                                        rosbag::Bag* bag) {
  if (frames == 0) return {};
  const SimulatedWorld room = makeSimulatedWorld("room", frames);
  const Eigen::Isometry3d T_map_room{Eigen::Translation3d(kRoomCentre)};
  const DepthImageCameraConfig camera;
  const Eigen::Isometry3d T_base_optical = camera.T_base_link * sim::opticalFrameInBody();
  for (int k = 0; k < frames; ++k) {
    const ros::Time stamp = stampAt(duration * (k + 0.25) / frames);
    const Eigen::Isometry3d T_map_base = T_map_room * room.T_map_base[k];
    bag->write("/tf", stamp,
               tfMessage({transformMessage(T_map_base, "map", "sim_base_link", stamp)}));
    // Rendered in the room's own frame, where the scene is.
    const sim::DepthImage depth = sim::renderDepth(
        room.scene, camera.camera, room.T_map_base[k] * T_base_optical, camera.max_range);
    bag->write(camera.info_topic, stamp,
               cameraInfoMessage(camera.camera, camera.optical_frame, stamp));
    bag->write(camera.image_topic, stamp,
               depthImageMessage(depth.depth, depth.width, depth.height, camera.millimetres,
                                 camera.optical_frame, stamp));
  }
  return {transformMessage(camera.T_base_link, "sim_base_link", camera.link_frame, stampAt(0)),
          transformMessage(sim::opticalFrameInBody(), camera.link_frame, camera.optical_frame,
                           stampAt(0))};
}

int run(int argc, char** argv) {
  const CommandLine line(argc, argv,
                         {"output", "carmen", "stereo", "rate", "stereo-frames", "depth-frames"},
                         {"help"});
  const Options options = parseOptions(line);
  std::vector<CarmenLaserScan> scans;
  try {
    scans = readCarmenLog(options.carmen);
  } catch (const std::runtime_error& error) {
    throw UsageError(std::string("--carmen: ") + error.what());
  }
  if (scans.empty()) throw UsageError("--carmen: no FLASER line in " + options.carmen);
  rosbag::Bag bag;
  try {
    bag.open(options.output, rosbag::bagmode::Write);
  } catch (const rosbag::BagException& error) {
    throw UsageError("cannot write --output " + options.output + ": " + error.what());
  }
  bag.setCompression(rosbag::compression::BZ2);
  // Every static transform in one /tf_static message, first: a latched playback keeps only the
  // last message, and the static buffer needs all of them before the first frame.
  std::vector<geometry_msgs::TransformStamped> statics = {
      transformMessage(Eigen::Isometry3d::Identity(), "base_link", "laser", stampAt(0))};
  const double duration = scans.size() / options.rate_hz;
  for (const auto& t : writeStereo(options, duration, &bag)) statics.push_back(t);
  for (const auto& t : writeDepth(options.depth_frames, duration, &bag)) statics.push_back(t);
  bag.write("/tf_static", stampAt(0), tfMessage(statics),
            latchedConnectionHeader<tf2_msgs::TFMessage>("/make_demo_recording"));
  writeLaser(scans, options.rate_hz, &bag);
  bag.close();
  std::cout << "make_demo_recording: wrote " << scans.size() << " scans, "
            << options.stereo_folders.size() * options.stereo_frames << " disparity images ("
            << options.stereo_folders.size() << " StereoSGBM pairs), " << options.depth_frames
            << " simulated depth images over " << duration << " s to " << options.output << "\n";
  return 0;
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  return occupancy_fusion::runTool("make_demo_recording", occupancy_fusion::kUsage, argc, argv,
                                   occupancy_fusion::run);
}
