// The map's unit of storage as readers and integrators see it: a dense cube of voxels.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace occupancy_fusion {

// A dense cube of kSide^3 voxels. NaN log-odds marks a voxel that was never observed.
struct VoxelBlock {
  static constexpr int kSideLog2 = 3;
  static constexpr int kSide = 1 << kSideLog2;
  static constexpr int kVolume = kSide * kSide * kSide;
  static constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();

  VoxelBlock() { log_odds.fill(kUnknown); }

  // x fastest, so a sweep along x walks memory in order.
  static int linearIndex(int x, int y, int z) { return x + kSide * (y + kSide * z); }
  static int linearIndex(const Eigen::Vector3i& local) {
    return linearIndex(local.x(), local.y(), local.z());
  }
  static Eigen::Vector3i localIndex(int linear) {
    return {linear & (kSide - 1), (linear >> kSideLog2) & (kSide - 1), linear >> (2 * kSideLog2)};
  }
  static bool isKnown(float value) { return !std::isnan(value); }

  // Adds delta to one voxel (an unknown voxel starts at the prior, 0) and clamps to
  // [min_log_odds, max_log_odds] (VoxelMap::minLogOdds(), maxLogOdds()).
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
  void set(int linear, float value) {
    if (isKnown(value) != isKnown(log_odds[linear])) known_count += isKnown(value) ? 1 : -1;
    log_odds[linear] = value;
  }

  std::array<float, kVolume> log_odds;
  int known_count = 0;
  std::uint64_t version = 0;  // map version of the last write; maintained by VoxelMap
};

}  // namespace occupancy_fusion
