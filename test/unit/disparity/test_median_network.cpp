// MedianNetwork: the upper median of every lane's set against std::nth_element on the same
// values, for set sizes up to the network's widest and every number of missing values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "occupancy_fusion/integrators/stereo/median_network.h"

namespace occupancy_fusion {
namespace {

constexpr int kLanes = MedianNetwork::kLanes;

float upperMedian(std::vector<float> values) {
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// Lane l's set: counts[l] values at random rows, NaN in the others.
void expectMediansOf(const MedianNetwork& network, const int* counts, std::mt19937* rng,
                     bool ties) {
  std::uniform_real_distribution<float> uniform(-5.0f, 5.0f);
  std::vector<MedianNetwork::Lanes> rows(network.slots());
  std::vector<std::vector<float>> sets(kLanes);
  for (int l = 0; l < kLanes; ++l) {
    std::vector<int> order(network.slots());
    for (int r = 0; r < network.slots(); ++r) order[r] = r;
    std::shuffle(order.begin(), order.end(), *rng);
    for (int k = 0; k < network.slots(); ++k) {
      float value = std::nanf("");
      if (k < counts[l]) {
        value = ties ? std::round(uniform(*rng)) : uniform(*rng);  // rounded: many equal
        sets[l].push_back(value);
      }
      rows[order[k]][l] = value;
    }
  }
  int found[kLanes];
  float medians[kLanes];
  network.medians(rows.data(), found, medians);
  for (int l = 0; l < kLanes; ++l) {
    ASSERT_EQ(found[l], counts[l]) << "slots " << network.slots() << ", lane " << l;
    if (counts[l] == 0) continue;
    EXPECT_EQ(medians[l], upperMedian(sets[l]))
        << "slots " << network.slots() << ", lane " << l << ", " << counts[l] << " values";
  }
}

// The widest vectors the processor has (AVX2 on most x86-64) and plain x86-64's: each against
// std::nth_element.
constexpr MedianNetwork::Instructions kInstructions[] = {MedianNetwork::Instructions::kWidest,
                                                         MedianNetwork::Instructions::kBaseline};

TEST(MedianNetwork, GivesTheUpperMedianOfEverySet) {
  for (const auto instructions : kInstructions) {
    SCOPED_TRACE(instructions == MedianNetwork::Instructions::kWidest ? "widest" : "baseline");
    std::mt19937 rng(7);
    for (int slots : {1, 2, 3, 5, 13, 16, 17, 25, 41, 61, 113, 481, 961, 1024}) {
      const MedianNetwork network(slots, instructions);
      std::uniform_int_distribution<int> count_of(0, slots);
      for (int trial = 0; trial < 60; ++trial) {
        int counts[kLanes];
        for (int& count : counts) count = count_of(rng);
        expectMediansOf(network, counts, &rng, trial % 2 == 1);
      }
    }
  }
}

TEST(MedianNetwork, EveryCountOfValidValues) {
  // The missing values become -inf or +inf so that the upper median lands on the middle wire,
  // for each count, even or odd, and wherever the missing values are.
  for (const auto instructions : kInstructions) {
    std::mt19937 rng(11);
    for (int slots : {24, 25}) {
      const MedianNetwork network(slots, instructions);
      for (int count = 0; count <= slots; ++count) {
        int counts[kLanes];
        for (int& c : counts) c = count;
        expectMediansOf(network, counts, &rng, false);
      }
    }
  }
}

TEST(MedianNetwork, BothInstructionSetsGiveTheSameBits) {
  // The measured surface's maps must not depend on the processor: the same rows, with missing
  // values and ties, through both.
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> uniform(-5.0f, 5.0f);
  std::bernoulli_distribution missing(0.3);
  for (int slots : {7, 25, 113}) {
    const MedianNetwork widest(slots, MedianNetwork::Instructions::kWidest);
    const MedianNetwork baseline(slots, MedianNetwork::Instructions::kBaseline);
    for (int trial = 0; trial < 50; ++trial) {
      std::vector<MedianNetwork::Lanes> rows(slots);
      for (auto& row : rows) {
        for (float& value : row) value = missing(rng) ? std::nanf("") : std::round(uniform(rng));
      }
      std::vector<MedianNetwork::Lanes> copy = rows;
      int counts[kLanes], baseline_counts[kLanes];
      float medians[kLanes], baseline_medians[kLanes];
      widest.medians(rows.data(), counts, medians);
      baseline.medians(copy.data(), baseline_counts, baseline_medians);
      for (int l = 0; l < kLanes; ++l) {
        EXPECT_EQ(counts[l], baseline_counts[l]);
        if (counts[l] > 0) {
          EXPECT_EQ(medians[l], baseline_medians[l]);
        }
      }
    }
  }
}

TEST(MedianNetwork, PrunesWhatTheMedianDoesNotNeed) {
  // Batcher's odd-even merge sort of 32 wires has 191 compare-exchanges, of 25 wires (those with
  // a wire >= 25 dropped) fewer; the median needs fewer still.
  const MedianNetwork network(25);
  EXPECT_LT(network.exchanges(), 191u);
  EXPECT_GT(network.exchanges(), 24u);  // every value is compared at least once
}

TEST(MedianNetwork, RejectsSizesItCannotHold) {
  EXPECT_THROW(MedianNetwork(0), std::invalid_argument);
  EXPECT_THROW(MedianNetwork(MedianNetwork::kMaxSlots + 1), std::invalid_argument);
}

}  // namespace
}  // namespace occupancy_fusion
