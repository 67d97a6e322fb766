#include "simulated_stereo_camera.h"

#include <cmath>
#include <stdexcept>

#include <sensor_msgs/CameraInfo.h>
#include <stereo_msgs/DisparityImage.h>

#include "occupancy_fusion/ros/disparity_messages.h"
#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {
namespace {

StereoCamera stereoCamera(const SimulatedStereoCameraConfig& config) {
  StereoCamera camera;
  camera.fx = config.left.camera.fx;
  camera.fy = config.left.camera.fy;
  camera.cx = config.left.camera.cx;
  camera.cy = config.left.camera.cy;
  camera.baseline = config.baseline;
  return camera;
}

}  // namespace

void SimulatedStereoCameraConfig::validate() const {
  left.validate();
  const std::string& name = left.name;
  if (!(baseline > 0.0) || !std::isfinite(baseline)) {
    throw std::invalid_argument(name + "/baseline must be a positive number of m");
  }
  validateUnder(name + "/noise/", noise);
}

SimulatedStereoCameraConfig readSimulatedStereoCameraConfig(const ParameterSource& source,
                                                            const std::string& prefix) {
  SimulatedStereoCameraConfig config;
  config.left = readSimulatedDepthCameraConfig(source, prefix);
  if (!source.get(prefix + "optical_frame_id", &config.left.optical_frame)) {
    config.left.optical_frame = config.left.name + "_left_optical_frame";
  }
  source.get(prefix + "baseline", &config.baseline);
  const std::string noise = prefix + "noise/";
  source.get(noise + "sigma_px", &config.noise.sigma_px);
  source.get(noise + "patches", &config.patches);
  // Defaults: a matcher that gets about 10 % of the image wrong, in patches lasting 2 s at 5 Hz.
  config.noise.patch_probability = 0.2;
  source.get(noise + "patch_probability", &config.noise.patch_probability);
  source.get(noise + "patch_size_px", &config.noise.patch_size_px);
  source.get(noise + "patch_offset_px", &config.noise.patch_offset_px);
  source.get(noise + "patch_persistence_frames", &config.noise.patch_persistence_frames);
  int seed = static_cast<int>(config.noise.seed);
  source.get(noise + "seed", &seed);
  if (seed < 0) throw std::invalid_argument(noise + "seed must be >= 0");
  config.noise.seed = static_cast<std::uint64_t>(seed);
  source.get(noise + "left_right_check", &config.noise.left_right_check);
  if (!config.patches) config.noise.patch_probability = 0.0;
  config.validate();
  return config;
}

SimulatedStereoCamera::SimulatedStereoCamera(const ros::NodeHandle& node_handle,
                                             const SimulatedStereoCameraConfig& config)
    : config_(config) {
  config_.validate();
  ros::NodeHandle camera_handle(node_handle, config_.left.name);
  disparity_publisher_ = camera_handle.advertise<stereo_msgs::DisparityImage>("disparity", 1);
  // Latched: the mapper caches the latest camera_info and may subscribe after it was sent.
  camera_info_publisher_ =
      camera_handle.advertise<sensor_msgs::CameraInfo>("left/camera_info", 1, true);
}

std::vector<geometry_msgs::TransformStamped> SimulatedStereoCamera::staticTransforms(
    const std::string& body_frame) const {
  return cameraStaticTransforms(config_.left, body_frame);
}

void SimulatedStereoCamera::publish(const sim::Scene& scene, const Eigen::Isometry3d& T_world_body,
                                    const ros::Time& stamp) {
  const StereoCamera camera = stereoCamera(config_);
  const int width = config_.left.camera.width;
  const int height = config_.left.camera.height;
  auto info =
      boost::make_shared<sensor_msgs::CameraInfo>(leftCameraInfoMessage(camera, width, height));
  info->header.frame_id = config_.left.optical_frame;
  info->header.stamp = stamp;
  camera_info_publisher_.publish(info);
  if (disparity_publisher_.getNumSubscribers() == 0) return;

  const Eigen::Isometry3d T_world_optical =
      T_world_body * config_.left.mount.T_body_sensor * sim::opticalFrameInBody();
  const sim::DisparityImage rendered =
      sim::renderDisparity(scene, config_.left.camera, config_.baseline, T_world_optical,
                           config_.left.max_range, config_.noise, frame_index_++);
  auto message = boost::make_shared<stereo_msgs::DisparityImage>(
      disparityImageMessage(rendered.disparity, rendered.width, rendered.height, camera));
  message->header = info->header;
  message->image.header = info->header;
  disparity_publisher_.publish(message);
}

}  // namespace occupancy_fusion
