// ParameterSource over the ROS parameter server, so the ROS-free config readers
// (params/config_readers.h) read a nodelet's parameters exactly as they read a YAML file.
#pragma once

#include <string>
#include <vector>

#include <ros/node_handle.h>

#include "occupancy_fusion/params/parameter_source.h"

namespace occupancy_fusion {

// Keys are resolved relative to the given handle (a nodelet's private handle, usually).
// Integers are accepted where a double is expected (YAML "resolution: 1"), nothing else is
// converted: a value of the wrong type throws std::invalid_argument naming the resolved key.
class RosParameterSource : public ParameterSource {
 public:
  explicit RosParameterSource(const ros::NodeHandle& node_handle);

  bool get(const std::string& key, double* value) const override;
  bool get(const std::string& key, int* value) const override;
  bool get(const std::string& key, bool* value) const override;
  bool get(const std::string& key, std::string* value) const override;
  bool get(const std::string& key, std::vector<std::string>* value) const override;
  bool get(const std::string& key, std::vector<double>* value) const override;
  // Every parameter under the handle's namespace, relative to it.
  std::vector<std::string> keys() const override;

  const std::string& nameSpace() const { return node_handle_.getNamespace(); }

 private:
  ros::NodeHandle node_handle_;
};

}  // namespace occupancy_fusion
