// Checkpoints of a map with its 2D laser layer (VoxelMapConfig::checkpoint_period): the voxels'
// blocks and the layer's tiles changed since the previous checkpoint go into the map's store in
// one transaction, so that the two resume together; a layer constructed beside a map that
// resumed a checkpoint gets that checkpoint's tiles back. The same store takes the layer's tiles
// beyond its memory bound (VoxelMapConfig::layer_max_memory_bytes).
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

// The laser layer that goes with a map: its resolution, sensor model and memory bound.
GridLayer2DConfig laserLayerConfig(const VoxelMapConfig& map);

// The time now in UTC, ISO 8601 ("2026-12-02T22:29:57Z"): what the MapServer and offline_mapper
// stamp their checkpoints with.
std::string checkpointStampNow();

class MapCheckpoints {
 public:
  // Gives `layer` the map's store for the tiles beyond its memory bound (when both are set),
  // and restores into it the tiles of the checkpoint `voxels` resumed, if it resumed one. Throws
  // std::runtime_error naming the store's folder for a damaged tile record. `voxels` must outlive
  // `layer`.
  MapCheckpoints(VoxelMap* voxels, GridLayer2D* layer);

  // VoxelMap::checkpoint with the layer's tiles changed since the previous one (all of them at
  // the first, or when the layer's change log no longer reaches back), and `companion` when
  // given: the bytes of what goes with the map (its submaps), in the same transaction.
  CheckpointResult checkpoint(const std::string& stamp,
                              const std::vector<unsigned char>* companion = nullptr);
  std::size_t resumedTiles() const { return resumed_tiles_; }
  // The companion bytes of the checkpoint resumed (empty: none).
  const std::vector<unsigned char>& resumedCompanion() const { return resumed_companion_; }
  // The store's key for them: a layer record no tile can have (tiles' x stays within +-2^25).
  static const std::uint64_t kCompanionKey;

 private:
  std::runtime_error damagedTile(std::uint64_t key, std::size_t size) const;

  VoxelMap* voxels_;
  GridLayer2D* layer_;
  std::uint64_t layer_version_ = 0;  // the layer's version the last checkpoint holds
  std::size_t resumed_tiles_ = 0;
  std::vector<unsigned char> resumed_companion_;
};

}  // namespace occupancy_fusion
