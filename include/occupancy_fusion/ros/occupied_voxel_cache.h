// Centres of the occupied voxels of a VoxelMap, kept per block and refreshed from the map's change
// log, so building markers and clouds costs what changed plus what is sent, not the map's size.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

class OccupiedVoxelCache {
 public:
  struct RefreshStats {
    bool full_rebuild = false;
    std::size_t blocks_refreshed = 0;  // blocks re-read from the map
  };

  // Re-reads the blocks written or removed since the last refresh (all of them the first time,
  // or when the map's change log no longer reaches back that far).
  RefreshStats refresh(const VoxelMap& map);

  std::size_t occupiedCount() const { return occupied_count_; }
  std::size_t blockCount() const { return blocks_.size(); }
  std::uint64_t mapVersion() const { return version_; }  // version the cache reflects

  // fn(const Eigen::Vector3f& centre) for every occupied voxel, block by block.
  template <typename Fn>
  void forEachCentre(Fn&& fn) const {
    for (const auto& entry : blocks_) {
      for (const Eigen::Vector3f& centre : entry.second) fn(centre);
    }
  }

 private:
  void storeBlock(const VoxelMap& map, const BlockIndex& index, const VoxelBlock& block);
  void dropBlock(std::uint64_t key);

  SpatialKeyMap<std::vector<Eigen::Vector3f>> blocks_;  // keyed by packKey(block)
  std::size_t occupied_count_ = 0;
  std::uint64_t version_ = 0;
};

}  // namespace occupancy_fusion
