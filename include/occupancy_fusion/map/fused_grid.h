// The fused 2D occupancy grid: the 3D map projected over a height band (octomap_server's
// projected_map) combined with the 2D laser layer.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <mutex>
#include <vector>

#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

// ROS-free equivalent of nav_msgs/OccupancyGrid. Row-major from the origin: data[x + width * y]
// is the cell whose lower-left corner is origin + (x, y) * resolution, so row 0 is the lowest y.
struct OccupancyRaster {
  static constexpr std::int8_t kUnknown = -1;
  static constexpr std::int8_t kFree = 0;
  static constexpr std::int8_t kOccupied = 100;

  double resolution = 0.0;  // m per cell
  double origin_x = 0.0;    // m, map frame position of cell (0, 0)'s corner
  double origin_y = 0.0;
  int width = 0;
  int height = 0;
  std::vector<std::int8_t> data;

  std::int8_t at(int x, int y) const { return data[static_cast<std::size_t>(x + width * y)]; }
  bool empty() const { return width == 0 || height == 0; }
};

struct FusedGridConfig {
  // m; voxels whose centre z lies in [min_z, max_z] are projected (octomap_server's
  // occupancy_min_z / occupancy_max_z, unbounded by default as there).
  double min_z = -std::numeric_limits<double>::infinity();
  double max_z = std::numeric_limits<double>::infinity();

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// Fusion rule per column of the 3D map's resolution: occupied if any projected voxel or any
// overlapping 2D cell is occupied, else free if any of them is free, else unknown. The 2D layer is
// resampled by area overlap: a layer cell contributes to every column its square overlaps (with a
// positive area), so layers finer or coarser than the 3D map both work.
//
// Reference implementation (non-incremental): walks every known voxel and cell. The raster covers
// the bounding box of the known columns; an empty raster (width = height = 0) if none.
OccupancyRaster projectToRaster(const VoxelMap& map, const GridLayer2D* layer,
                                const FusedGridConfig& config);

// Incremental fused view. Keeps, per column, the counts of occupied and free voxels inside the
// band (and each map block's share of them) and the resampled 2D state, and on update() only
// recomputes the columns of the blocks and tiles reported by changesSince(); a full rebuild
// happens on the first call, when a change log no longer reaches back (e.g. after reset()), or
// when a different map or layer object is passed. The result equals projectToRaster().
//
// Thread safety: update() may be called from any thread; calls are serialised by an internal
// mutex. It reads the map and layer through their public (shared-lock) API, so writers may keep
// writing: what they write during an update shows up at the latest in the next one.
class FusedGridView {
 public:
  explicit FusedGridView(const FusedGridConfig& config = FusedGridConfig());  // validates

  const FusedGridConfig& config() const { return config_; }

  // layer may be null (no 2D layer). Returns the fused raster over everything known.
  OccupancyRaster update(const VoxelMap& map, const GridLayer2D* layer);
  // Forget all state: the next update() rebuilds from scratch. Maps and layers are recognised by
  // address, so call this when one is destroyed and another may take its place.
  void reset();

  // What the last update() did, for tests and diagnostics.
  struct UpdateStats {
    bool map_rebuilt = false;
    bool layer_rebuilt = false;
    std::size_t map_blocks_processed = 0;
    std::size_t layer_tiles_processed = 0;
  };
  const UpdateStats& lastUpdateStats() const { return stats_; }

 private:
  static constexpr int kSide = VoxelBlock::kSide;
  static constexpr int kArea = kSide * kSide;
  // Per column (the x-y footprint of one map block): band counts and the resampled 2D state.
  struct ColumnTile {
    ColumnTile() { layer.fill(-1); }
    std::array<std::uint32_t, kArea> occupied{};
    std::array<std::uint32_t, kArea> free{};
    std::array<std::int8_t, kArea> layer;  // -1 unknown, 0 free, 1 occupied
  };
  // One map block's share of its column tile's counts.
  struct BlockShare {
    std::array<std::uint8_t, kArea> occupied{};
    std::array<std::uint8_t, kArea> free{};
  };
  using TileTable = SpatialKeyMap<ColumnTile>;   // keyed by packKey(column tile)
  using ShareTable = SpatialKeyMap<BlockShare>;  // keyed by packKey(map block)

  void updateFromMap(const VoxelMap& map);
  void rebuildFromMap(const VoxelMap& map);
  void refreshBlock(const VoxelMap& map, const BlockIndex& block);
  bool computeShare(const VoxelMap& map, const BlockIndex& block_index, const VoxelBlock& block,
                    BlockShare* share) const;
  void applyShare(const BlockIndex& block, const BlockShare& share, int sign);
  void updateFromLayer(const GridLayer2D* layer);
  void refreshLayerTile(const GridLayer2D& layer, const TileIndex& tile);
  void dropEmptyColumnTiles();
  OccupancyRaster compose() const;

  FusedGridConfig config_;
  std::mutex mutex_;
  UpdateStats stats_;

  const VoxelMap* map_ = nullptr;  // the map the state was built from
  double resolution_ = 0.0;        // its resolution (column size)
  std::uint64_t map_version_ = 0;
  ShareTable shares_;

  const GridLayer2D* layer_ = nullptr;
  bool layer_valid_ = false;  // the columns' 2D states match layer_ at layer_version_
  std::uint64_t layer_version_ = 0;

  TileTable columns_;
};

}  // namespace occupancy_fusion
