// Simulated 2D laser scanners of the Simulator nodelet: each renders the scene in its scan plane
// (sim::renderScan) and publishes sensor_msgs/LaserScan as a driver would (REP-117 ranges).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <ros/ros.h>

#include "occupancy_fusion/sim/laser_scanner.h"

#include "simulated_sensors.h"

namespace occupancy_fusion {

struct SimulatedLaserScannerConfig {
  std::string name = "laser";  // key of the scanner's parameter block
  std::string topic;           // default "<name>/scan"
  double rate = 10.0;          // Hz
  sim::LaserScanner scanner;   // field of view, resolution, limits, noise
  SensorMount mount;           // the scan's frame (default: the name) on the body

  void validate() const;  // throws std::invalid_argument naming the bad parameter
};

// Under `<name>/`: topic, rate (Hz), angle_min, angle_max, angle_increment (rad), range_min,
// range_max, noise_sigma (m), seed, frame_id, and the mount pose x, y, z (m), roll, pitch, yaw
// (rad) in the body frame.
SimulatedLaserScannerConfig readSimulatedLaserScannerConfig(const ParameterSource& source,
                                                            const std::string& name);

// Publishes <topic> (sensor_msgs/LaserScan in the mount's frame), only while it has subscribers.
class SimulatedLaserScanner : public SimulatedSensor {
 public:
  SimulatedLaserScanner(const ros::NodeHandle& node_handle,
                        const SimulatedLaserScannerConfig& config);

  const std::string& name() const override { return config_.name; }
  double rate() const override { return config_.rate; }
  std::vector<geometry_msgs::TransformStamped> staticTransforms(
      const std::string& body_frame) const override;
  void publish(const sim::Scene& scene, const Eigen::Isometry3d& T_world_body,
               const ros::Time& stamp) override;

 private:
  SimulatedLaserScannerConfig config_;
  ros::Publisher scan_publisher_;
  int frame_index_ = 0;  // varies the noise from scan to scan
};

// Appends one SimulatedLaserScanner per name in `laser_scanners` (space-separated string or
// list; none when absent) to `sensors`.
void appendSimulatedLaserScanners(const ros::NodeHandle& node_handle, const ParameterSource& source,
                                  std::vector<std::unique_ptr<SimulatedSensor>>* sensors);

}  // namespace occupancy_fusion
