// Simulator nodelet: a robot drives a circle through an analytic scene, or the building's corridor
// loop; publishes TF (map -> odom -> base_link -> sensor frames) and the data of its simulated
// sensors, stamped with the current time. On the loop its odometry may drift, and a graph-SLAM
// stand-in then publishes map -> odom and its keyframe path, correcting both at loop closures.
// An obstacle box may be put into the scene and taken away (~set_obstacle) while the sensors look.
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <std_srvs/SetBool.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <pluginlib/class_list_macros.hpp>

#include "occupancy_fusion/ros/path_message.h"
#include "occupancy_fusion/ros/ros_parameter_source.h"
#include "occupancy_fusion/ros/transform_message.h"
#include "occupancy_fusion/sim/scenes.h"

#include "simulated_laser_scanner.h"
#include "simulated_localisation.h"
#include "simulated_sensors.h"
#include "simulated_stereo_camera.h"

namespace occupancy_fusion {
namespace {

sim::Scene sceneNamed(const std::string& name) {
  if (name == "room") return sim::makeRoomScene();
  if (name == "box") return sim::makeBoxScene();
  if (name == "spheres") return sim::makeSpheresScene();
  if (name == "corridor") return sim::makeCorridorScene();
  if (name == "building") return sim::makeBuildingFloorScene();
  throw std::invalid_argument("scene must be one of room, box, spheres, corridor, building; got '" +
                              name + "'");
}

// The robot's path: a horizontal circle at constant speed, the body turned by yaw_offset from
// the outward radial direction, so a forward-looking sensor sweeps the whole surroundings.
struct CirclePath {
  double center_x = 0.0;    // m
  double center_y = 0.0;    // m
  double radius = 0.5;      // m
  double period = 20.0;     // s per turn
  double yaw_offset = 0.0;  // rad

  void validate() const {
    if (!(radius >= 0.0)) throw std::invalid_argument("trajectory/radius must be >= 0 (m)");
    if (!(period > 0.0)) throw std::invalid_argument("trajectory/period must be positive (s)");
  }

  Eigen::Isometry3d bodyPoseAt(double seconds) const {
    const double phase = 2.0 * M_PI * seconds / period;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(center_x + radius * std::cos(phase),
                                         center_y + radius * std::sin(phase), 0.0);
    pose.linear() =
        Eigen::AngleAxisd(phase + yaw_offset, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    return pose;
  }
};

// obstacle/box: [min_x, min_y, min_z, max_x, max_y, max_z] (m, map frame), or none.
std::optional<sim::Box> readObstacleBox(const ParameterSource& source) {
  std::vector<double> corners;
  if (!source.get("obstacle/box", &corners) || corners.empty()) return std::nullopt;
  if (corners.size() != 6 || corners[0] >= corners[3] || corners[1] >= corners[4] ||
      corners[2] >= corners[5]) {
    throw std::invalid_argument(
        "obstacle/box must be [min_x, min_y, min_z, max_x, max_y, max_z] with each min < max");
  }
  return sim::Box::axisAligned(Eigen::Vector3d(corners[0], corners[1], corners[2]),
                               Eigen::Vector3d(corners[3], corners[4], corners[5]));
}

CirclePath readCirclePath(const ParameterSource& source) {
  CirclePath path;
  source.get("trajectory/center_x", &path.center_x);
  source.get("trajectory/center_y", &path.center_y);
  source.get("trajectory/radius", &path.radius);
  source.get("trajectory/period", &path.period);
  source.get("trajectory/yaw_offset", &path.yaw_offset);
  path.validate();
  return path;
}

}  // namespace

class Simulator : public nodelet::Nodelet {
 private:
  void onInit() override {
    const RosParameterSource parameters(getPrivateNodeHandle());
    try {
      readParameters(parameters);
    } catch (const std::invalid_argument& error) {
      NODELET_FATAL("invalid parameter: %s", error.what());
      throw;
    }
    start_ = ros::Time::now();
    if (drifting()) {
      path_publisher_ = getNodeHandle().advertise<nav_msgs::Path>("slam/path", 1, /*latch=*/true);
    }
    publishStaticTransforms();
    pause_service_ = getPrivateNodeHandle().advertiseService("pause", &Simulator::onPause, this);
    obstacle_service_ =
        getPrivateNodeHandle().advertiseService("set_obstacle", &Simulator::onSetObstacle, this);
    ros::NodeHandle& node_handle = getNodeHandle();
    tf_timer_ = node_handle.createTimer(
        ros::Duration(1.0 / tf_rate_),
        [this](const ros::TimerEvent&) { publishBodyPose(ros::Time::now()); });
    for (const std::unique_ptr<SimulatedSensor>& sensor : sensors_) {
      SimulatedSensor* raw = sensor.get();
      sensor_timers_.push_back(node_handle.createTimer(
          ros::Duration(1.0 / raw->rate()), [this, raw](const ros::TimerEvent&) {
            // The body pose at exactly the data's stamp goes out first, so tf2 message filters
            // downstream release the data without waiting for the next TF tick.
            if (paused_) return;
            const ros::Time stamp = ros::Time::now();
            publishBodyPose(stamp);
            raw->publish(scene_, bodyPoseAt(stamp), stamp);
          }));
    }
    NODELET_INFO("simulating scene '%s' with %zu sensor(s)%s", scene_name_.c_str(), sensors_.size(),
                 drifting() ? ", drifting odometry and a SLAM stand-in" : "");
  }

  void readParameters(const ParameterSource& parameters) {
    parameters.get("scene", &scene_name_);
    obstacle_ = readObstacleBox(parameters);
    parameters.get("obstacle/present", &obstacle_present_);
    composeScene();
    parameters.get("map_frame", &map_frame_);
    parameters.get("odom_frame", &odom_frame_);
    parameters.get("base_frame", &base_frame_);
    parameters.get("tf_rate", &tf_rate_);
    if (!(tf_rate_ > 0.0)) throw std::invalid_argument("tf_rate must be a positive number of Hz");
    readTrajectory(parameters);
    sensors_.push_back(std::make_unique<SimulatedDepthCamera>(
        getNodeHandle(), readSimulatedDepthCameraConfig(parameters, "camera/")));
    appendSimulatedLaserScanners(getNodeHandle(), parameters, &sensors_);
    sensors_.push_back(std::make_unique<SimulatedStereoCamera>(
        getNodeHandle(), readSimulatedStereoCameraConfig(parameters, "stereo/")));
  }

  // trajectory/type: circle (CirclePath), or loop (the building's corridor loop, with drift/ and
  // localisation/ for its odometry and SLAM stand-in).
  void readTrajectory(const ParameterSource& parameters) {
    std::string type = "circle";
    parameters.get("trajectory/type", &type);
    bool drift = false;
    parameters.get("drift/enabled", &drift);
    if (type == "circle") {
      if (drift) throw std::invalid_argument("drift/enabled needs trajectory/type loop");
      path_ = readCirclePath(parameters);
    } else if (type == "loop") {
      if (scene_name_ != "building") {
        throw std::invalid_argument(
            "trajectory/type loop drives the building's corridor loop: scene must be building");
      }
      loop_.emplace(readLoopMotionConfig(parameters), tf_rate_);
      parameters.get("localisation/publish_map_to_odom", &publish_map_to_odom_);
    } else {
      throw std::invalid_argument("trajectory/type must be circle or loop; got '" + type + "'");
    }
  }

  bool drifting() const { return loop_ && loop_->track(); }

  // The robot stands still while paused: path time excludes the paused intervals.
  double pathSeconds(const ros::Time& stamp) const {
    const ros::Time path_clock = paused_ ? pause_start_ : stamp;
    return (path_clock - start_ - paused_total_).toSec();
  }

  // The true body pose in the map: what the sensors see.
  Eigen::Isometry3d bodyPoseAt(const ros::Time& stamp) const {
    const double seconds = pathSeconds(stamp);
    return loop_ ? loop_->truth(loop_->frameAt(seconds)) : path_.bodyPoseAt(seconds);
  }

  // ~pause (std_srvs/SetBool): true stops the robot and the sensor data (TF keeps flowing), false
  // resumes. Lets a test or a demo freeze the map while it inspects it.
  bool onPause(std_srvs::SetBool::Request& request, std_srvs::SetBool::Response& response) {
    const ros::Time now = ros::Time::now();
    if (request.data && !paused_) pause_start_ = now;
    if (!request.data && paused_) paused_total_ += now - pause_start_;
    paused_ = request.data;
    response.success = true;
    response.message = paused_ ? "paused" : "running";
    NODELET_INFO("simulation %s", response.message.c_str());
    return true;
  }

  // The named scene, with the obstacle while it is present. Sensor timers and services share the
  // nodelet's one callback queue, so no frame renders a scene being replaced.
  void composeScene() {
    scene_ = sceneNamed(scene_name_);
    if (obstacle_ && obstacle_present_) scene_.add(*obstacle_);
  }

  // ~set_obstacle (std_srvs/SetBool): true puts obstacle/box into the scene, false takes it away.
  bool onSetObstacle(std_srvs::SetBool::Request& request, std_srvs::SetBool::Response& response) {
    if (!obstacle_) {
      response.success = false;
      response.message = "no obstacle/box given";
      return true;
    }
    obstacle_present_ = request.data;
    composeScene();
    response.success = true;
    response.message = obstacle_present_ ? "obstacle in the scene" : "obstacle taken away";
    NODELET_INFO("%s", response.message.c_str());
    return true;
  }

  void publishStaticTransforms() {
    // Without drift odom coincides with map; with it, map -> odom moves (publishBodyPose).
    std::vector<geometry_msgs::TransformStamped> transforms;
    if (!drifting()) {
      transforms.push_back(
          transformMessage(Eigen::Isometry3d::Identity(), map_frame_, odom_frame_, start_));
    }
    for (const std::unique_ptr<SimulatedSensor>& sensor : sensors_) {
      for (const auto& transform : sensor->staticTransforms(base_frame_)) {
        transforms.push_back(transform);
      }
    }
    static_broadcaster_.sendTransform(transforms);
  }

  void publishBodyPose(const ros::Time& stamp) {
    if (stamp == last_body_stamp_) return;  // tf2 rejects repeated stamps
    last_body_stamp_ = stamp;
    if (!loop_) {
      broadcaster_.sendTransform(
          transformMessage(bodyPoseAt(stamp), odom_frame_, base_frame_, stamp));
      return;
    }
    const int frame = loop_->frameAt(pathSeconds(stamp));
    std::vector<geometry_msgs::TransformStamped> transforms = {
        transformMessage(loop_->odometry(frame), odom_frame_, base_frame_, stamp)};
    if (drifting() && publish_map_to_odom_) {
      transforms.push_back(
          transformMessage(loop_->mapToOdom(frame), map_frame_, odom_frame_, stamp));
    }
    broadcaster_.sendTransform(transforms);
    if (drifting()) publishSlamPath(frame, stamp);
  }

  // slam/path (latched) whenever the stand-in's keyframe path changes: a keyframe is added or the
  // past is corrected.
  void publishSlamPath(int frame, const ros::Time& stamp) {
    const sim::LocalisationTrack& track = *loop_->track();
    const int keyframes = track.keyframeCountAt(frame);
    const int correction = track.lastCorrectionAt(frame);
    if (keyframes == published_keyframes_ && correction == published_correction_) return;
    // A keyframe's stamp: when the robot was at its frame, on the path clock of now.
    while (static_cast<int>(keyframe_stamps_.size()) < keyframes) {
      const int keyframe_frame = track.keyframe_frames[keyframe_stamps_.size()];
      keyframe_stamps_.push_back(stamp - ros::Duration((frame - keyframe_frame) / tf_rate_));
    }
    path_publisher_.publish(pathMessage(track.pathAt(frame), keyframe_stamps_, map_frame_, stamp));
    published_keyframes_ = keyframes;
    published_correction_ = correction;
  }

  std::string scene_name_ = "room";
  std::optional<sim::Box> obstacle_;
  bool obstacle_present_ = true;
  sim::Scene scene_;
  std::string map_frame_ = "map";
  std::string odom_frame_ = "odom";
  std::string base_frame_ = "base_link";
  double tf_rate_ = 30.0;
  CirclePath path_;
  std::optional<LoopMotion> loop_;   // trajectory/type loop
  bool publish_map_to_odom_ = true;  // localisation/publish_map_to_odom (with drift)
  std::vector<std::unique_ptr<SimulatedSensor>> sensors_;

  ros::Time start_;
  ros::Time last_body_stamp_;
  bool paused_ = false;
  ros::Time pause_start_;
  ros::Duration paused_total_;
  ros::ServiceServer pause_service_;
  ros::ServiceServer obstacle_service_;
  ros::Publisher path_publisher_;
  std::vector<ros::Time> keyframe_stamps_;  // of the keyframes published so far
  int published_keyframes_ = -1;
  int published_correction_ = -1;
  tf2_ros::TransformBroadcaster broadcaster_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
  ros::Timer tf_timer_;
  std::vector<ros::Timer> sensor_timers_;
};

}  // namespace occupancy_fusion

PLUGINLIB_EXPORT_CLASS(occupancy_fusion::Simulator, nodelet::Nodelet)
