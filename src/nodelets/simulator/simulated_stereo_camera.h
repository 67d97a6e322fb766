// A simulated rectified stereo pair for the Simulator nodelet, publishing what stereo_image_proc
// would: <name>/disparity (stereo_msgs/DisparityImage of the left camera, 32FC1) and
// <name>/left/camera_info, with the matcher's errors of sim::DisparityNoise (white noise and
// patches of wrong disparity that persist over several frames).
#pragma once

#include <string>
#include <vector>

#include <ros/ros.h>

#include "occupancy_fusion/sim/stereo_camera.h"

#include "simulated_sensors.h"

namespace occupancy_fusion {

struct SimulatedStereoCameraConfig {
  // name, rate, max_range, intrinsics and mount as a depth camera's; the optical frame is the
  // left camera's.
  SimulatedDepthCameraConfig left;
  double baseline = 0.12;  // m, right camera along the left optical frame's +x
  // Patches off: only the white noise of noise.sigma_px.
  bool patches = true;
  sim::DisparityNoise noise;

  void validate() const;  // throws std::invalid_argument naming the bad parameter
};

// Under `prefix` (e.g. "stereo/"): everything readSimulatedDepthCameraConfig reads (the optical
// frame defaults to "<name>_left_optical_frame"), baseline (m), and noise/sigma_px,
// noise/patches (bool), noise/patch_probability, noise/patch_size_px, noise/patch_offset_px,
// noise/patch_persistence_frames, noise/seed, noise/left_right_check.
SimulatedStereoCameraConfig readSimulatedStereoCameraConfig(const ParameterSource& source,
                                                            const std::string& prefix);

class SimulatedStereoCamera : public SimulatedSensor {
 public:
  SimulatedStereoCamera(const ros::NodeHandle& node_handle,
                        const SimulatedStereoCameraConfig& config);

  const std::string& name() const override { return config_.left.name; }
  double rate() const override { return config_.left.rate; }
  std::vector<geometry_msgs::TransformStamped> staticTransforms(
      const std::string& body_frame) const override;
  // Frames are numbered in publishing order, so the patch layout persists over
  // noise.patch_persistence_frames published images.
  void publish(const sim::Scene& scene, const Eigen::Isometry3d& T_world_body,
               const ros::Time& stamp) override;

 private:
  SimulatedStereoCameraConfig config_;
  ros::Publisher disparity_publisher_;
  ros::Publisher camera_info_publisher_;
  int frame_index_ = 0;
};

}  // namespace occupancy_fusion
