#include "occupancy_fusion/tools/yaml_parameter_source.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace occupancy_fusion {
namespace {

std::vector<std::string> splitKey(const std::string& key) {
  std::vector<std::string> parts;
  std::stringstream stream(key);
  std::string part;
  while (std::getline(stream, part, '/')) {
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

// "/a//b/" and "a/b" name the same parameter.
std::string normaliseKey(const std::string& key) {
  std::string joined;
  for (const std::string& part : splitKey(key)) joined += (joined.empty() ? "" : "/") + part;
  return joined;
}

// Follows the parts of a key through nested maps; an undefined node when any level is missing.
// (yaml-cpp's operator[] on a const node never inserts.)
YAML::Node descend(const YAML::Node& root, const std::vector<std::string>& parts) {
  YAML::Node node = root;
  for (const std::string& part : parts) {
    if (!node.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
    const YAML::Node& const_node = node;
    YAML::Node child = const_node[part];
    if (!child.IsDefined()) return YAML::Node(YAML::NodeType::Undefined);
    node.reset(child);  // rebind; operator= would overwrite the parent's content
  }
  return node;
}

void collectLeafKeys(const YAML::Node& node, const std::string& prefix,
                     std::set<std::string>* keys) {
  if (!node.IsMap()) {
    if (!prefix.empty()) keys->insert(prefix);
    return;
  }
  for (const auto& entry : node) {
    const std::string name = entry.first.as<std::string>();
    collectLeafKeys(entry.second, prefix.empty() ? name : prefix + "/" + name, keys);
  }
}

// overlay laid over base: maps merge key by key, anything else replaces. Works on clones, so
// neither input changes (yaml-cpp nodes share their data).
YAML::Node merged(const YAML::Node& base, const YAML::Node& overlay) {
  if (!base.IsMap() || !overlay.IsMap()) return YAML::Clone(overlay);
  YAML::Node result = YAML::Clone(base);
  for (const auto& entry : overlay) {
    const std::string key = entry.first.as<std::string>();
    const YAML::Node existing = base[key];  // const lookup: inserts nothing
    result[key] = existing.IsDefined() ? merged(existing, entry.second) : YAML::Clone(entry.second);
  }
  return result;
}

std::invalid_argument wrongType(const std::string& key, const std::string& origin,
                                const char* type_name, const YAML::Node& node) {
  std::string shown = node.IsScalar() ? "'" + node.Scalar() + "'" : "a non-scalar value";
  return std::invalid_argument("parameter '" + key + "' (" + origin + "): expected " + type_name +
                               ", got " + shown);
}

}  // namespace

YamlParameterSource YamlParameterSource::fromString(const std::string& yaml_text,
                                                    const std::string& section) {
  YAML::Node root;
  try {
    root.reset(YAML::Load(yaml_text));
  } catch (const YAML::Exception& error) {
    throw std::invalid_argument(std::string("YAML does not parse: ") + error.what());
  }
  if (root.IsNull()) root.reset(YAML::Node(YAML::NodeType::Map));  // an empty file sets nothing
  if (!section.empty()) {
    root.reset(descend(root, splitKey(section)));
    if (!root.IsDefined()) throw std::invalid_argument("YAML has no section '" + section + "'");
  }
  if (!root.IsMap()) {
    throw std::invalid_argument(
        "YAML " + (section.empty() ? std::string("top level") : "section '" + section + "'") +
        " is not a map of parameters");
  }
  return YamlParameterSource(root);
}

YamlParameterSource YamlParameterSource::fromFile(const std::string& path,
                                                  const std::string& section) {
  std::ifstream file(path);
  if (!file) throw std::invalid_argument("cannot read parameter file '" + path + "'");
  std::stringstream text;
  text << file.rdbuf();
  try {
    return fromString(text.str(), section);
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument("parameter file '" + path + "': " + error.what());
  }
}

YamlParameterSource YamlParameterSource::fromFiles(const std::vector<std::string>& paths,
                                                   const std::string& section) {
  if (paths.empty()) throw std::invalid_argument("no parameter file given");
  YAML::Node root(YAML::NodeType::Map);
  for (const std::string& path : paths) root.reset(merged(root, fromFile(path, section).root_));
  return YamlParameterSource(root);
}

void YamlParameterSource::addOverride(const std::string& assignment) {
  const std::size_t equals = assignment.find('=');
  if (equals == std::string::npos) {
    throw std::invalid_argument("--set '" + assignment + "': expected key=value");
  }
  addOverride(assignment.substr(0, equals), assignment.substr(equals + 1));
}

void YamlParameterSource::addOverride(const std::string& key, const std::string& value) {
  const std::string normalised = normaliseKey(key);
  if (normalised.empty()) throw std::invalid_argument("--set with an empty key");
  overrides_[normalised] = value;
}

YAML::Node YamlParameterSource::find(const std::string& key, std::string* origin) const {
  const std::string normalised = normaliseKey(key);
  read_keys_.insert(normalised);
  const auto override_entry = overrides_.find(normalised);
  if (override_entry == overrides_.end()) {
    *origin = "from the parameter file";
    return descend(root_, splitKey(normalised));
  }
  *origin = "from --set " + normalised + "=" + override_entry->second;
  try {
    return YAML::Load(override_entry->second);
  } catch (const YAML::Exception&) {
    // Not YAML (e.g. "[1,"): keep the raw text, so the type check below names the key.
    return YAML::Node(override_entry->second);
  }
}

template <typename T>
bool YamlParameterSource::getScalar(const std::string& key, const char* type_name, T* value) const {
  std::string origin;
  const YAML::Node node = find(key, &origin);
  if (!node.IsDefined()) return false;
  if (!node.IsScalar()) throw wrongType(key, origin, type_name, node);
  try {
    *value = node.as<T>();
  } catch (const YAML::Exception&) {
    throw wrongType(key, origin, type_name, node);
  }
  return true;
}

template <typename T>
bool YamlParameterSource::getSequence(const std::string& key, const char* type_name,
                                      std::vector<T>* value) const {
  std::string origin;
  const YAML::Node node = find(key, &origin);
  if (!node.IsDefined()) return false;
  if (!node.IsSequence()) throw wrongType(key, origin, type_name, node);
  std::vector<T> parsed;
  for (const YAML::Node& element : node) {
    if (!element.IsScalar()) throw wrongType(key, origin, type_name, element);
    try {
      parsed.push_back(element.as<T>());
    } catch (const YAML::Exception&) {
      throw wrongType(key, origin, type_name, element);
    }
  }
  *value = std::move(parsed);
  return true;
}

bool YamlParameterSource::get(const std::string& key, double* value) const {
  return getScalar(key, "a number", value);
}

bool YamlParameterSource::get(const std::string& key, int* value) const {
  return getScalar(key, "an integer", value);
}

bool YamlParameterSource::get(const std::string& key, bool* value) const {
  return getScalar(key, "true or false", value);
}

bool YamlParameterSource::get(const std::string& key, std::string* value) const {
  const std::string normalised = normaliseKey(key);
  const auto override_entry = overrides_.find(normalised);
  if (override_entry != overrides_.end()) {
    // Strings from --set are taken verbatim: "--set frame_id=yes" means the frame "yes".
    read_keys_.insert(normalised);
    *value = override_entry->second;
    return true;
  }
  return getScalar(key, "a string", value);
}

bool YamlParameterSource::get(const std::string& key, std::vector<std::string>* value) const {
  return getSequence(key, "a list of strings", value);
}

bool YamlParameterSource::get(const std::string& key, std::vector<double>* value) const {
  return getSequence(key, "a list of numbers", value);
}

std::vector<std::string> YamlParameterSource::keys() const {
  std::set<std::string> all;
  collectLeafKeys(root_, "", &all);
  for (const auto& entry : overrides_) all.insert(entry.first);
  return {all.begin(), all.end()};
}

std::vector<std::string> YamlParameterSource::unreadOverrides() const {
  std::vector<std::string> unread;
  for (const auto& entry : overrides_) {
    if (read_keys_.count(entry.first) == 0) unread.push_back(entry.first);
  }
  return unread;
}

}  // namespace occupancy_fusion
