// Writes rosbags of the scene simulator: a robot moving through a scene with its sensors, each
// sensor's messages on its topic and the robot's poses on /tf and /tf_static (REP-105: map ->
// odom -> base_link, then static sensor mounts), optionally with drifting odometry and a SLAM
// stand-in's corrections and keyframe path. Deterministic: the same config gives the same
// messages. A new sensor kind is a new SimulatedSensor.
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <rosbag/bag.h>

#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/laser_scanner.h"
#include "occupancy_fusion/sim/localisation_stand_in.h"
#include "occupancy_fusion/sim/odometry_drift.h"
#include "occupancy_fusion/sim/scene.h"
#include "occupancy_fusion/sim/stereo_camera.h"

namespace occupancy_fusion {

// A scene with the path a robot takes through it.
struct SimulatedWorld {
  sim::Scene scene;
  std::vector<Eigen::Isometry3d> T_map_base;  // robot (base_link) pose per frame
};

// The building scene's path: sim::buildingLoopPath(step_m, laps).
struct LoopPathOptions {
  double step_m = 0.2;  // m between frames
  double laps = 1.25;   // once round and back to the start (a loop closure), then a quarter more
};

// Scene names: "room" (sim::makeRoomScene, the robot turns on a circle of 0.5 m around the free
// centre, facing outward), "corridor" (drives down the corridor), "box" and "spheres" (the depth
// paper's scenes, the robot turning in place at the paper's camera position), "building"
// (sim::makeBuildingFloorScene, the first `frames` poses of the corridor loop; throws
// std::invalid_argument when the loop has fewer: see loopPathFrames). Throws
// std::invalid_argument listing the names for an unknown one.
SimulatedWorld makeSimulatedWorld(const std::string& scene_name, int frames,
                                  const LoopPathOptions& loop = {});
std::vector<std::string> simulatedSceneNames();
// How many poses the building's loop path has.
int loopPathFrames(const LoopPathOptions& loop);

// One simulated sensor on the robot.
class SimulatedSensor {
 public:
  virtual ~SimulatedSensor() = default;
  // Its mount on the robot: static transforms from base_link down to the frame its data is in.
  virtual std::vector<geometry_msgs::TransformStamped> mountTransforms() const = 0;
  // Renders the scene from the robot pose and writes frame number `frame`'s messages stamped
  // `stamp` (the number drives noise that persists over frames).
  virtual void writeFrame(const sim::Scene& scene, const Eigen::Isometry3d& T_map_base, int frame,
                          const ros::Time& stamp, rosbag::Bag* bag) const = 0;

  // Writes at every n-th frame of the recording only (its own frame k is the recording's k n):
  // sensors at rates below the recording's.
  int every() const { return every_; }
  void setEvery(int every);  // throws std::invalid_argument unless every >= 1

 private:
  int every_ = 1;
};

// A depth camera publishing sensor_msgs/PointCloud2 in its optical frame (z forward, x right,
// y down): base_link -> camera_link (mount) -> camera_optical_frame (REP-103 rotation).
struct PointCloudCameraConfig {
  std::string topic = "/cloud_in";
  std::string link_frame = "camera_link";
  std::string optical_frame = "camera_optical_frame";
  // A small, quick camera: 160 x 120 px, 60 deg horizontal field of view.
  sim::PinholeCamera camera{160, 120, 138.6, 138.6, 79.5, 59.5};
  double max_range = 6.0;  // m; pixels seeing nothing nearer give no point
  // camera_link in base_link: 1 m up, 0.1 m forward, tilted down by 0.25 rad to see the floor.
  Eigen::Isometry3d T_base_link =
      Eigen::Translation3d(0.1, 0.0, 1.0) * Eigen::AngleAxisd(0.25, Eigen::Vector3d::UnitY());

  void validate() const;  // throws std::invalid_argument naming the bad field
};

class PointCloudCameraSensor : public SimulatedSensor {
 public:
  explicit PointCloudCameraSensor(const PointCloudCameraConfig& config);  // validates
  std::vector<geometry_msgs::TransformStamped> mountTransforms() const override;
  void writeFrame(const sim::Scene& scene, const Eigen::Isometry3d& T_map_base, int frame,
                  const ros::Time& stamp, rosbag::Bag* bag) const override;

 private:
  PointCloudCameraConfig config_;
};

// A depth camera publishing what an RGB-D driver does: sensor_msgs/Image (16UC1 in mm, 0 = no
// return, or 32FC1 in m, NaN = no return) with sensor_msgs/CameraInfo beside it.
struct DepthImageCameraConfig {
  std::string image_topic = "/camera/depth/image";
  std::string info_topic = "/camera/depth/camera_info";
  std::string link_frame = "depth_camera_link";
  std::string optical_frame = "depth_camera_optical_frame";
  sim::PinholeCamera camera{160, 120, 138.6, 138.6, 79.5, 59.5};
  double max_range = 6.0;   // m
  bool millimetres = true;  // 16UC1 (true) or 32FC1
  // 0.9 m up, looking 0.5 rad to the left of the robot's heading, tilted down by 0.3 rad.
  Eigen::Isometry3d T_base_link = Eigen::Translation3d(0.0, 0.1, 0.9) *
                                  Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY());

  void validate() const;  // throws std::invalid_argument naming the bad field
};

class DepthImageCameraSensor : public SimulatedSensor {
 public:
  explicit DepthImageCameraSensor(const DepthImageCameraConfig& config);  // validates
  std::vector<geometry_msgs::TransformStamped> mountTransforms() const override;
  void writeFrame(const sim::Scene& scene, const Eigen::Isometry3d& T_map_base, int frame,
                  const ros::Time& stamp, rosbag::Bag* bag) const override;

 private:
  DepthImageCameraConfig config_;
};

// A stereo camera publishing what stereo_image_proc does: stereo_msgs/DisparityImage of the left
// camera (invalid pixels below min_disparity) and the left sensor_msgs/CameraInfo, with the
// simulator's matcher errors (white noise, optionally correlated patches that persist).
struct DisparityCameraConfig {
  std::string disparity_topic = "/stereo/disparity";
  std::string info_topic = "/stereo/left/camera_info";
  std::string link_frame = "stereo_link";
  std::string optical_frame = "stereo_left_optical_frame";
  sim::PinholeCamera camera{160, 120, 138.6, 138.6, 79.5, 59.5};
  double baseline = 0.12;      // m
  double max_range = 6.0;      // m
  double min_disparity = 0.5;  // px, as published; smaller values mark invalid pixels
  double max_disparity = 256.0;
  sim::DisparityNoise noise = [] {
    sim::DisparityNoise noise;
    noise.sigma_px = 0.1;
    return noise;
  }();
  // 1.1 m up, looking 0.5 rad to the right of the robot's heading, tilted down by 0.2 rad.
  Eigen::Isometry3d T_base_link = Eigen::Translation3d(0.05, -0.1, 1.1) *
                                  Eigen::AngleAxisd(-0.5, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY());

  void validate() const;  // throws std::invalid_argument naming the bad field
};

class DisparityCameraSensor : public SimulatedSensor {
 public:
  explicit DisparityCameraSensor(const DisparityCameraConfig& config);  // validates
  std::vector<geometry_msgs::TransformStamped> mountTransforms() const override;
  void writeFrame(const sim::Scene& scene, const Eigen::Isometry3d& T_map_base, int frame,
                  const ros::Time& stamp, rosbag::Bag* bag) const override;

 private:
  DisparityCameraConfig config_;
};

// A 2D laser scanner publishing sensor_msgs/LaserScan (REP-117) in its own frame.
struct LaserScannerConfig {
  std::string topic = "/scan";
  std::string frame = "laser";
  sim::LaserScanner scanner;  // 361 beams over 180 degrees, 30 m
  Eigen::Isometry3d T_base_laser = Eigen::Isometry3d(Eigen::Translation3d(0.25, 0.0, 0.3));

  void validate() const;  // throws std::invalid_argument naming the bad field
};

class LaserScannerSensor : public SimulatedSensor {
 public:
  explicit LaserScannerSensor(const LaserScannerConfig& config);  // validates
  std::vector<geometry_msgs::TransformStamped> mountTransforms() const override;
  void writeFrame(const sim::Scene& scene, const Eigen::Isometry3d& T_map_base, int frame,
                  const ros::Time& stamp, rosbag::Bag* bag) const override;

 private:
  LaserScannerConfig config_;
};

// The two scanners of the simulated robot: /scan_front (frame laser_front, 0.25 m ahead, 0.3 m
// up, facing forward) and /scan_rear (frame laser_rear, 0.25 m behind, 0.35 m up, facing
// backward and mounted upside down, so its beams sweep clockwise in the map).
std::vector<LaserScannerConfig> twoLaserScanners();

// Sensor kinds of simulate_recording's --sensors: "cloud", "depth", "disparity", "scan".
std::vector<std::string> simulatedSensorKinds();
struct SimulatedSensorOptions {
  double disparity_patch_probability = 0.0;  // correlated disparity patches (0: none)
  // The depth and stereo cameras' images (px; 0: 160 x 120), the focal lengths scaled alike (the
  // same field of view) and the principal point at the centre.
  int image_width = 0, image_height = 0;
  // Per sensor kind, every how many frames of the recording it writes (absent: every frame).
  std::map<std::string, int> every;
};
// The sensors of the given kinds (each name once at most; "scan" gives both scanners). Throws
// std::invalid_argument naming an unknown kind.
std::vector<std::unique_ptr<SimulatedSensor>> makeSimulatedSensors(
    const std::vector<std::string>& kinds, const SimulatedSensorOptions& options = {});

struct SimulatedRecordingConfig {
  std::string scene = "room";
  int frames = 60;
  double rate_hz = 5.0;        // frames per second; stamps are start_time + k / rate_hz
  double start_time = 1000.0;  // s, stamp of frame 0 (bag times are stamps, like a recording)
  LoopPathOptions loop;        // the building scene's path
  // Localisation's correction, published as map -> odom at every frame (odom -> base_link then
  // carries the rest of the robot's pose). Not used with drift.
  Eigen::Isometry3d T_map_odom =
      Eigen::Translation3d(0.3, -0.2, 0.0) * Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ());
  // Drifting odometry and a graph-SLAM stand-in (sim/odometry_drift.h, sim/localisation_stand_in.h)
  // instead of the fixed correction: odom -> base_link is the drifted odometry, map -> odom the
  // stand-in's (it changes at its corrections), and the keyframe path goes on path_topic.
  bool drift = false;
  sim::OdometryDriftConfig odometry_drift;
  sim::LocalisationConfig localisation;
  std::string path_topic = "/slam/path";
  std::string truth_path_topic = "/ground_truth/path";
  int path_every =
      10;  // frames: the growing path is written at most this often (and at corrections)

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// Writes the recording to bag_path (overwritten): /tf_static once (every sensor's mount) at
// frame 0's stamp, then per frame /tf (map -> odom, odom -> base_link) and the messages of each
// sensor due at it (SimulatedSensor::every), all stamped alike. With drift, also the SLAM
// keyframe path (nav_msgs/Path in map, one pose of base_link per keyframe stamped with its frame,
// latched) on path_topic at frame 0, at every correction and, while keyframes are added, every
// path_every frames and at the last frame; and the true path (every frame's pose, latched) on
// truth_path_topic once, at the last frame's stamp. Returns the number of frames written.
int writeSimulatedRecording(const SimulatedRecordingConfig& config,
                            const std::vector<std::unique_ptr<SimulatedSensor>>& sensors,
                            const std::string& bag_path);

}  // namespace occupancy_fusion
