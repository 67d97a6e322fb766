// The upper medians of many small sets of values at once, by a sorting network pruned to its
// middle output: the same compare-exchanges for every set, without a data-dependent branch, so
// that the compiler runs kLanes sets in one vector register. The measured surface takes one
// median per grid point, tens of thousands a frame; std::nth_element mispredicts its branches on
// noisy values and sorts one set at a time.
#pragma once

#include <array>
#include <cstddef>
#include <utility>
#include <vector>

namespace occupancy_fusion {

class MedianNetwork {
 public:
  static constexpr int kLanes = 8;  // sets per call, one per lane
  static constexpr int kMaxSlots = 1024;
  using Lanes = std::array<float, kLanes>;  // one value of each set

  // The vector instructions the network runs on: the widest the processor has (AVX2 on x86-64,
  // chosen at run time), or plain x86-64's (SSE2). Both give the same bits.
  enum class Instructions { kWidest, kBaseline };

  // For sets of up to `slots` values (1 .. kMaxSlots); throws std::invalid_argument otherwise.
  explicit MedianNetwork(int slots, Instructions instructions = Instructions::kWidest);

  int slots() const { return slots_; }
  std::size_t exchanges() const { return exchanges_.size(); }

  // values: slots() rows, lane l's set in column l, NaN where a set has fewer values than
  // slots. Overwrites the rows; returns in counts[l] the number of lane l's values and in
  // medians[l] their upper median (the value of rank count / 2, counted from 0; any value where
  // the lane has none).
  void medians(Lanes* values, int* counts, float* medians) const;

 private:
  int slots_;
  int middle_;                                  // the output wire of the median
  bool use_octets_;                             // AVX2: the lanes in one vector, not two
  std::vector<std::pair<int, int>> exchanges_;  // (low, high) wires, in order
};

}  // namespace occupancy_fusion
