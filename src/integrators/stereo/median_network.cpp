#include "occupancy_fusion/integrators/stereo/median_network.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "float_quads.h"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#endif

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

MedianNetwork::MedianNetwork(int slots, Instructions instructions)
    : slots_(slots),
      middle_(slots / 2),
      use_octets_(instructions == Instructions::kWidest && processorHasAvx2()) {
  if (slots < 1 || slots > kMaxSlots) {
    throw std::invalid_argument("MedianNetwork: slots must be in [1, " + std::to_string(kMaxSlots) +
                                "], got " + std::to_string(slots));
  }
  exchanges_ = prunedTo(oddEvenMergeSort(slots), slots, middle_);
}

namespace {

static_assert(MedianNetwork::kLanes == 8, "one octet or two quads hold the lanes");

// The network on the lanes as kLanes / Width vectors of Width floats (Vector), the same
// operations on every lane whatever the width, so that both widths give the same bits. Inlined
// into each caller so that the vectors take the caller's instruction set.
template <typename Vector, int Width>
inline __attribute__((always_inline)) void runNetwork(
    const std::vector<std::pair<int, int>>& exchanges, int slots, int middle,
    MedianNetwork::Lanes* values, int* counts, float* medians) {
  constexpr int kParts = MedianNetwork::kLanes / Width;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  // A set of n values whose missing ones become middle - n / 2 times -inf and the rest +inf has
  // its upper median on the middle wire: -inf ... v_0 .. v_n-1 ... +inf, v_(n/2) at middle.
  const Vector zero = {}, one = zero + 1.0f, plus_inf = zero + kInf, minus_inf = zero - kInf;
  for (int part = 0; part < kParts; ++part) {
    // Counts as floats, so that they select floats lane by lane.
    Vector valid = zero, missing = zero, below, row = zero;
    for (int r = 0; r < slots; ++r) {
      std::memcpy(&row, values[r].data() + Width * part, sizeof(row));
      valid += row == row ? one : zero;  // not NaN
    }
    for (int l = 0; l < Width; ++l) below[l] = middle - std::floor(0.5f * valid[l]);
    for (int r = 0; r < slots; ++r) {
      std::memcpy(&row, values[r].data() + Width * part, sizeof(row));
      const auto absent = row != row;  // NaN
      const Vector filled = absent ? (missing < below ? minus_inf : plus_inf) : row;
      std::memcpy(values[r].data() + Width * part, &filled, sizeof(filled));
      missing += absent ? one : zero;
    }
    for (int l = 0; l < Width; ++l) counts[Width * part + l] = static_cast<int>(valid[l]);
  }
  for (const std::pair<int, int>& exchange : exchanges) {
    float* low = values[exchange.first].data();
    float* high = values[exchange.second].data();
    for (int part = 0; part < kParts; ++part) {
      // One vector a load: a vector read from two smaller stores stalls its forwarding.
      Vector a, b;
      std::memcpy(&a, low + Width * part, sizeof(a));
      std::memcpy(&b, high + Width * part, sizeof(b));
      // std::min and std::max lane by lane (the first argument where both are equal).
      const Vector smaller = b < a ? b : a;
      const Vector larger = a < b ? b : a;
      std::memcpy(low + Width * part, &smaller, sizeof(smaller));
      std::memcpy(high + Width * part, &larger, sizeof(larger));
    }
  }
  for (int l = 0; l < MedianNetwork::kLanes; ++l) medians[l] = values[middle][l];
}

// The pruned network of a slot count known at compile time (the measured surface's windows of
// 3 x 3 to 9 x 9 samples), as oddEvenMergeSort and prunedTo above: its exchanges unroll on
// constant wires, without the runtime network's loads of each exchange's wire numbers.
struct Exchange {
  int low, high;
};
struct ExchangeList {
  std::array<Exchange, 1024> items{};  // Batcher's network on 64 wires has 543
  int size = 0;
};
template <int Slots>
constexpr ExchangeList prunedNetworkOf() {
  static_assert(Slots >= 1 && Slots <= 64, "a fixed network has at most 64 wires");
  ExchangeList all{};
  int wires = 1;
  while (wires < Slots) wires *= 2;
  for (int p = 1; p < wires; p *= 2) {
    for (int k = p; k >= 1; k /= 2) {
      for (int j = k % p; j + k < wires; j += 2 * k) {
        for (int i = 0; i < k && i < wires - j - k; ++i) {
          const int low = i + j, high = i + j + k;
          if (low / (2 * p) == high / (2 * p) && high < Slots) all.items[all.size++] = {low, high};
        }
      }
    }
  }
  bool needed[Slots]{};
  needed[Slots / 2] = true;
  ExchangeList kept{};
  for (int e = all.size - 1; e >= 0; --e) {
    const Exchange exchange = all.items[e];
    if (!needed[exchange.low] && !needed[exchange.high]) continue;
    needed[exchange.low] = needed[exchange.high] = true;
    kept.items[kept.size++] = exchange;
  }
  ExchangeList ordered{};
  for (int e = kept.size - 1; e >= 0; --e) ordered.items[ordered.size++] = kept.items[e];
  return ordered;
}
template <int Slots>
struct FixedNetwork {
  static constexpr int kMiddle = Slots / 2;
  static constexpr ExchangeList kList = prunedNetworkOf<Slots>();
};

template <int Slots, typename Vector, std::size_t... E>
inline __attribute__((always_inline)) void exchangeAll(Vector* wires, std::index_sequence<E...>) {
  constexpr const auto& list = FixedNetwork<Slots>::kList;
  // std::min and std::max lane by lane, as runNetwork.
  auto exchange = [](Vector& a, Vector& b) {
    const Vector smaller = b < a ? b : a;
    const Vector larger = a < b ? b : a;
    a = smaller;
    b = larger;
  };
  // A braced list, evaluated in order, rather than a fold: Clang nests a fold's 257 operands.
  const int done[] = {(exchange(wires[list.items[E].low], wires[list.items[E].high]), 0)...};
  static_cast<void>(done);
}

// runNetwork for a fixed network on loaded wires (Width lanes): the same fill of the missing
// values and the same exchanges in the same order, so the same bits.
template <int Slots, typename Vector, int Width>
inline __attribute__((always_inline)) void medianOfWires(Vector* wires, int* counts,
                                                         float* medians) {
  constexpr int kMiddle = FixedNetwork<Slots>::kMiddle;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const Vector zero = {}, one = zero + 1.0f, plus_inf = zero + kInf, minus_inf = zero - kInf;
  Vector valid = zero, missing = zero, below;
  for (int r = 0; r < Slots; ++r) valid += wires[r] == wires[r] ? one : zero;  // not NaN
  for (int l = 0; l < Width; ++l) below[l] = kMiddle - std::floor(0.5f * valid[l]);
  for (int r = 0; r < Slots; ++r) {
    const auto absent = wires[r] != wires[r];  // NaN
    wires[r] = absent ? (missing < below ? minus_inf : plus_inf) : wires[r];
    missing += absent ? one : zero;
  }
  exchangeAll<Slots>(wires, std::make_index_sequence<FixedNetwork<Slots>::kList.size>());
  for (int l = 0; l < Width; ++l) {
    counts[l] = static_cast<int>(valid[l]);
    medians[l] = wires[kMiddle][l];
  }
}

template <int Slots>
void runFixedOnQuads(MedianNetwork::Lanes* values, int* counts, float* medians) {
  for (int part = 0; part < MedianNetwork::kLanes / 4; ++part) {
    FloatQuad wires[Slots];
    for (int r = 0; r < Slots; ++r) wires[r] = loadQuad(values[r].data() + 4 * part);
    medianOfWires<Slots, FloatQuad, 4>(wires, counts + 4 * part, medians + 4 * part);
  }
}

#ifdef OCCUPANCY_FUSION_HAS_AVX2_PATH
template <int Slots>
__attribute__((target("avx2"))) void runFixedOnOctets(MedianNetwork::Lanes* values, int* counts,
                                                      float* medians) {
  FloatOctet wires[Slots];
  for (int r = 0; r < Slots; ++r) {
    // The rows are written a quad at a time (the measured surface's lattice): each half is
    // loaded from its own store. A vector loaded from two smaller stores that are still in the
    // store buffer waits for both to reach the cache, which was most of the network's time.
    const float* row = values[r].data();
    wires[r] =
        _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(row)), _mm_loadu_ps(row + 4), 1);
  }
  medianOfWires<Slots, FloatOctet, 8>(wires, counts, medians);
}
#endif

// The fixed networks of 2 r (r + 1) + 1 slots, reach r = 1 .. 4: the pair means (and the
// checkerboard samples) of the measured surface's windows of 3 x 3 to 9 x 9 samples.
using FixedSlots = std::integer_sequence<int, 5, 13, 25, 41>;

// Run<slots>::run where slots is one of FixedSlots; false for other slot counts.
template <template <int> class Run, int... Fixed>
bool runFixed(std::integer_sequence<int, Fixed...>, int slots, MedianNetwork::Lanes* values,
              int* counts, float* medians) {
  return ((slots == Fixed && (Run<Fixed>::run(values, counts, medians), true)) || ...);
}
template <int Slots>
struct OnQuads {
  static void run(MedianNetwork::Lanes* v, int* c, float* m) { runFixedOnQuads<Slots>(v, c, m); }
};
#ifdef OCCUPANCY_FUSION_HAS_AVX2_PATH
template <int Slots>
struct OnOctets {
  static void run(MedianNetwork::Lanes* v, int* c, float* m) { runFixedOnOctets<Slots>(v, c, m); }
};
#endif

// Plain x86-64 (SSE2): two quads.
void runOnQuads(const std::vector<std::pair<int, int>>& exchanges, int slots, int middle,
                MedianNetwork::Lanes* values, int* counts, float* medians) {
  if (!runFixed<OnQuads>(FixedSlots(), slots, values, counts, medians)) {
    runNetwork<FloatQuad, 4>(exchanges, slots, middle, values, counts, medians);
  }
}

#ifdef OCCUPANCY_FUSION_HAS_AVX2_PATH
// With AVX2 (chosen at run time): one octet, half the instructions.
__attribute__((target("avx2"))) void runOnOctets(const std::vector<std::pair<int, int>>& exchanges,
                                                 int slots, int middle,
                                                 MedianNetwork::Lanes* values, int* counts,
                                                 float* medians) {
  if (!runFixed<OnOctets>(FixedSlots(), slots, values, counts, medians)) {
    runNetwork<FloatOctet, 8>(exchanges, slots, middle, values, counts, medians);
  }
}
#endif

}  // namespace

void MedianNetwork::medians(Lanes* values, int* counts, float* medians) const {
#ifdef OCCUPANCY_FUSION_HAS_AVX2_PATH
  if (use_octets_) {
    runOnOctets(exchanges_, slots_, middle_, values, counts, medians);
    return;
  }
#endif
  runOnQuads(exchanges_, slots_, middle_, values, counts, medians);
}

}  // namespace occupancy_fusion
