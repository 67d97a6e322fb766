// MedianNetwork: the upper median of every lane's set against std::nth_element on the same
// values, for every set size up to the network's and every number of valid values.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

#include "occupancy_fusion/integrators/median_network.h"

namespace occupancy_fusion {
namespace {

constexpr int kLanes = MedianNetwork::kLanes;

float upperMedian(std::vector<float> values) {
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

void expectMediansOf(const MedianNetwork& network, std::mt19937* rng, bool ties) {
  std::uniform_real_distribution<float> uniform(-5.0f, 5.0f);
  std::uniform_int_distribution<int> count_of(1, network.slots());
  std::vector<MedianNetwork::Lanes> rows(network.slots());
  std::vector<std::vector<float>> sets(kLanes);
  int counts[kLanes];
  for (int l = 0; l < kLanes; ++l) {
    counts[l] = count_of(*rng);
    for (int r = 0; r < network.slots(); ++r) {
      // Rows past the count hold anything, also what a median must not return.
      float value = r < counts[l] ? uniform(*rng) : 1e9f;
      if (ties && r < counts[l]) value = std::round(value);  // many equal values
      rows[r][l] = value;
      if (r < counts[l]) sets[l].push_back(value);
    }
  }
  float medians[kLanes];
  network.medians(rows.data(), counts, medians);
  for (int l = 0; l < kLanes; ++l) {
    EXPECT_EQ(medians[l], upperMedian(sets[l]))
        << "slots " << network.slots() << ", lane " << l << ", " << counts[l] << " values";
  }
}

TEST(MedianNetwork, GivesTheUpperMedianOfEverySet) {
  std::mt19937 rng(7);
  for (int slots : {1, 2, 3, 5, 13, 16, 17, 25, 41, 61, 113, 481, 512}) {
    const MedianNetwork network(slots);
    for (int trial = 0; trial < 60; ++trial) expectMediansOf(network, &rng, trial % 2 == 1);
  }
}

TEST(MedianNetwork, EveryCountOfValidValues) {
  // The padding with -inf and +inf must put the upper median on the middle wire for each count.
  std::mt19937 rng(11);
  const MedianNetwork network(25);
  std::uniform_real_distribution<float> uniform(0.0f, 100.0f);
  for (int count = 1; count <= 25; ++count) {
    std::vector<MedianNetwork::Lanes> rows(25);
    int counts[kLanes];
    std::vector<std::vector<float>> sets(kLanes);
    for (int l = 0; l < kLanes; ++l) {
      counts[l] = count;
      for (int r = 0; r < count; ++r) sets[l].push_back(rows[r][l] = uniform(rng));
    }
    float medians[kLanes];
    network.medians(rows.data(), counts, medians);
    for (int l = 0; l < kLanes; ++l) EXPECT_EQ(medians[l], upperMedian(sets[l])) << count;
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
