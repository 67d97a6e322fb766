#include "occupancy_fusion/params/laser_config_reader.h"

#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

namespace occupancy_fusion {
namespace {

constexpr char kSharedLaserPrefix[] = "laser/";

std::string describe(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

void require(bool ok, const std::string& key, const std::string& requirement, double value) {
  if (!ok) {
    throw std::invalid_argument(key + " must be " + requirement + ", got " + describe(value));
  }
}

// Reads `prefix + name` when present, checks it with `is_valid` (message: `requirement`) and only
// then stores it, so a bad value is reported under the key it was read from.
template <typename Check>
void readChecked(const ParameterSource& source, const std::string& prefix, const std::string& name,
                 const std::string& requirement, Check is_valid, double* value) {
  double read = *value;
  if (source.get(prefix + name, &read)) {
    require(is_valid(read), prefix + name, requirement, read);
    *value = read;
  }
}

bool isFinitePositive(double v) { return std::isfinite(v) && v > 0.0; }
bool isFiniteNonNegative(double v) { return std::isfinite(v) && v >= 0.0; }

void readSensorModel(const ParameterSource& source, const std::string& prefix,
                     LaserSensorModelConfig* model) {
  readChecked(source, prefix, "range_resolution", "finite and > 0", isFinitePositive,
              &model->range_resolution);
  readChecked(source, prefix, "range_sigma", "finite and >= 0", isFiniteNonNegative,
              &model->range_sigma);
  readChecked(
      source, prefix, "prior", "in (0, 1)", [](double v) { return v > 0.0 && v < 1.0; },
      &model->prior_occupancy);
  readChecked(
      source, prefix, "min_log_ratio", "finite and < 0",
      [](double v) { return std::isfinite(v) && v < 0.0; }, &model->min_log_ratio);
  readChecked(source, prefix, "max_log_ratio", "finite and > 0", isFinitePositive,
              &model->max_log_ratio);
  readChecked(source, prefix, "no_return_free_length", "finite and >= 0 (0: +inf observes nothing)",
              isFiniteNonNegative, &model->no_return_free_length);
  readChecked(source, prefix, "negligible_log_ratio", "finite and >= 0", isFiniteNonNegative,
              &model->negligible_log_ratio);
  source.get(prefix + "above_range_max_is_no_return", &model->ranges.above_range_max_is_no_return);
}

void readMethod(const ParameterSource& source, const std::string& prefix,
                PolarToCartesianMethod* method) {
  std::string name;
  if (!source.get(prefix + "method", &name)) return;
  try {
    *method = parsePolarToCartesianMethod(name);
  } catch (const std::invalid_argument&) {
    throw std::invalid_argument(
        prefix + "method must be one of exact, sampling, mipmap, lines, got '" + name + "'");
  }
}

void readPositiveInt(const ParameterSource& source, const std::string& key, int* value) {
  int read = *value;
  if (source.get(key, &read)) {
    require(read >= 1, key, ">= 1", read);
    *value = read;
  }
}

// costmap_2d writes observation_sources as one space-separated string; a YAML list is accepted too.
std::vector<std::string> readSourceNames(const ParameterSource& source) {
  std::vector<std::string> names;
  std::string joined;
  bool present = false;
  try {
    present = source.get("observation_sources", &joined);
    std::istringstream words(joined);
    for (std::string word; words >> word;) names.push_back(word);
  } catch (const std::invalid_argument&) {
    present = source.get("observation_sources", &names);  // not a string: a list
  }
  if (!present || names.empty()) {
    throw std::invalid_argument(
        "observation_sources must name at least one laser source, e.g. \"front rear\"");
  }
  std::set<std::string> seen;
  for (const auto& name : names) {
    if (!seen.insert(name).second) {
      throw std::invalid_argument("observation_sources names '" + name + "' twice");
    }
  }
  return names;
}

}  // namespace

PolarLaserIntegratorConfig readPolarLaserIntegratorConfig(
    const ParameterSource& source, const std::string& prefix,
    const PolarLaserIntegratorConfig& defaults) {
  PolarLaserIntegratorConfig config = defaults;
  readMethod(source, prefix, &config.method);
  readSensorModel(source, prefix, &config.model);
  readPositiveInt(source, prefix + "max_samples_per_axis", &config.max_samples_per_axis);
  readChecked(source, prefix, "mipmap_safety_radius", "finite and >= 0", isFiniteNonNegative,
              &config.mipmap.safety_radius);
  int capacity = static_cast<int>(config.exact_cache_capacity);
  readPositiveInt(source, prefix + "exact_cache_capacity", &capacity);
  config.exact_cache_capacity = static_cast<std::size_t>(capacity);
  config.validate();  // backstop: every field was checked above under its key
  return config;
}

void LaserSourceConfig::validate() const {
  if (name.empty()) throw std::invalid_argument("LaserSourceConfig.name must not be empty");
  if (topic.empty()) throw std::invalid_argument("LaserSourceConfig.topic must not be empty");
  if (!(max_tilt >= 0.0 && max_tilt < M_PI / 2)) {
    throw std::invalid_argument("LaserSourceConfig.max_tilt must be in [0, pi/2)");
  }
  integrator.validate();
}

LaserSourceConfig readLaserSourceConfig(const ParameterSource& source, const std::string& name) {
  const std::string prefix = name + "/";
  LaserSourceConfig config;
  config.name = name;
  config.topic = name;
  source.get(prefix + "topic", &config.topic);
  source.get(prefix + "sensor_frame", &config.sensor_frame);
  const auto tilt_ok = [](double v) { return v >= 0.0 && v < M_PI / 2; };
  readChecked(source, kSharedLaserPrefix, "max_tilt", "in [0, pi/2) rad", tilt_ok,
              &config.max_tilt);
  readChecked(source, prefix, "max_tilt", "in [0, pi/2) rad", tilt_ok, &config.max_tilt);
  if (config.topic.empty()) throw std::invalid_argument(prefix + "topic must not be empty");
  const PolarLaserIntegratorConfig shared =
      readPolarLaserIntegratorConfig(source, kSharedLaserPrefix);
  config.integrator = readPolarLaserIntegratorConfig(source, prefix, shared);
  config.validate();
  return config;
}

std::vector<LaserSourceConfig> readLaserSourceConfigs(const ParameterSource& source) {
  std::vector<LaserSourceConfig> sources;
  for (const auto& name : readSourceNames(source)) {
    sources.push_back(readLaserSourceConfig(source, name));
  }
  return sources;
}

void LocalGridPublishConfig::validate() const {
  grid.validate();
  if (frame_id.empty())
    throw std::invalid_argument("LocalGridPublishConfig.frame_id must not be empty");
  if (!isFinitePositive(publish_rate)) {
    throw std::invalid_argument("LocalGridPublishConfig.publish_rate must be finite and > 0");
  }
}

LocalGridPublishConfig readLocalGridPublishConfig(const ParameterSource& source) {
  const std::string prefix = "local_grid/";
  LocalGridPublishConfig config;
  readChecked(source, prefix, "resolution", "finite and > 0", isFinitePositive,
              &config.grid.resolution);
  const double resolution = config.grid.resolution;
  const auto covers_a_cell = [resolution](double v) { return std::isfinite(v) && v >= resolution; };
  readChecked(source, prefix, "size_x", "finite and >= local_grid/resolution", covers_a_cell,
              &config.grid.size_x);
  readChecked(source, prefix, "size_y", "finite and >= local_grid/resolution", covers_a_cell,
              &config.grid.size_y);
  source.get(prefix + "frame_id", &config.frame_id);
  if (config.frame_id.empty()) throw std::invalid_argument(prefix + "frame_id must not be empty");
  readChecked(source, prefix, "publish_rate", "finite and > 0 (Hz)", isFinitePositive,
              &config.publish_rate);
  config.validate();
  return config;
}

LaserMapperConfig readLaserMapperConfig(const ParameterSource& source) {
  LaserMapperConfig config;
  source.get("frame_id", &config.map_frame);
  if (config.map_frame.empty()) throw std::invalid_argument("frame_id must not be empty");
  source.get("write_world_layer", &config.write_world_layer);
  config.sources = readLaserSourceConfigs(source);
  config.local_grid = readLocalGridPublishConfig(source);
  return config;
}

}  // namespace occupancy_fusion
