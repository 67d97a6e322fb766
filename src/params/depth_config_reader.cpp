#include "occupancy_fusion/params/depth_config_reader.h"

#include <stdexcept>
#include <string>

namespace occupancy_fusion {
namespace {

const std::string kStructPrefix = "PyramidDepthConfig.";
const std::string kKeyPrefix = "depth/";

// PyramidDepthConfig::validate() names fields as "PyramidDepthConfig.<field>"; the user wrote
// "depth/<field>", so the message is rewritten to the key the user can find in the YAML file.
std::string nameParameters(std::string message) {
  for (std::size_t at = message.find(kStructPrefix); at != std::string::npos;
       at = message.find(kStructPrefix, at + kKeyPrefix.size())) {
    message.replace(at, kStructPrefix.size(), kKeyPrefix);
  }
  return message;
}

DepthMethod readMethod(const ParameterSource& source, DepthMethod fallback) {
  std::string name;
  if (!source.get(kKeyPrefix + "method", &name)) return fallback;
  try {
    return depthMethodFromString(name);
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(nameParameters(error.what()));
  }
}

}  // namespace

PyramidDepthConfig readPyramidDepthConfig(const ParameterSource& source) {
  PyramidDepthConfig config;
  config.method = readMethod(source, config.method);
  source.get(kKeyPrefix + "k", &config.k);
  source.get(kKeyPrefix + "sigma", &config.sigma);
  source.get(kKeyPrefix + "sigma_quadratic", &config.sigma_quadratic);
  source.get(kKeyPrefix + "min_range", &config.min_range);
  source.get(kKeyPrefix + "max_range", &config.max_range);
  source.get(kKeyPrefix + "unknown_behind_sigmas", &config.unknown_behind_sigmas);
  source.get(kKeyPrefix + "max_pyramid_levels", &config.max_pyramid_levels);
  source.get(kKeyPrefix + "finer_layers", &config.finer_layers);
  source.get(kKeyPrefix + "clear_passed", &config.clear_passed);
  source.get(kKeyPrefix + "passed_sigmas", &config.passed_sigmas);
  source.get(kKeyPrefix + "passed_miss_probability", &config.passed_miss_probability);
  try {
    config.validate();
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(nameParameters(error.what()));
  }
  return config;
}

}  // namespace occupancy_fusion
