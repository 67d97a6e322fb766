// Where configuration values come from: the ROS parameter server (nodelets) or a YAML file
// (offline_mapper, benchmark). One reader per config struct works with both, so a YAML file
// loaded with rosparam and given to offline_mapper configures both the same way.
#pragma once

#include <string>
#include <vector>

namespace occupancy_fusion {

// Keys are relative names with '/' separating levels, e.g. "sensor_model/hit".
// Each get() leaves *value unchanged and returns false when the key is absent; a present key of
// the wrong type throws std::invalid_argument naming the key.
class ParameterSource {
 public:
  virtual ~ParameterSource() = default;
  virtual bool get(const std::string& key, double* value) const = 0;
  virtual bool get(const std::string& key, int* value) const = 0;
  virtual bool get(const std::string& key, bool* value) const = 0;
  virtual bool get(const std::string& key, std::string* value) const = 0;
  virtual bool get(const std::string& key, std::vector<std::string>* value) const = 0;
  virtual bool get(const std::string& key, std::vector<double>* value) const = 0;
  // Every key this source reads from, for documentation checks; may be empty.
  virtual std::vector<std::string> keys() const { return {}; }
};

}  // namespace occupancy_fusion
