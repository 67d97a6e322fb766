// A flat key -> value ParameterSource for tests of the config readers; get() with the wrong type
// throws as the real sources (ROS parameters, YAML) do.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "occupancy_fusion/params/parameter_source.h"

namespace occupancy_fusion {

class MapParameterSource : public ParameterSource {
 public:
  using Value = std::variant<double, int, bool, std::string, std::vector<std::string>>;
  explicit MapParameterSource(std::map<std::string, Value> values) : values_(std::move(values)) {}

  bool get(const std::string& key, double* value) const override { return read(key, value); }
  bool get(const std::string& key, int* value) const override { return read(key, value); }
  bool get(const std::string& key, bool* value) const override { return read(key, value); }
  bool get(const std::string& key, std::string* value) const override { return read(key, value); }
  bool get(const std::string& key, std::vector<std::string>* value) const override {
    return read(key, value);
  }
  bool get(const std::string&, std::vector<double>*) const override { return false; }

 private:
  template <typename T>
  bool read(const std::string& key, T* value) const {
    const auto found = values_.find(key);
    if (found == values_.end()) return false;
    if (const T* typed = std::get_if<T>(&found->second)) {
      *value = *typed;
      return true;
    }
    throw std::invalid_argument(key + " has the wrong type");
  }
  std::map<std::string, Value> values_;
};

}  // namespace occupancy_fusion
