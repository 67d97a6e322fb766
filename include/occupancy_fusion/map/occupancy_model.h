// Log-odds occupancy semantics shared by every map layer.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>

namespace occupancy_fusion {

// State of a voxel or cell. Unknown means "never observed", which is not the same as p = 0.5.
enum class Occupancy : std::int8_t { kUnknown = -1, kFree = 0, kOccupied = 1 };

inline float logit(double probability) {
  return static_cast<float>(std::log(probability / (1.0 - probability)));
}

inline double probabilityFromLogOdds(double log_odds) { return 1.0 / (1.0 + std::exp(-log_odds)); }

// Update and clamping parameters, OctoMap's defaults (octomap_server's sensor_model/*).
struct OccupancyModel {
  double prob_hit = 0.7;             // sensor_model/hit
  double prob_miss = 0.4;            // sensor_model/miss
  double clamp_min = 0.1192;         // sensor_model/min
  double clamp_max = 0.971;          // sensor_model/max
  double occupancy_threshold = 0.5;  // above: occupied, at or below: free

  // Throws std::invalid_argument naming the offending field.
  void validate() const;

  float hitLogOdds() const { return logit(prob_hit); }
  float missLogOdds() const { return logit(prob_miss); }
  float minLogOdds() const { return logit(clamp_min); }
  float maxLogOdds() const { return logit(clamp_max); }
  float thresholdLogOdds() const { return logit(occupancy_threshold); }

  float clamp(float log_odds) const;
  Occupancy classify(float log_odds) const {
    return log_odds > thresholdLogOdds() ? Occupancy::kOccupied : Occupancy::kFree;
  }
};

}  // namespace occupancy_fusion
