#include "occupancy_fusion/integrators/stereo/median_network.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "float_quads.h"

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

namespace {

constexpr int kQuads = MedianNetwork::kLanes / 4;
static_assert(MedianNetwork::kLanes % 4 == 0, "lanes come in quads");

FloatQuad load(const MedianNetwork::Lanes& lanes, int quad) {
  return loadQuad(lanes.data() + 4 * quad);
}

void store(const FloatQuad& value, int quad, MedianNetwork::Lanes* lanes) {
  storeQuad(value, lanes->data() + 4 * quad);
}

}  // namespace

void MedianNetwork::medians(Lanes* values, int* counts, float* medians) const {
  // A set of n values whose missing ones become middle - n / 2 times -inf and the rest +inf has
  // its upper median on the middle wire: -inf ... v_0 .. v_n-1 ... +inf, v_(n/2) at middle.
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const FloatQuad zero = {}, one = zero + 1.0f, plus_inf = zero + kInf, minus_inf = zero - kInf;
  for (int q = 0; q < kQuads; ++q) {
    // Counts as floats, so that they select floats lane by lane.
    FloatQuad valid = zero, missing = zero, below;
    for (int r = 0; r < slots_; ++r) {
      const FloatQuad row = load(values[r], q);
      valid += row == row ? one : zero;  // not NaN
    }
    for (int l = 0; l < 4; ++l) below[l] = middle_ - std::floor(0.5f * valid[l]);
    for (int r = 0; r < slots_; ++r) {
      const FloatQuad row = load(values[r], q);
      const auto absent = row != row;  // NaN
      store(absent ? (missing < below ? minus_inf : plus_inf) : row, q, &values[r]);
      missing += absent ? one : zero;
    }
    for (int l = 0; l < 4; ++l) counts[4 * q + l] = static_cast<int>(valid[l]);
  }
  for (const std::pair<int, int>& exchange : exchanges_) {
    // The wires copied: the stores (as bytes) could otherwise change them.
    const int low = exchange.first, high = exchange.second;
    FloatQuad a[kQuads], b[kQuads];
    for (int q = 0; q < kQuads; ++q) {
      a[q] = load(values[low], q);
      b[q] = load(values[high], q);
    }
    for (int q = 0; q < kQuads; ++q) {
      // std::min and std::max lane by lane (the first argument where both are equal).
      store(b[q] < a[q] ? b[q] : a[q], q, &values[low]);
      store(a[q] < b[q] ? b[q] : a[q], q, &values[high]);
    }
  }
  for (int l = 0; l < kLanes; ++l) medians[l] = values[middle_][l];
}

}  // namespace occupancy_fusion
