// Writes rosbags of the scene simulator: a robot moving through a scene with its sensors, each
// sensor's messages on its topic and the robot's poses on /tf and /tf_static (REP-105: map ->
// odom -> base_link, then static sensor mounts). Deterministic: the same config gives the same
// messages. A new sensor kind is a new SimulatedSensor.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <rosbag/bag.h>

#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/scene.h"

namespace occupancy_fusion {

// A scene with the path a robot takes through it.
struct SimulatedWorld {
  sim::Scene scene;
  std::vector<Eigen::Isometry3d> T_map_base;  // robot (base_link) pose per frame
};

// Scene names: "room" (sim::makeRoomScene, the robot turns on a circle around the free centre,
// facing outward), "corridor" (drives down the corridor), "box" and "spheres" (the depth paper's
// scenes, the robot turning in place at the paper's camera position). Throws
// std::invalid_argument listing the names for an unknown one.
SimulatedWorld makeSimulatedWorld(const std::string& scene_name, int frames);
std::vector<std::string> simulatedSceneNames();

// One simulated sensor on the robot.
class SimulatedSensor {
 public:
  virtual ~SimulatedSensor() = default;
  // Its mount on the robot: static transforms from base_link down to the frame its data is in.
  virtual std::vector<geometry_msgs::TransformStamped> mountTransforms() const = 0;
  // Renders the scene from the robot pose and writes the frame's messages stamped `stamp`.
  virtual void writeFrame(const sim::Scene& scene, const Eigen::Isometry3d& T_map_base,
                          const ros::Time& stamp, rosbag::Bag* bag) const = 0;
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
  void writeFrame(const sim::Scene& scene, const Eigen::Isometry3d& T_map_base,
                  const ros::Time& stamp, rosbag::Bag* bag) const override;

 private:
  PointCloudCameraConfig config_;
};

struct SimulatedRecordingConfig {
  std::string scene = "room";
  int frames = 60;
  double rate_hz = 5.0;        // frames per second; stamps are start_time + k / rate_hz
  double start_time = 1000.0;  // s, stamp of frame 0 (bag times are stamps, like a recording)
  // Localisation's correction, published as map -> odom at every frame (odom -> base_link then
  // carries the rest of the robot's pose).
  Eigen::Isometry3d T_map_odom =
      Eigen::Translation3d(0.3, -0.2, 0.0) * Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ());

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// Writes the recording to bag_path (overwritten): /tf_static once (every sensor's mount) at
// frame 0's stamp, then per frame /tf (map -> odom, odom -> base_link) and each sensor's
// messages, all stamped alike. Returns the number of frames written.
int writeSimulatedRecording(const SimulatedRecordingConfig& config,
                            const std::vector<std::unique_ptr<SimulatedSensor>>& sensors,
                            const std::string& bag_path);

}  // namespace occupancy_fusion
