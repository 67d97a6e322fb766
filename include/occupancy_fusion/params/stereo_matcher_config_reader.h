// Reader of the stereo matcher's configuration over any ParameterSource (the StereoMatcher
// nodelet's private parameters, a YAML file in the tools). Header only.
#pragma once

#include <stdexcept>
#include <string>

#include "occupancy_fusion/params/parameter_source.h"
#include "occupancy_fusion/sensors/stereo_matcher.h"

namespace occupancy_fusion {

namespace stereo_matcher_params {

// stereo_image_proc's dynamic_reconfigure limits (Disparity.cfg), so that a value it would refuse
// is refused here too, at start, naming the parameter.
inline void requireWithin(const std::string& key, int value, int low, int high) {
  if (value < low || value > high) {
    throw std::invalid_argument(key + " must be in [" + std::to_string(low) + ", " +
                                std::to_string(high) + "], not " + std::to_string(value));
  }
}

// stereo_image_proc declares uniqueness_ratio, P1 and P2 as doubles: read them as doubles (a
// YAML "15" is accepted too) and keep the whole number OpenCV takes.
inline void getWhole(const ParameterSource& source, const std::string& key, int* value) {
  double number = *value;
  if (!source.get(key, &number)) return;
  // Range first: it also refuses NaN, whose conversion to an integer is undefined.
  if (!(number >= -1e9 && number <= 1e9)) throw std::invalid_argument(key + " is out of range");
  if (number != static_cast<double>(static_cast<long long>(number))) {
    throw std::invalid_argument(key + " must be a whole number, not " + std::to_string(number));
  }
  *value = static_cast<int>(number);
}

}  // namespace stereo_matcher_params

// Reads, at the top level of the source (stereo_image_proc's names; absent keys keep the
// StereoMatcherConfig defaults):
//   stereo_algorithm         0 block matching (StereoBM), 1 semi-global (StereoSGBM)
//   sgbm_mode                sgbm | 3way | hh
//   correlation_window_size  px, odd, 5..255
//   min_disparity            px, -128..128
//   disparity_range          px, 32..256, a multiple of 16
//   uniqueness_ratio         %, 0..100
//   texture_threshold        0..10000 (block matching)
//   speckle_size             px, 0..1000
//   speckle_range            px, 0..31
//   prefilter_size           px, odd, 5..255 (block matching)
//   prefilter_cap            1..63
//   P1, P2                   0..4000, P2 > P1 (semi-global)
//   disp12MaxDiff            px, 0..128
// Validates the result; throws std::invalid_argument naming the parameter.
inline StereoMatcherConfig readStereoMatcherConfig(const ParameterSource& source) {
  using stereo_matcher_params::getWhole;
  using stereo_matcher_params::requireWithin;
  StereoMatcherConfig config;
  int algorithm = static_cast<int>(config.algorithm);
  source.get("stereo_algorithm", &algorithm);
  if (algorithm != 0 && algorithm != 1) {
    throw std::invalid_argument("stereo_algorithm must be 0 (StereoBM) or 1 (StereoSGBM), not " +
                                std::to_string(algorithm));
  }
  config.algorithm = static_cast<StereoAlgorithm>(algorithm);
  std::string mode;
  if (source.get("sgbm_mode", &mode)) {
    try {
      config.sgbm_mode = sgbmModeFromString(mode);
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument(std::string("sgbm_mode: ") + error.what());
    }
  }
  source.get("correlation_window_size", &config.correlation_window_size);
  requireWithin("correlation_window_size", config.correlation_window_size, 5, 255);
  source.get("min_disparity", &config.min_disparity);
  requireWithin("min_disparity", config.min_disparity, -128, 128);
  source.get("disparity_range", &config.disparity_range);
  requireWithin("disparity_range", config.disparity_range, 32, 256);
  getWhole(source, "uniqueness_ratio", &config.uniqueness_ratio);
  requireWithin("uniqueness_ratio", config.uniqueness_ratio, 0, 100);
  source.get("texture_threshold", &config.texture_threshold);
  requireWithin("texture_threshold", config.texture_threshold, 0, 10000);
  source.get("speckle_size", &config.speckle_size);
  requireWithin("speckle_size", config.speckle_size, 0, 1000);
  source.get("speckle_range", &config.speckle_range);
  requireWithin("speckle_range", config.speckle_range, 0, 31);
  source.get("prefilter_size", &config.prefilter_size);
  requireWithin("prefilter_size", config.prefilter_size, 5, 255);
  source.get("prefilter_cap", &config.prefilter_cap);
  requireWithin("prefilter_cap", config.prefilter_cap, 1, 63);
  getWhole(source, "P1", &config.p1);
  requireWithin("P1", config.p1, 0, 4000);
  getWhole(source, "P2", &config.p2);
  requireWithin("P2", config.p2, 0, 4000);
  source.get("disp12MaxDiff", &config.disp12_max_diff);
  requireWithin("disp12MaxDiff", config.disp12_max_diff, 0, 128);
  try {
    config.validate();
  } catch (const std::invalid_argument& error) {
    // The struct's field names are the parameters' except for P1, P2 and disp12MaxDiff.
    std::string message = error.what();
    const std::string prefix = "StereoMatcherConfig.";
    if (message.compare(0, prefix.size(), prefix) == 0) message.erase(0, prefix.size());
    throw std::invalid_argument(message);
  }
  return config;
}

}  // namespace occupancy_fusion
