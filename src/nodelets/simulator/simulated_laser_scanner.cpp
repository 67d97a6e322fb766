#include "simulated_laser_scanner.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <sensor_msgs/LaserScan.h>

#include "occupancy_fusion/ros/transform_message.h"

namespace occupancy_fusion {
namespace {

void readScanner(const ParameterSource& source, const std::string& prefix,
                 sim::LaserScanner* scanner) {
  source.get(prefix + "angle_min", &scanner->angle_min);
  source.get(prefix + "angle_max", &scanner->angle_max);
  source.get(prefix + "angle_increment", &scanner->angle_increment);
  source.get(prefix + "range_min", &scanner->range_min);
  source.get(prefix + "range_max", &scanner->range_max);
  source.get(prefix + "noise_sigma", &scanner->noise_sigma);
  int seed = static_cast<int>(scanner->seed);
  source.get(prefix + "seed", &seed);
  scanner->seed = static_cast<std::uint64_t>(seed);
}

std::vector<std::string> readScannerNames(const ParameterSource& source) {
  std::vector<std::string> names;
  std::string joined;
  try {
    source.get("laser_scanners", &joined);
    std::istringstream words(joined);
    for (std::string word; words >> word;) names.push_back(word);
  } catch (const std::invalid_argument&) {
    source.get("laser_scanners", &names);  // a list rather than a string
  }
  return names;
}

}  // namespace

void SimulatedLaserScannerConfig::validate() const {
  if (name.empty()) throw std::invalid_argument("laser scanner name must not be empty");
  if (topic.empty()) throw std::invalid_argument(name + "/topic must not be empty");
  validateSensorRate(name, rate);
  if (mount.frame.empty()) throw std::invalid_argument(name + "/frame_id must not be empty");
  validateUnder(name + "/", scanner);
}

SimulatedLaserScannerConfig readSimulatedLaserScannerConfig(const ParameterSource& source,
                                                            const std::string& name) {
  const std::string prefix = name + "/";
  SimulatedLaserScannerConfig config;
  config.name = name;
  config.topic = name + "/scan";
  config.mount.frame = name;
  source.get(prefix + "topic", &config.topic);
  source.get(prefix + "rate", &config.rate);
  source.get(prefix + "frame_id", &config.mount.frame);
  readScanner(source, prefix, &config.scanner);
  Eigen::Isometry3d default_mount = Eigen::Isometry3d::Identity();
  default_mount.translation() = Eigen::Vector3d(0.0, 0.0, 0.3);  // 0.3 m above the base's origin
  config.mount.T_body_sensor = readMountPose(source, prefix, default_mount);
  config.validate();
  return config;
}

SimulatedLaserScanner::SimulatedLaserScanner(const ros::NodeHandle& node_handle,
                                             const SimulatedLaserScannerConfig& config)
    : config_(config) {
  config_.validate();
  ros::NodeHandle handle(node_handle);
  scan_publisher_ = handle.advertise<sensor_msgs::LaserScan>(config_.topic, 5);
}

std::vector<geometry_msgs::TransformStamped> SimulatedLaserScanner::staticTransforms(
    const std::string& body_frame) const {
  return {transformMessage(config_.mount.T_body_sensor, body_frame, config_.mount.frame,
                           ros::Time::now())};
}

void SimulatedLaserScanner::publish(const sim::Scene& scene, const Eigen::Isometry3d& T_world_body,
                                    const ros::Time& stamp) {
  const int frame_index = frame_index_++;
  if (scan_publisher_.getNumSubscribers() == 0) return;
  const sim::LaserScan scan = sim::renderScan(
      scene, config_.scanner, T_world_body * config_.mount.T_body_sensor, frame_index);
  auto message = boost::make_shared<sensor_msgs::LaserScan>();
  message->header.frame_id = config_.mount.frame;
  message->header.stamp = stamp;
  message->angle_min = static_cast<float>(scan.angle_min);
  message->angle_max = static_cast<float>(scan.angle_max);
  message->angle_increment = static_cast<float>(scan.angle_increment);
  message->time_increment = 0.0f;  // every beam of a simulated scan is taken at `stamp`
  message->scan_time = static_cast<float>(1.0 / config_.rate);
  message->range_min = static_cast<float>(scan.range_min);
  message->range_max = static_cast<float>(scan.range_max);
  message->ranges = scan.ranges;
  scan_publisher_.publish(message);
}

void appendSimulatedLaserScanners(const ros::NodeHandle& node_handle, const ParameterSource& source,
                                  std::vector<std::unique_ptr<SimulatedSensor>>* sensors) {
  for (const std::string& name : readScannerNames(source)) {
    sensors->push_back(std::make_unique<SimulatedLaserScanner>(
        node_handle, readSimulatedLaserScannerConfig(source, name)));
  }
}

}  // namespace occupancy_fusion
