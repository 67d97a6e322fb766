// The log-odds storage shared by the 3D map's voxel blocks and the 2D layer's tiles: a fixed
// array of cells with an explicit unknown state and the clamped update of OctoMap's model.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace occupancy_fusion {

// kCount log-odds cells. NaN marks a cell that was never observed.
template <int kCount>
struct LogOddsCells {
  static constexpr int kCellCount = kCount;
  static constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();

  LogOddsCells() { log_odds.fill(kUnknown); }

  static bool isKnown(float value) { return !std::isnan(value); }

  // Adds delta to one cell (an unknown cell starts at the prior, 0) and clamps to
  // [min_log_odds, max_log_odds] (the model's clamping bounds).
  void update(int linear, float delta, float min_log_odds, float max_log_odds) {
    float& value = log_odds[linear];
    float sum = delta;
    if (isKnown(value)) {
      sum += value;
    } else {
      ++known_count;
    }
    value = sum < min_log_odds ? min_log_odds : (sum > max_log_odds ? max_log_odds : sum);
  }
  // Sets one cell as it is (unclamped; NaN makes it unknown).
  void set(int linear, float value) {
    if (isKnown(value) != isKnown(log_odds[linear])) known_count += isKnown(value) ? 1 : -1;
    log_odds[linear] = value;
  }

  std::array<float, kCount> log_odds;
  int known_count = 0;
  std::uint64_t version = 0;  // version of the map or layer at the last write; kept by its owner
};

}  // namespace occupancy_fusion
