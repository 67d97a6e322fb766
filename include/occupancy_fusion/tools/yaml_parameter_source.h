// ParameterSource over a YAML file, in the layout `rosparam load` puts under a nodelet's private
// namespace (nested maps: "sensor_model/hit" is sensor_model: {hit: ...}), plus command-line
// overrides given as `--set key=value`. The tools read the same file as the nodelets this way.
#pragma once

#include <map>
#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "occupancy_fusion/params/parameter_source.h"

namespace occupancy_fusion {

class YamlParameterSource : public ParameterSource {
 public:
  // Parses YAML text. `section` (may be empty) picks a top-level map, with '/' for nesting, e.g.
  // "point_cloud_mapper" for a file written for a whole launch file. Throws std::invalid_argument
  // when the text does not parse or the section is missing or not a map.
  static YamlParameterSource fromString(const std::string& yaml_text,
                                        const std::string& section = "");
  // As fromString, for a file; the message names the file.
  static YamlParameterSource fromFile(const std::string& path, const std::string& section = "");
  // Several files read as successive `rosparam load`s into one namespace: maps are merged key by
  // key, and a later file's value replaces an earlier one's. Throws as fromFile, and for none.
  static YamlParameterSource fromFiles(const std::vector<std::string>& paths,
                                       const std::string& section = "");

  // Adds an override from "key=value" (as given to --set); it wins over the file. The value is
  // parsed as the type asked for at get() time. Throws std::invalid_argument without '=' or key.
  void addOverride(const std::string& assignment);
  void addOverride(const std::string& key, const std::string& value);

  bool get(const std::string& key, double* value) const override;
  bool get(const std::string& key, int* value) const override;
  bool get(const std::string& key, bool* value) const override;
  bool get(const std::string& key, std::string* value) const override;
  bool get(const std::string& key, std::vector<std::string>* value) const override;
  bool get(const std::string& key, std::vector<double>* value) const override;

  // Every leaf key of the file (maps flattened with '/') and every override, sorted.
  std::vector<std::string> keys() const override;
  // Overrides that no get() has asked for so far: most likely misspelt keys.
  std::vector<std::string> unreadOverrides() const;

 private:
  explicit YamlParameterSource(YAML::Node root) : root_(std::move(root)) {}

  // The node for a key (an override parsed as YAML, or the file's), or an undefined node.
  // Records the key as read. `origin` tells where the value came from, for error messages.
  YAML::Node find(const std::string& key, std::string* origin) const;
  template <typename T>
  bool getScalar(const std::string& key, const char* type_name, T* value) const;
  template <typename T>
  bool getSequence(const std::string& key, const char* type_name, std::vector<T>* value) const;

  YAML::Node root_;
  std::map<std::string, std::string> overrides_;  // normalised key -> raw text
  mutable std::set<std::string> read_keys_;       // not thread-safe: tools read on one thread
};

}  // namespace occupancy_fusion
