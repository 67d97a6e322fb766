#include "occupancy_fusion/ros/occupied_voxel_cache.h"

namespace occupancy_fusion {

void OccupiedVoxelCache::dropBlock(std::uint64_t key) {
  auto found = blocks_.find(key);
  if (found == blocks_.end()) return;
  occupied_count_ -= found->second.size();
  blocks_.erase(found);
}

void OccupiedVoxelCache::storeBlock(const VoxelMap& map, const BlockIndex& index,
                                    const VoxelBlock& block) {
  const std::uint64_t key = packKey(index);
  dropBlock(key);
  std::vector<Eigen::Vector3f> centres;
  const float threshold = map.model().thresholdLogOdds();
  for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
    const float value = block.log_odds[linear];
    // NaN (unknown) compares false, so only known voxels above the threshold pass.
    if (value > threshold) {
      centres.push_back(map.centerOf(VoxelMap::voxelIndex(index, linear)).cast<float>());
    }
  }
  if (centres.empty()) return;
  occupied_count_ += centres.size();
  blocks_.emplace(key, std::move(centres));
}

OccupiedVoxelCache::RefreshStats OccupiedVoxelCache::refresh(const VoxelMap& map) {
  RefreshStats stats;
  const MapChanges changes = map.changesSince(version_);
  if (changes.full_rebuild) {
    stats.full_rebuild = true;
    blocks_.clear();
    occupied_count_ = 0;
    map.forEachBlock([&](const BlockIndex& index, const VoxelBlock& block) {
      storeBlock(map, index, block);
      ++stats.blocks_refreshed;
    });
  } else {
    // A block listed as changed may have been removed later and vice versa: the map's current
    // content decides.
    VoxelBlock copy;
    auto reread = [&](const BlockIndex& index) {
      if (map.copyBlock(index, &copy)) {
        storeBlock(map, index, copy);
      } else {
        dropBlock(packKey(index));
      }
      ++stats.blocks_refreshed;
    };
    for (const BlockIndex& index : changes.changed) reread(index);
    for (const BlockIndex& index : changes.removed) reread(index);
  }
  version_ = changes.version;
  return stats;
}

}  // namespace occupancy_fusion
