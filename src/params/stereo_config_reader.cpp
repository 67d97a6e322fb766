#include "occupancy_fusion/params/stereo_config_reader.h"

#include <stdexcept>
#include <string>

namespace occupancy_fusion {
namespace {

// The config structs' validate() names struct fields ("VisibilityStereoConfig.visibility_min");
// a user editing a YAML file needs the parameter ("stereo/visibility_min"). Every field's
// parameter is the field's name under the prefix, so replacing the struct prefixes suffices.
std::string withParameterNames(std::string message) {
  for (const std::string struct_prefix :
       {"VisibilityStereoConfig.", "DisparityConversionConfig."}) {
    for (std::size_t at = message.find(struct_prefix); at != std::string::npos;
         at = message.find(struct_prefix, at)) {
      message.replace(at, struct_prefix.size(), kStereoParameterPrefix);
    }
  }
  return message;
}

template <typename Value>
void read(const ParameterSource& source, const std::string& name, Value* value) {
  source.get(kStereoParameterPrefix + name, value);
}

// Reads a string parameter and parses it; a parse error names the parameter.
template <typename Enum, typename Parse>
void readEnum(const ParameterSource& source, const std::string& name, Parse parse, Enum* value) {
  std::string text;
  if (!source.get(kStereoParameterPrefix + name, &text)) return;
  try {
    *value = parse(text);
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(kStereoParameterPrefix + name + ": " + error.what());
  }
}

}  // namespace

VisibilityStereoConfig readVisibilityStereoConfig(const ParameterSource& source) {
  // The named set first; every key below overrides its value.
  StereoParameterSet set = StereoParameterSet::kMeasured;
  readEnum(source, "parameter_set", stereoParameterSetFromString, &set);
  VisibilityStereoConfig config = visibilityStereoConfigFor(set);
  readEnum(source, "method", stereoIntegrationMethodFromString, &config.method);
  read(source, "prob_hit_visible_occupied", &config.prob_hit_visible_occupied);
  read(source, "prob_hit_visible_free", &config.prob_hit_visible_free);
  read(source, "prob_hit_invisible", &config.prob_hit_invisible);
  read(source, "prob_visible_if_occluded", &config.prob_visible_if_occluded);
  read(source, "prob_visible_if_not_occluded", &config.prob_visible_if_not_occluded);
  read(source, "visibility_min", &config.visibility_min);
  read(source, "visibility_max", &config.visibility_max);
  read(source, "unknown_occupancy", &config.unknown_occupancy);
  read(source, "unknown_neighbour_occupancy", &config.unknown_neighbour_occupancy);
  readEnum(source, "unknown_neighbours", unknownNeighboursFromString, &config.unknown_neighbours);
  read(source, "measured_window_px", &config.measured_surface.window_px);
  read(source, "measured_step_px", &config.measured_surface.step_px);
  read(source, "measured_grid_fraction", &config.measured_surface.grid_footprint_fraction);
  read(source, "measured_grid_max_px", &config.measured_surface.grid_max_step_px);
  read(source, "inside_stop_probability", &config.inside_stop_probability);
  read(source, "clear_passed", &config.clear_passed);
  read(source, "passed_sigmas", &config.passed_sigmas);
  read(source, "passed_miss_probability", &config.passed_miss_probability);
  read(source, "max_range", &config.max_range);
  read(source, "bundle_rays", &config.bundle_rays);
  read(source, "disparity_sigma_px", &config.disparity.disparity_sigma_px);
  read(source, "min_disparity_px", &config.disparity.min_disparity_px);
  read(source, "max_depth_sigma_ratio", &config.disparity.max_depth_sigma_ratio);
  readEnum(source, "input_resolution", inputResolutionFromString,
           &config.disparity.input_resolution);
  try {
    config.validate();
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(withParameterNames(error.what()));
  }
  return config;
}

}  // namespace occupancy_fusion
