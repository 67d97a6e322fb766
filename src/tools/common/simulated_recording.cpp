#include "occupancy_fusion/tools/simulated_recording.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include "occupancy_fusion/ros/path_message.h"
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

// One full turn on a circle of radius 0.5 m around the room's free centre, facing outward, so
// the sensors see every wall and object once. The table's nearest corner is 0.89 m from the
// centre: on this circle the robot and its scanners (0.25 m from its centre) stay clear of it.
std::vector<Eigen::Isometry3d> roomPath(int frames) {
  constexpr double kRadius = 0.5;  // m
  std::vector<Eigen::Isometry3d> poses;
  for (int k = 0; k < frames; ++k) {
    const double angle = 2.0 * M_PI * k / frames;
    poses.push_back(robotPose(kRadius * std::cos(angle), kRadius * std::sin(angle), angle));
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

// base_link -> link (the mount) -> optical frame (REP-103 rotation).
std::vector<geometry_msgs::TransformStamped> cameraMount(const Eigen::Isometry3d& T_base_link,
                                                         const std::string& link_frame,
                                                         const std::string& optical_frame) {
  return {transformMessage(T_base_link, "base_link", link_frame, ros::Time()),
          transformMessage(sim::opticalFrameInBody(), link_frame, optical_frame, ros::Time())};
}

void checkFrames(const std::vector<std::string>& names) {
  for (const std::string& name : names) {
    if (name.empty()) throw std::invalid_argument("topic and frame names must not be empty");
  }
}

ros::Time stampOf(const SimulatedRecordingConfig& config, int frame) {
  return ros::Time(config.start_time + frame / config.rate_hz);
}

}  // namespace

std::vector<std::string> simulatedSceneNames() {
  return {"room", "corridor", "box", "spheres", "building"};
}

int loopPathFrames(const LoopPathOptions& loop) {
  return static_cast<int>(sim::buildingLoopPath(loop.step_m, loop.laps).size());
}

SimulatedWorld makeSimulatedWorld(const std::string& scene_name, int frames,
                                  const LoopPathOptions& loop) {
  if (frames < 1) throw std::invalid_argument("frames must be >= 1, got " + std::to_string(frames));
  if (scene_name == "building") {
    std::vector<Eigen::Isometry3d> path = sim::buildingLoopPath(loop.step_m, loop.laps);
    if (static_cast<int>(path.size()) < frames) {
      throw std::invalid_argument("the building loop has " + std::to_string(path.size()) +
                                  " frames at this step and laps, fewer than " +
                                  std::to_string(frames));
    }
    path.resize(frames);
    return {sim::makeBuildingFloorScene(), path};
  }
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
                                        const Eigen::Isometry3d& T_map_base, int /*frame*/,
                                        const ros::Time& stamp, rosbag::Bag* bag) const {
  const Eigen::Isometry3d T_map_optical =
      T_map_base * config_.T_base_link * sim::opticalFrameInBody();
  const std::vector<Eigen::Vector3d> points =
      sim::renderPointCloud(scene, config_.camera, T_map_optical, config_.max_range);
  std::vector<Eigen::Vector3f> points_f;
  points_f.reserve(points.size());
  for (const Eigen::Vector3d& point : points) points_f.push_back(point.cast<float>());
  bag->write(config_.topic, stamp, cloudFromPoints(points_f, config_.optical_frame, stamp));
}

void DepthImageCameraConfig::validate() const {
  checkFrames({image_topic, info_topic, link_frame, optical_frame});
  camera.validate();
  if (!(max_range > 0.0)) throw std::invalid_argument("max_range must be > 0");
  if (millimetres && max_range > 65.535) {
    throw std::invalid_argument("max_range must be <= 65.535 m for 16-bit millimetres");
  }
}

DepthImageCameraSensor::DepthImageCameraSensor(const DepthImageCameraConfig& config)
    : config_(config) {
  config_.validate();
}

std::vector<geometry_msgs::TransformStamped> DepthImageCameraSensor::mountTransforms() const {
  return cameraMount(config_.T_base_link, config_.link_frame, config_.optical_frame);
}

void DepthImageCameraSensor::writeFrame(const sim::Scene& scene,
                                        const Eigen::Isometry3d& T_map_base, int /*frame*/,
                                        const ros::Time& stamp, rosbag::Bag* bag) const {
  const Eigen::Isometry3d T_map_optical =
      T_map_base * config_.T_base_link * sim::opticalFrameInBody();
  const sim::DepthImage depth =
      sim::renderDepth(scene, config_.camera, T_map_optical, config_.max_range);
  bag->write(config_.info_topic, stamp,
             cameraInfoMessage(config_.camera, config_.optical_frame, stamp));
  bag->write(config_.image_topic, stamp,
             depthImageMessage(depth.depth, depth.width, depth.height, config_.millimetres,
                               config_.optical_frame, stamp));
}

void DisparityCameraConfig::validate() const {
  checkFrames({disparity_topic, info_topic, link_frame, optical_frame});
  camera.validate();
  noise.validate();
  if (!(baseline > 0.0)) throw std::invalid_argument("baseline must be > 0");
  if (!(max_range > 0.0)) throw std::invalid_argument("max_range must be > 0");
  if (!(min_disparity > 0.0) || !(max_disparity > min_disparity)) {
    throw std::invalid_argument("min_disparity must be > 0 and below max_disparity");
  }
}

DisparityCameraSensor::DisparityCameraSensor(const DisparityCameraConfig& config)
    : config_(config) {
  config_.validate();
}

std::vector<geometry_msgs::TransformStamped> DisparityCameraSensor::mountTransforms() const {
  return cameraMount(config_.T_base_link, config_.link_frame, config_.optical_frame);
}

void DisparityCameraSensor::writeFrame(const sim::Scene& scene, const Eigen::Isometry3d& T_map_base,
                                       int frame, const ros::Time& stamp, rosbag::Bag* bag) const {
  const Eigen::Isometry3d T_map_optical =
      T_map_base * config_.T_base_link * sim::opticalFrameInBody();
  const sim::DisparityImage image =
      sim::renderDisparity(scene, config_.camera, config_.baseline, T_map_optical,
                           config_.max_range, config_.noise, frame);
  StereoCamera camera;
  camera.fx = config_.camera.fx;
  camera.fy = config_.camera.fy;
  camera.cx = config_.camera.cx;
  camera.cy = config_.camera.cy;
  camera.baseline = config_.baseline;
  // A matcher reports nothing outside its search range: those pixels become invalid.
  std::vector<float> disparity = image.disparity;
  for (float& value : disparity) {
    if (!(value >= config_.min_disparity && value <= config_.max_disparity)) {
      value = std::numeric_limits<float>::quiet_NaN();
    }
  }
  bag->write(config_.info_topic, stamp,
             cameraInfoMessage(config_.camera, config_.optical_frame, stamp));
  bag->write(config_.disparity_topic, stamp,
             disparityMessage(disparity, image.width, image.height, camera, config_.min_disparity,
                              config_.max_disparity, config_.optical_frame, stamp));
}

void LaserScannerConfig::validate() const {
  checkFrames({topic, frame});
  scanner.validate();
}

LaserScannerSensor::LaserScannerSensor(const LaserScannerConfig& config) : config_(config) {
  config_.validate();
}

std::vector<geometry_msgs::TransformStamped> LaserScannerSensor::mountTransforms() const {
  return {transformMessage(config_.T_base_laser, "base_link", config_.frame, ros::Time())};
}

void LaserScannerSensor::writeFrame(const sim::Scene& scene, const Eigen::Isometry3d& T_map_base,
                                    int frame, const ros::Time& stamp, rosbag::Bag* bag) const {
  const sim::LaserScan scan =
      sim::renderScan(scene, config_.scanner, T_map_base * config_.T_base_laser, frame);
  sensor_msgs::LaserScan message;
  message.header.frame_id = config_.frame;
  message.header.stamp = stamp;
  message.angle_min = static_cast<float>(scan.angle_min);
  message.angle_max = static_cast<float>(scan.angle_max);
  message.angle_increment = static_cast<float>(scan.angle_increment);
  message.range_min = static_cast<float>(scan.range_min);
  message.range_max = static_cast<float>(scan.range_max);
  message.ranges = scan.ranges;
  bag->write(config_.topic, stamp, message);
}

std::vector<LaserScannerConfig> twoLaserScanners() {
  LaserScannerConfig front;
  front.topic = "/scan_front";
  front.frame = "laser_front";
  front.T_base_laser = Eigen::Translation3d(0.25, 0.0, 0.3);
  LaserScannerConfig rear;
  rear.topic = "/scan_rear";
  rear.frame = "laser_rear";
  rear.scanner.seed = 2;
  rear.T_base_laser = Eigen::Translation3d(-0.25, 0.0, 0.35) *
                      Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()) *
                      Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX());
  return {front, rear};
}

std::vector<std::string> simulatedSensorKinds() { return {"cloud", "depth", "disparity", "scan"}; }

void SimulatedSensor::setEvery(int every) {
  if (every < 1) throw std::invalid_argument("a sensor writes every n-th frame, n >= 1");
  every_ = every;
}

namespace {

// The camera with images of width x height (0: unchanged) and the same field of view.
sim::PinholeCamera resized(const sim::PinholeCamera& camera, int width, int height) {
  if (width == 0 && height == 0) return camera;
  if (width < 1 || height < 1) throw std::invalid_argument("image size must be at least 1 x 1");
  sim::PinholeCamera result = camera;
  result.fx = camera.fx * width / camera.width;
  result.fy = camera.fy * height / camera.height;
  result.cx = (width - 1) / 2.0;
  result.cy = (height - 1) / 2.0;
  result.width = width;
  result.height = height;
  return result;
}

}  // namespace

std::vector<std::unique_ptr<SimulatedSensor>> makeSimulatedSensors(
    const std::vector<std::string>& kinds, const SimulatedSensorOptions& options) {
  std::vector<std::unique_ptr<SimulatedSensor>> sensors;
  std::vector<std::string> seen;
  for (const auto& [kind, every] : options.every) {
    if (std::find(kinds.begin(), kinds.end(), kind) == kinds.end()) {
      throw std::invalid_argument("a rate for sensor kind '" + kind + "', which is not recorded");
    }
  }
  for (const std::string& kind : kinds) {
    if (std::find(seen.begin(), seen.end(), kind) != seen.end()) {
      throw std::invalid_argument("sensor kind '" + kind + "' given twice");
    }
    seen.push_back(kind);
    const std::size_t first = sensors.size();
    if (kind == "cloud") {
      sensors.push_back(std::make_unique<PointCloudCameraSensor>(PointCloudCameraConfig()));
    } else if (kind == "depth") {
      DepthImageCameraConfig config;
      config.camera = resized(config.camera, options.image_width, options.image_height);
      sensors.push_back(std::make_unique<DepthImageCameraSensor>(config));
    } else if (kind == "disparity") {
      DisparityCameraConfig config;
      config.camera = resized(config.camera, options.image_width, options.image_height);
      config.noise.patch_probability = options.disparity_patch_probability;
      sensors.push_back(std::make_unique<DisparityCameraSensor>(config));
    } else if (kind == "scan") {
      for (const LaserScannerConfig& config : twoLaserScanners()) {
        sensors.push_back(std::make_unique<LaserScannerSensor>(config));
      }
    } else {
      throw std::invalid_argument("unknown sensor kind '" + kind +
                                  "' (known: cloud, depth, disparity, scan)");
    }
    const auto every = options.every.find(kind);
    for (std::size_t i = first; every != options.every.end() && i < sensors.size(); ++i) {
      sensors[i]->setEvery(every->second);
    }
  }
  return sensors;
}

void SimulatedRecordingConfig::validate() const {
  if (frames < 1) throw std::invalid_argument("frames must be >= 1");
  if (drift) {
    odometry_drift.validate();
    localisation.validate();
    if (path_every < 1) throw std::invalid_argument("path_every must be >= 1");
    checkFrames({path_topic, truth_path_topic});
  }
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz))
    throw std::invalid_argument("rate_hz must be > 0");
  if (!(start_time > 0.0) || !std::isfinite(start_time)) {
    // 0 would mean "latest" to tf; rosbag cannot store negative times.
    throw std::invalid_argument("start_time must be > 0");
  }
}

namespace {

// The robot's transforms per frame: map -> odom and odom -> base_link.
struct RobotTransforms {
  std::vector<Eigen::Isometry3d> T_map_odom;
  std::vector<Eigen::Isometry3d> T_odom_base;
  std::optional<sim::LocalisationTrack> track;  // with drift: the SLAM stand-in's output
};

RobotTransforms robotTransforms(const SimulatedRecordingConfig& config,
                                const std::vector<Eigen::Isometry3d>& T_map_base) {
  RobotTransforms transforms;
  if (!config.drift) {
    // The fixed correction with exact odometry: the robot's pose split at the same odom.
    for (const Eigen::Isometry3d& pose : T_map_base) {
      transforms.T_map_odom.push_back(config.T_map_odom);
      transforms.T_odom_base.push_back(config.T_map_odom.inverse() * pose);
    }
    return transforms;
  }
  transforms.T_odom_base = sim::driftedOdometry(T_map_base, config.odometry_drift);
  transforms.track = sim::runLocalisation(T_map_base, transforms.T_odom_base, config.localisation);
  transforms.T_map_odom = transforms.track->T_map_odom;
  return transforms;
}

// Writes the keyframe path as published at `frame` when it has changed: at every correction, and
// as it grows every path_every frames and at the last frame. `written` is the keyframe count of
// the last path written (-1: none yet).
void writeSlamPath(const SimulatedRecordingConfig& config, const sim::LocalisationTrack& track,
                   int frame, int* written, rosbag::Bag* bag) {
  const int keyframes = track.keyframeCountAt(frame);
  const bool corrected = track.lastCorrectionAt(frame) == frame;
  const bool due = frame % config.path_every == 0 || frame == config.frames - 1;
  if (!corrected && !(due && keyframes != *written)) return;
  std::vector<ros::Time> stamps;
  for (int i = 0; i < keyframes; ++i) stamps.push_back(stampOf(config, track.keyframe_frames[i]));
  const ros::Time stamp = stampOf(config, frame);
  bag->write(config.path_topic, stamp, pathMessage(track.pathAt(frame), stamps, "map", stamp),
             latchedConnectionHeader<nav_msgs::Path>("/simulate_recording"));
  *written = keyframes;
}

void writeTruthPath(const SimulatedRecordingConfig& config,
                    const std::vector<Eigen::Isometry3d>& T_map_base, rosbag::Bag* bag) {
  std::vector<ros::Time> stamps;
  for (int frame = 0; frame < config.frames; ++frame) stamps.push_back(stampOf(config, frame));
  bag->write(config.truth_path_topic, stamps.back(),
             pathMessage(T_map_base, stamps, "map", stamps.back()),
             latchedConnectionHeader<nav_msgs::Path>("/simulate_recording"));
}

}  // namespace

int writeSimulatedRecording(const SimulatedRecordingConfig& config,
                            const std::vector<std::unique_ptr<SimulatedSensor>>& sensors,
                            const std::string& bag_path) {
  config.validate();
  const SimulatedWorld world = makeSimulatedWorld(config.scene, config.frames, config.loop);
  const RobotTransforms robot = robotTransforms(config, world.T_map_base);
  rosbag::Bag bag(bag_path, rosbag::bagmode::Write);

  tf2_msgs::TFMessage mounts;
  for (const std::unique_ptr<SimulatedSensor>& sensor : sensors) {
    for (geometry_msgs::TransformStamped transform : sensor->mountTransforms()) {
      transform.header.stamp = stampOf(config, 0);
      mounts.transforms.push_back(transform);
    }
  }
  bag.write("/tf_static", stampOf(config, 0), mounts,
            latchedConnectionHeader<tf2_msgs::TFMessage>("/simulate_recording"));

  int written_keyframes = -1;
  for (int frame = 0; frame < config.frames; ++frame) {
    const ros::Time stamp = stampOf(config, frame);
    const Eigen::Isometry3d& T_map_base = world.T_map_base[frame];
    tf2_msgs::TFMessage poses;
    poses.transforms.push_back(transformMessage(robot.T_map_odom[frame], "map", "odom", stamp));
    poses.transforms.push_back(
        transformMessage(robot.T_odom_base[frame], "odom", "base_link", stamp));
    bag.write("/tf", stamp, poses);
    if (robot.track) writeSlamPath(config, *robot.track, frame, &written_keyframes, &bag);
    for (const std::unique_ptr<SimulatedSensor>& sensor : sensors) {
      if (frame % sensor->every() != 0) continue;
      sensor->writeFrame(world.scene, T_map_base, frame / sensor->every(), stamp, &bag);
    }
  }
  if (robot.track) writeTruthPath(config, world.T_map_base, &bag);
  bag.close();
  return config.frames;
}

}  // namespace occupancy_fusion
