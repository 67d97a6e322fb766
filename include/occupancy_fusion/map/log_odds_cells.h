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

// Sees what a map's writers change (VoxelMap and GridLayer2D::setWriteWatcher): how a submap
// records what its stretch of frames wrote (mapping/submap_fusion.h) without a second integration.
// `Index` names a block or tile, `Cells` is its storage.
template <class Index, class Cells>
class CellsWriteWatcher {
 public:
  virtual ~CellsWriteWatcher() = default;
  // Before a block's (tile's) first write since the watcher was set; `before` is its contents
  // then (nullptr: the map had none). May come again for one that went to the spill store and
  // came back: the first call holds its contents. Runs under the map's exclusive lock: must not
  // call the map.
  virtual void beforeFirstWrite(const Index& index, const Cells* before) = 0;
};

}  // namespace occupancy_fusion
