#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "occupancy_fusion/params/stereo_config_reader.h"

namespace occupancy_fusion {
namespace {

// Key/value pairs as text, parsed at get() like a YAML scalar; a value that does not parse as the
// asked type throws, as the real sources do.
class TextParameterSource : public ParameterSource {
 public:
  explicit TextParameterSource(std::map<std::string, std::string> values)
      : values_(std::move(values)) {}
  bool get(const std::string& key, double* value) const override { return parse(key, value); }
  bool get(const std::string& key, int* value) const override { return parse(key, value); }
  bool get(const std::string& key, bool* value) const override { return parse(key, value); }
  bool get(const std::string& key, std::string* value) const override { return parse(key, value); }
  bool get(const std::string&, std::vector<std::string>*) const override { return false; }
  bool get(const std::string&, std::vector<double>*) const override { return false; }

 private:
  template <typename T>
  bool parse(const std::string& key, T* value) const {
    const auto found = values_.find(key);
    if (found == values_.end()) return false;
    try {
      *value = YAML::Load(found->second).as<T>();
    } catch (const YAML::Exception&) {
      throw std::invalid_argument(key + " has the wrong type");
    }
    return true;
  }
  std::map<std::string, std::string> values_;
};

// The leaves of a YAML map as "a/b" keys, as rosparam puts them under a namespace.
void flatten(const YAML::Node& node, const std::string& prefix,
             std::map<std::string, std::string>* out) {
  for (const auto& entry : node) {
    const std::string key = prefix + entry.first.as<std::string>();
    if (entry.second.IsMap()) {
      flatten(entry.second, key + "/", out);
    } else {
      (*out)[key] = entry.second.as<std::string>();
    }
  }
}

std::string messageOf(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "(no exception)";
}

VisibilityStereoConfig readFrom(std::map<std::string, std::string> values) {
  return readVisibilityStereoConfig(TextParameterSource(std::move(values)));
}

TEST(StereoConfigReader, EmptySourceGivesTableI) {
  const VisibilityStereoConfig config = readFrom({});
  EXPECT_EQ(config.method, StereoIntegrationMethod::kVisibility);
  EXPECT_DOUBLE_EQ(config.prob_hit_visible_occupied, 0.55);
  EXPECT_DOUBLE_EQ(config.prob_hit_visible_free, 0.43);
  EXPECT_DOUBLE_EQ(config.prob_hit_invisible, 0.05);
  EXPECT_DOUBLE_EQ(config.prob_visible_if_occluded, 0.2);
  EXPECT_DOUBLE_EQ(config.prob_visible_if_not_occluded, 1.0);
  EXPECT_DOUBLE_EQ(config.visibility_min, 0.1);
  EXPECT_DOUBLE_EQ(config.visibility_max, 0.7);
}

TEST(StereoConfigReader, ReadsEveryField) {
  const VisibilityStereoConfig config = readFrom({
      {"stereo/method", "octomap"},
      {"stereo/prob_hit_visible_occupied", "0.6"},
      {"stereo/prob_hit_visible_free", "0.4"},
      {"stereo/prob_hit_invisible", "0.1"},
      {"stereo/prob_visible_if_occluded", "0.3"},
      {"stereo/prob_visible_if_not_occluded", "0.9"},
      {"stereo/visibility_min", "0.15"},
      {"stereo/visibility_max", "0.8"},
      {"stereo/unknown_occupancy", "0.45"},
      {"stereo/unknown_neighbour_occupancy", "0.35"},
      {"stereo/inside_stop_probability", "0.95"},
      {"stereo/max_range", "7.5"},
      {"stereo/bundle_rays", "false"},
      {"stereo/disparity_sigma_px", "0.25"},
      {"stereo/min_disparity_px", "2"},
      {"stereo/max_depth_sigma_ratio", "0.4"},
      {"stereo/input_resolution", "quarter"},
  });
  EXPECT_EQ(config.method, StereoIntegrationMethod::kOctomap);
  EXPECT_DOUBLE_EQ(config.prob_hit_visible_occupied, 0.6);
  EXPECT_DOUBLE_EQ(config.prob_hit_visible_free, 0.4);
  EXPECT_DOUBLE_EQ(config.prob_hit_invisible, 0.1);
  EXPECT_DOUBLE_EQ(config.prob_visible_if_occluded, 0.3);
  EXPECT_DOUBLE_EQ(config.prob_visible_if_not_occluded, 0.9);
  EXPECT_DOUBLE_EQ(config.visibility_min, 0.15);
  EXPECT_DOUBLE_EQ(config.visibility_max, 0.8);
  EXPECT_DOUBLE_EQ(config.unknown_occupancy, 0.45);
  EXPECT_DOUBLE_EQ(config.unknown_neighbour_occupancy, 0.35);
  EXPECT_DOUBLE_EQ(config.inside_stop_probability, 0.95);
  EXPECT_DOUBLE_EQ(config.max_range, 7.5);
  EXPECT_FALSE(config.bundle_rays);
  EXPECT_TRUE(VisibilityStereoConfig().bundle_rays);  // so that reading "false" is seen
  EXPECT_DOUBLE_EQ(config.disparity.disparity_sigma_px, 0.25);
  EXPECT_DOUBLE_EQ(config.disparity.min_disparity_px, 2.0);
  EXPECT_DOUBLE_EQ(config.disparity.max_depth_sigma_ratio, 0.4);
  EXPECT_EQ(config.disparity.input_resolution, InputResolution::kQuarter);
}

TEST(StereoConfigReader, ErrorsNameTheParameter) {
  EXPECT_NE(messageOf([] {
              readFrom({{"stereo/method", "sgbm"}});
            }).find("stereo/method"),
            std::string::npos);
  EXPECT_NE(messageOf([] {
              readFrom({{"stereo/input_resolution", "eighth"}});
            }).find("stereo/input_resolution"),
            std::string::npos);
  EXPECT_NE(messageOf([] {
              readFrom({{"stereo/visibility_min", "0.9"}});
            }).find("stereo/visibility_min"),
            std::string::npos);
  EXPECT_NE(messageOf([] {
              readFrom({{"stereo/prob_hit_invisible", "1.5"}});
            }).find("stereo/prob_hit_invisible"),
            std::string::npos);
  EXPECT_NE(messageOf([] {
              readFrom({{"stereo/disparity_sigma_px", "-1"}});
            }).find("stereo/disparity_sigma_px"),
            std::string::npos);
  EXPECT_NE(messageOf([] {
              readFrom({{"stereo/max_depth_sigma_ratio", "nan"}});
            }).find("stereo/max_depth_sigma_ratio"),
            std::string::npos);
  EXPECT_NE(messageOf([] {
              readFrom({{"stereo/max_range", "far"}});
            }).find("stereo/max_range"),
            std::string::npos);
}

// A named set is read first and the keys override it.
TEST(StereoConfigReader, ParameterSetThenKeys) {
  const VisibilityStereoConfig fast = readFrom({{"stereo/parameter_set", "fast_expansion"}});
  EXPECT_DOUBLE_EQ(fast.visibility_min, 0.003);
  EXPECT_DOUBLE_EQ(fast.prob_hit_invisible, 0.2);
  EXPECT_DOUBLE_EQ(fast.visibility_max, 0.7);  // the rest is Table I
  EXPECT_DOUBLE_EQ(fast.prob_visible_if_occluded, 0.2);
  const VisibilityStereoConfig overridden =
      readFrom({{"stereo/parameter_set", "fast_expansion"}, {"stereo/visibility_min", "0.01"}});
  EXPECT_DOUBLE_EQ(overridden.visibility_min, 0.01);
  EXPECT_DOUBLE_EQ(overridden.prob_hit_invisible, 0.2);
  const VisibilityStereoConfig table_i = readFrom({{"stereo/parameter_set", "table_i"}});
  EXPECT_DOUBLE_EQ(table_i.visibility_min, 0.1);
  EXPECT_DOUBLE_EQ(table_i.prob_hit_invisible, 0.05);
  EXPECT_NE(messageOf([] {
              readFrom({{"stereo/parameter_set", "fast"}});
            }).find("stereo/parameter_set"),
            std::string::npos);
}

// The shipped YAML file: every stereo/ key is one the reader knows, Table I's values are its
// values, its set is the measured one, and it parses into a valid configuration.
TEST(StereoConfigReader, ShippedConfigFileHoldsTableIWithTheMeasuredSet) {
  const std::filesystem::path file =
      std::filesystem::path(OCCUPANCY_FUSION_SOURCE_DIR) / "config/disparity_mapper.yaml";
  std::map<std::string, std::string> values;
  flatten(YAML::LoadFile(file.string()), "", &values);
  const std::vector<std::string> known = {"parameter_set",
                                          "method",
                                          "prob_hit_visible_occupied",
                                          "prob_hit_visible_free",
                                          "prob_hit_invisible",
                                          "prob_visible_if_occluded",
                                          "prob_visible_if_not_occluded",
                                          "visibility_min",
                                          "visibility_max",
                                          "unknown_occupancy",
                                          "unknown_neighbour_occupancy",
                                          "unknown_neighbours",
                                          "measured_window_px",
                                          "measured_step_px",
                                          "measured_grid_fraction",
                                          "measured_grid_max_px",
                                          "inside_stop_probability",
                                          "clear_passed",
                                          "passed_sigmas",
                                          "passed_miss_probability",
                                          "max_range",
                                          "bundle_rays",
                                          "disparity_sigma_px",
                                          "min_disparity_px",
                                          "max_depth_sigma_ratio",
                                          "input_resolution"};
  std::size_t stereo_keys = 0;
  for (const auto& [key, value] : values) {
    if (key.rfind(kStereoParameterPrefix, 0) != 0) continue;
    ++stereo_keys;
    const std::string name = key.substr(kStereoParameterPrefix.size());
    EXPECT_NE(std::find(known.begin(), known.end(), name), known.end()) << key;
  }
  // The keys the sets change are commented out in the file, so the set takes effect.
  EXPECT_EQ(stereo_keys, known.size() - 4);
  EXPECT_EQ(values.count("stereo/clear_passed"), 0u);
  EXPECT_EQ(values.count("stereo/visibility_min"), 0u);
  EXPECT_EQ(values.count("stereo/prob_hit_invisible"), 0u);
  EXPECT_EQ(values.count("stereo/unknown_neighbours"), 0u);
  EXPECT_EQ(values.at("stereo/parameter_set"), "measured");
  const VisibilityStereoConfig from_file = readFrom(values);
  const VisibilityStereoConfig defaults;  // Table I
  EXPECT_EQ(from_file.unknown_neighbours, UnknownNeighbours::kMeasured);
  EXPECT_TRUE(from_file.clear_passed);
  EXPECT_FALSE(defaults.clear_passed);
  EXPECT_DOUBLE_EQ(from_file.passed_sigmas, defaults.passed_sigmas);
  EXPECT_DOUBLE_EQ(from_file.passed_miss_probability, defaults.passed_miss_probability);
  EXPECT_EQ(from_file.measured_surface.window_px, MeasuredSurfaceConfig().window_px);
  EXPECT_DOUBLE_EQ(from_file.measured_surface.grid_footprint_fraction,
                   MeasuredSurfaceConfig().grid_footprint_fraction);
  EXPECT_EQ(from_file.measured_surface.grid_max_step_px,
            MeasuredSurfaceConfig().grid_max_step_px);
  EXPECT_EQ(from_file.method, defaults.method);
  EXPECT_DOUBLE_EQ(from_file.prob_hit_visible_occupied, defaults.prob_hit_visible_occupied);
  EXPECT_DOUBLE_EQ(from_file.prob_hit_visible_free, defaults.prob_hit_visible_free);
  EXPECT_DOUBLE_EQ(from_file.prob_hit_invisible, defaults.prob_hit_invisible);
  EXPECT_DOUBLE_EQ(from_file.prob_visible_if_occluded, defaults.prob_visible_if_occluded);
  EXPECT_DOUBLE_EQ(from_file.prob_visible_if_not_occluded, defaults.prob_visible_if_not_occluded);
  EXPECT_DOUBLE_EQ(from_file.visibility_min, defaults.visibility_min);
  EXPECT_DOUBLE_EQ(from_file.visibility_max, defaults.visibility_max);
  EXPECT_DOUBLE_EQ(from_file.unknown_occupancy, defaults.unknown_occupancy);
  EXPECT_DOUBLE_EQ(from_file.unknown_neighbour_occupancy, defaults.unknown_neighbour_occupancy);
  EXPECT_DOUBLE_EQ(from_file.inside_stop_probability, defaults.inside_stop_probability);
  EXPECT_EQ(from_file.bundle_rays, defaults.bundle_rays);
  EXPECT_DOUBLE_EQ(from_file.disparity.disparity_sigma_px, defaults.disparity.disparity_sigma_px);
  EXPECT_EQ(from_file.disparity.input_resolution, defaults.disparity.input_resolution);
}

}  // namespace
}  // namespace occupancy_fusion
