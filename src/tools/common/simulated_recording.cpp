#include "occupancy_fusion/tools/simulated_recording.h"

#include <cmath>
#include <stdexcept>

#include <tf2_msgs/TFMessage.h>

#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/trajectory.h"
#include "occupancy_fusion/tools/ros_conversions.h"

namespace occupancy_fusion {
namespace {

Eigen::Isometry3d robotPose(double x, double y, double yaw) {
  return Eigen::Isometry3d(Eigen::Translation3d(x, y, 0.0) *
                           Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
}

// Fraction of the way along a path for frame k of n (0 for a single frame).
double progressOf(int k, int frames) { return frames > 1 ? double(k) / (frames - 1) : 0.0; }

// One full turn on a circle of radius 1 m around the room's free centre, facing outward, so
// the camera sees every wall and object once.
std::vector<Eigen::Isometry3d> roomPath(int frames) {
  std::vector<Eigen::Isometry3d> poses;
  for (int k = 0; k < frames; ++k) {
    const double angle = 2.0 * M_PI * k / frames;
    poses.push_back(robotPose(std::cos(angle), std::sin(angle), angle));
  }
  return poses;
}

// Turning in place at `position` (ground projection) from yaw -max_yaw to +max_yaw.
std::vector<Eigen::Isometry3d> turnInPlace(const Eigen::Vector3d& position, double max_yaw,
                                           int frames) {
  std::vector<Eigen::Isometry3d> poses;
  for (int k = 0; k < frames; ++k) {
    const double yaw = -max_yaw + 2.0 * max_yaw * progressOf(k, frames);
    poses.push_back(robotPose(position.x(), position.y(), yaw));
  }
  return poses;
}

std::vector<Eigen::Isometry3d> corridorPath(int frames) {
  std::vector<Eigen::Isometry3d> poses;
  for (int k = 0; k < frames; ++k)
    poses.push_back(robotPose(1.0 + 16.0 * progressOf(k, frames), 0.0, 0.0));
  return poses;
}

ros::Time stampOf(const SimulatedRecordingConfig& config, int frame) {
  return ros::Time(config.start_time + frame / config.rate_hz);
}

}  // namespace

std::vector<std::string> simulatedSceneNames() { return {"room", "corridor", "box", "spheres"}; }

SimulatedWorld makeSimulatedWorld(const std::string& scene_name, int frames) {
  if (frames < 1) throw std::invalid_argument("frames must be >= 1, got " + std::to_string(frames));
  if (scene_name == "room") return {sim::makeRoomScene(), roomPath(frames)};
  if (scene_name == "corridor") return {sim::makeCorridorScene(), corridorPath(frames)};
  if (scene_name == "box") {
    return {sim::makeBoxScene(), turnInPlace(sim::boxSceneCameraPosition(), 0.5, frames)};
  }
  if (scene_name == "spheres") {
    return {sim::makeSpheresScene(), turnInPlace(sim::spheresSceneCameraPosition(), 0.3, frames)};
  }
  std::string names;
  for (const std::string& name : simulatedSceneNames()) names += (names.empty() ? "" : ", ") + name;
  throw std::invalid_argument("unknown scene '" + scene_name + "' (known: " + names + ")");
}

void PointCloudCameraConfig::validate() const {
  if (topic.empty()) throw std::invalid_argument("topic must not be empty");
  if (link_frame.empty() || optical_frame.empty()) {
    throw std::invalid_argument("link_frame and optical_frame must not be empty");
  }
  camera.validate();
  if (!(max_range > 0.0)) throw std::invalid_argument("max_range must be > 0");
}

PointCloudCameraSensor::PointCloudCameraSensor(const PointCloudCameraConfig& config)
    : config_(config) {
  config_.validate();
}

std::vector<geometry_msgs::TransformStamped> PointCloudCameraSensor::mountTransforms() const {
  return {transformMessage(config_.T_base_link, "base_link", config_.link_frame, ros::Time()),
          transformMessage(sim::opticalFrameInBody(), config_.link_frame, config_.optical_frame,
                           ros::Time())};
}

void PointCloudCameraSensor::writeFrame(const sim::Scene& scene,
                                        const Eigen::Isometry3d& T_map_base, const ros::Time& stamp,
                                        rosbag::Bag* bag) const {
  const Eigen::Isometry3d T_map_optical =
      T_map_base * config_.T_base_link * sim::opticalFrameInBody();
  const std::vector<Eigen::Vector3d> points =
      sim::renderPointCloud(scene, config_.camera, T_map_optical, config_.max_range);
  std::vector<Eigen::Vector3f> points_f;
  points_f.reserve(points.size());
  for (const Eigen::Vector3d& point : points) points_f.push_back(point.cast<float>());
  bag->write(config_.topic, stamp, cloudFromPoints(points_f, config_.optical_frame, stamp));
}

void SimulatedRecordingConfig::validate() const {
  if (frames < 1) throw std::invalid_argument("frames must be >= 1");
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz))
    throw std::invalid_argument("rate_hz must be > 0");
  if (!(start_time > 0.0) || !std::isfinite(start_time)) {
    // 0 would mean "latest" to tf; rosbag cannot store negative times.
    throw std::invalid_argument("start_time must be > 0");
  }
}

int writeSimulatedRecording(const SimulatedRecordingConfig& config,
                            const std::vector<std::unique_ptr<SimulatedSensor>>& sensors,
                            const std::string& bag_path) {
  config.validate();
  const SimulatedWorld world = makeSimulatedWorld(config.scene, config.frames);
  rosbag::Bag bag(bag_path, rosbag::bagmode::Write);

  tf2_msgs::TFMessage mounts;
  for (const std::unique_ptr<SimulatedSensor>& sensor : sensors) {
    for (geometry_msgs::TransformStamped transform : sensor->mountTransforms()) {
      transform.header.stamp = stampOf(config, 0);
      mounts.transforms.push_back(transform);
    }
  }
  bag.write("/tf_static", stampOf(config, 0), mounts);

  for (int frame = 0; frame < config.frames; ++frame) {
    const ros::Time stamp = stampOf(config, frame);
    const Eigen::Isometry3d& T_map_base = world.T_map_base[frame];
    tf2_msgs::TFMessage poses;
    poses.transforms.push_back(transformMessage(config.T_map_odom, "map", "odom", stamp));
    poses.transforms.push_back(
        transformMessage(config.T_map_odom.inverse() * T_map_base, "odom", "base_link", stamp));
    bag.write("/tf", stamp, poses);
    for (const std::unique_ptr<SimulatedSensor>& sensor : sensors) {
      sensor->writeFrame(world.scene, T_map_base, stamp, &bag);
    }
  }
  bag.close();
  return config.frames;
}

}  // namespace occupancy_fusion
