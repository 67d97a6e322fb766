// Sensors of the Simulator nodelet. Each renders the scene (core simulator, occupancy_fusion::sim)
// at the pose of its frame and publishes what the real sensor's driver would. A new kind of
// sensor (stereo disparity, laser scan) is one more SimulatedSensor subclass and one line in the
// Simulator's sensor list.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <image_transport/image_transport.h>
#include <ros/ros.h>

#include "occupancy_fusion/params/parameter_source.h"
#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/scene.h"

namespace occupancy_fusion {

// Where a sensor sits on the robot: frame names and T_body_sensor (REP-103 axes: x forward).
struct SensorMount {
  std::string frame;  // e.g. camera_link
  Eigen::Isometry3d T_body_sensor = Eigen::Isometry3d::Identity();
};

// The mount pose under `prefix`: x, y, z (m) and roll, pitch, yaw (rad, applied as yaw * pitch *
// roll) in the body frame; each key that is absent keeps default_pose's value.
Eigen::Isometry3d readMountPose(const ParameterSource& source, const std::string& prefix,
                                const Eigen::Isometry3d& default_pose);

// Throws std::invalid_argument naming `<name>/rate` unless `rate` is a positive number of Hz.
void validateSensorRate(const std::string& name, double rate);

// Runs part.validate() and prefixes what it throws with the parameter block `prefix` (e.g.
// "camera/"), so the user learns where the bad parameter sits.
template <typename Part>
void validateUnder(const std::string& prefix, const Part& part) {
  try {
    part.validate();
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(prefix + ": " + error.what());
  }
}

class SimulatedSensor {
 public:
  virtual ~SimulatedSensor() = default;
  virtual const std::string& name() const = 0;
  virtual double rate() const = 0;  // Hz
  // Transforms from the body frame to the sensor's frames, for /tf_static.
  virtual std::vector<geometry_msgs::TransformStamped> staticTransforms(
      const std::string& body_frame) const = 0;
  // Renders and publishes one measurement taken at `stamp` with the robot at T_world_body.
  // Renders nothing when no one listens.
  virtual void publish(const sim::Scene& scene, const Eigen::Isometry3d& T_world_body,
                       const ros::Time& stamp) = 0;
};

struct SimulatedDepthCameraConfig {
  std::string name = "camera";
  double rate = 5.0;          // Hz
  double max_range = 6.0;     // m, farther surfaces give NaN pixels
  sim::PinholeCamera camera;  // intrinsics
  SensorMount mount;          // camera_link on the body
  std::string optical_frame;  // the image's frame (z forward, x right, y down)

  void validate() const;  // throws std::invalid_argument naming the bad parameter
};

// Under the namespace `prefix` (e.g. "camera/"): rate, max_range, width, height, fx, fy, cx, cy
// (px; cx, cy default to the image centre), frame_id, optical_frame_id, and the mount pose
// x, y, z (m), roll, pitch, yaw (rad) in the body frame.
SimulatedDepthCameraConfig readSimulatedDepthCameraConfig(const ParameterSource& source,
                                                          const std::string& prefix);

// For /tf_static: the body to the camera's link, and the link to its optical frame.
std::vector<geometry_msgs::TransformStamped> cameraStaticTransforms(
    const SimulatedDepthCameraConfig& camera, const std::string& body_frame);

// A depth camera as an RGB-D driver publishes it: <name>/depth/image (32FC1, metres, NaN = no
// return) with <name>/depth/camera_info, and the same pixels as <name>/depth/points
// (PointCloud2 in the optical frame, NaN pixels left out). Remap <name>/depth/points to cloud_in
// for the point-cloud mapper.
class SimulatedDepthCamera : public SimulatedSensor {
 public:
  SimulatedDepthCamera(const ros::NodeHandle& node_handle,
                       const SimulatedDepthCameraConfig& config);

  const std::string& name() const override { return config_.name; }
  double rate() const override { return config_.rate; }
  std::vector<geometry_msgs::TransformStamped> staticTransforms(
      const std::string& body_frame) const override;
  void publish(const sim::Scene& scene, const Eigen::Isometry3d& T_world_body,
               const ros::Time& stamp) override;

 private:
  SimulatedDepthCameraConfig config_;
  image_transport::ImageTransport image_transport_;
  image_transport::CameraPublisher depth_publisher_;
  ros::Publisher cloud_publisher_;
};

}  // namespace occupancy_fusion
