#include "occupancy_fusion/integrators/stereo/median_network.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace occupancy_fusion {

namespace {

// Batcher's odd-even merge sort on the next power of two above `slots`, without the exchanges
// that touch a wire >= slots: those wires hold +inf, which such an exchange leaves in place.
std::vector<std::pair<int, int>> oddEvenMergeSort(int slots) {
  int wires = 1;
  while (wires < slots) wires *= 2;
  std::vector<std::pair<int, int>> exchanges;
  for (int p = 1; p < wires; p *= 2) {
    for (int k = p; k >= 1; k /= 2) {
      for (int j = k % p; j + k < wires; j += 2 * k) {
        for (int i = 0; i < std::min(k, wires - j - k); ++i) {
          const int low = i + j, high = i + j + k;
          if (low / (2 * p) == high / (2 * p) && high < slots) exchanges.emplace_back(low, high);
        }
      }
    }
  }
  return exchanges;
}

// Only the exchanges the wire `output` depends on, walking back from the network's end.
std::vector<std::pair<int, int>> prunedTo(const std::vector<std::pair<int, int>>& exchanges,
                                          int slots, int output) {
  std::vector<bool> needed(slots, false);
  needed[output] = true;
  std::vector<std::pair<int, int>> kept;
  for (auto it = exchanges.rbegin(); it != exchanges.rend(); ++it) {
    if (!needed[it->first] && !needed[it->second]) continue;
    needed[it->first] = needed[it->second] = true;
    kept.push_back(*it);
  }
  std::reverse(kept.begin(), kept.end());
  return kept;
}

}  // namespace

MedianNetwork::MedianNetwork(int slots) : slots_(slots), middle_(slots / 2) {
  if (slots < 1 || slots > kMaxSlots) {
    throw std::invalid_argument("MedianNetwork: slots must be in [1, " + std::to_string(kMaxSlots) +
                                "], got " + std::to_string(slots));
  }
  exchanges_ = prunedTo(oddEvenMergeSort(slots), slots, middle_);
}

void MedianNetwork::medians(Lanes* values, int* counts, float* medians) const {
  // A set of n values whose missing ones become middle - n / 2 times -inf and the rest +inf has
  // its upper median on the middle wire: -inf ... v_0 .. v_n-1 ... +inf, v_(n/2) at middle.
  // Lane by lane in step, so that the compiler keeps the lanes in one register.
  constexpr float kInf = std::numeric_limits<float>::infinity();
  // Counts as floats: a float selection by an integer comparison does not vectorise.
  float valid[kLanes] = {}, below[kLanes], missing[kLanes] = {};
  for (int r = 0; r < slots_; ++r) {
    const Lanes row = values[r];
    for (int l = 0; l < kLanes; ++l) valid[l] += row[l] == row[l] ? 1.0f : 0.0f;  // not NaN
  }
  for (int l = 0; l < kLanes; ++l) below[l] = middle_ - std::floor(0.5f * valid[l]);
  for (int r = 0; r < slots_; ++r) {
    const Lanes row = values[r];
    Lanes filled;
    for (int l = 0; l < kLanes; ++l) {
      const float absent = row[l] == row[l] ? 0.0f : 1.0f;  // NaN
      filled[l] = absent > 0 ? (missing[l] < below[l] ? -kInf : kInf) : row[l];
      missing[l] += absent;
    }
    values[r] = filled;
  }
  for (const auto& [low, high] : exchanges_) {
    // Through copies: the compiler cannot know that the two rows differ, and vectorises only
    // what cannot alias.
    const Lanes a = values[low], b = values[high];
    Lanes lower, upper;
    for (int l = 0; l < kLanes; ++l) {
      lower[l] = std::min(a[l], b[l]);
      upper[l] = std::max(a[l], b[l]);
    }
    values[low] = lower;
    values[high] = upper;
  }
  for (int l = 0; l < kLanes; ++l) {
    counts[l] = static_cast<int>(valid[l]);
    medians[l] = values[middle_][l];
  }
}

}  // namespace occupancy_fusion
