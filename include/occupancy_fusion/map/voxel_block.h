// The map's unit of storage as readers and integrators see it: a dense cube of voxels.
#pragma once

#include <Eigen/Core>

#include "occupancy_fusion/map/log_odds_cells.h"

namespace occupancy_fusion {

// A dense cube of kSide^3 voxels. NaN log-odds marks a voxel that was never observed; version is
// maintained by VoxelMap.
struct VoxelBlock : LogOddsCells<8 * 8 * 8> {
  static constexpr int kSideLog2 = 3;
  static constexpr int kSide = 1 << kSideLog2;
  static constexpr int kVolume = kSide * kSide * kSide;
  static_assert(kVolume == kCellCount, "kSide^3 cells");

  // x fastest, so a sweep along x walks memory in order.
  static int linearIndex(int x, int y, int z) { return x + kSide * (y + kSide * z); }
  static int linearIndex(const Eigen::Vector3i& local) {
    return linearIndex(local.x(), local.y(), local.z());
  }
  static Eigen::Vector3i localIndex(int linear) {
    return {linear & (kSide - 1), (linear >> kSideLog2) & (kSide - 1), linear >> (2 * kSideLog2)};
  }
};

}  // namespace occupancy_fusion
