#include "simulated_sensors.h"

#include <cmath>
#include <stdexcept>

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/fill_image.h>
#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include "occupancy_fusion/ros/camera_info_message.h"
#include "occupancy_fusion/ros/conversions.h"
#include "occupancy_fusion/ros/transform_message.h"
#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {

Eigen::Isometry3d readMountPose(const ParameterSource& source, const std::string& prefix,
                                const Eigen::Isometry3d& default_pose) {
  Eigen::Vector3d position = default_pose.translation();
  source.get(prefix + "x", &position.x());
  source.get(prefix + "y", &position.y());
  source.get(prefix + "z", &position.z());
  const Eigen::Vector3d default_ypr = default_pose.linear().eulerAngles(2, 1, 0);
  double yaw = default_ypr[0], pitch = default_ypr[1], roll = default_ypr[2];
  source.get(prefix + "roll", &roll);
  source.get(prefix + "pitch", &pitch);
  source.get(prefix + "yaw", &yaw);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = position;
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  return pose;
}

void validateSensorRate(const std::string& name, double rate) {
  if (!(rate > 0.0) || !std::isfinite(rate)) {
    throw std::invalid_argument(name + "/rate must be a positive number of Hz");
  }
}

void SimulatedDepthCameraConfig::validate() const {
  if (name.empty()) throw std::invalid_argument("camera name must not be empty");
  validateSensorRate(name, rate);
  if (!(max_range > 0.0)) throw std::invalid_argument(name + "/max_range must be positive (m)");
  if (mount.frame.empty() || optical_frame.empty()) {
    throw std::invalid_argument(name + "/frame_id and " + name +
                                "/optical_frame_id must not be empty");
  }
  validateUnder(name + "/", camera);
}

SimulatedDepthCameraConfig readSimulatedDepthCameraConfig(const ParameterSource& source,
                                                          const std::string& prefix) {
  SimulatedDepthCameraConfig config;
  config.name = prefix.empty() ? "camera" : prefix.substr(0, prefix.find('/'));
  config.mount.frame = config.name + "_link";
  config.optical_frame = config.name + "_depth_optical_frame";
  // A camera 1 m above the base, pitched down 20 deg, sees the floor in front of the robot.
  Eigen::Isometry3d default_mount = Eigen::Isometry3d::Identity();
  default_mount.translation() = Eigen::Vector3d(0.1, 0.0, 1.0);
  default_mount.linear() =
      Eigen::AngleAxisd(20.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();

  source.get(prefix + "rate", &config.rate);
  source.get(prefix + "max_range", &config.max_range);
  int width = 320, height = 240;
  source.get(prefix + "width", &width);
  source.get(prefix + "height", &height);
  config.camera.width = width;
  config.camera.height = height;
  config.camera.fx = config.camera.fy = 0.82 * width;  // about 63 deg horizontal field of view
  config.camera.cx = 0.5 * (width - 1);
  config.camera.cy = 0.5 * (height - 1);
  source.get(prefix + "fx", &config.camera.fx);
  source.get(prefix + "fy", &config.camera.fy);
  source.get(prefix + "cx", &config.camera.cx);
  source.get(prefix + "cy", &config.camera.cy);
  source.get(prefix + "frame_id", &config.mount.frame);
  source.get(prefix + "optical_frame_id", &config.optical_frame);
  config.mount.T_body_sensor = readMountPose(source, prefix, default_mount);
  config.validate();
  return config;
}

SimulatedDepthCamera::SimulatedDepthCamera(const ros::NodeHandle& node_handle,
                                           const SimulatedDepthCameraConfig& config)
    : config_(config), image_transport_(ros::NodeHandle(node_handle, config.name)) {
  config_.validate();
  ros::NodeHandle camera_handle(node_handle, config_.name);
  depth_publisher_ = image_transport_.advertiseCamera("depth/image", 1);
  cloud_publisher_ = camera_handle.advertise<sensor_msgs::PointCloud2>("depth/points", 1);
}

std::vector<geometry_msgs::TransformStamped> cameraStaticTransforms(
    const SimulatedDepthCameraConfig& camera, const std::string& body_frame) {
  const ros::Time now = ros::Time::now();
  return {
      transformMessage(camera.mount.T_body_sensor, body_frame, camera.mount.frame, now),
      transformMessage(sim::opticalFrameInBody(), camera.mount.frame, camera.optical_frame, now)};
}

std::vector<geometry_msgs::TransformStamped> SimulatedDepthCamera::staticTransforms(
    const std::string& body_frame) const {
  return cameraStaticTransforms(config_, body_frame);
}

void SimulatedDepthCamera::publish(const sim::Scene& scene, const Eigen::Isometry3d& T_world_body,
                                   const ros::Time& stamp) {
  const bool want_image = depth_publisher_.getNumSubscribers() > 0;
  const bool want_cloud = cloud_publisher_.getNumSubscribers() > 0;
  if (!want_image && !want_cloud) return;
  const Eigen::Isometry3d T_world_optical =
      T_world_body * config_.mount.T_body_sensor * sim::opticalFrameInBody();
  const sim::DepthImage depth =
      sim::renderDepth(scene, config_.camera, T_world_optical, config_.max_range);

  if (want_image) {
    auto image = boost::make_shared<sensor_msgs::Image>();
    image->header.frame_id = config_.optical_frame;
    image->header.stamp = stamp;
    sensor_msgs::fillImage(*image, sensor_msgs::image_encodings::TYPE_32FC1, depth.height,
                           depth.width, depth.width * sizeof(float), depth.depth.data());
    auto info = boost::make_shared<sensor_msgs::CameraInfo>(
        cameraInfoMessage(config_.camera, image->header.frame_id, image->header.stamp));
    depth_publisher_.publish(image, info);
  }
  if (want_cloud) {
    const std::vector<Eigen::Vector3d> points = sim::depthToPointCloud(depth, config_.camera);
    auto cloud = boost::make_shared<sensor_msgs::PointCloud2>();
    cloud->header.frame_id = config_.optical_frame;
    cloud->header.stamp = stamp;
    resizeXyzCloud(points.size(), cloud.get());
    sensor_msgs::PointCloud2Iterator<float> x(*cloud, "x"), y(*cloud, "y"), z(*cloud, "z");
    for (const Eigen::Vector3d& point : points) {
      *x = static_cast<float>(point.x());
      *y = static_cast<float>(point.y());
      *z = static_cast<float>(point.z());
      ++x, ++y, ++z;
    }
    cloud_publisher_.publish(cloud);
  }
}

}  // namespace occupancy_fusion
