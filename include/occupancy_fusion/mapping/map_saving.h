// Saving a map: the one saver behind the MapServer's ~save_map and save_on_shutdown and
// offline_mapper, so a map saved live and one saved offline are the same files.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

struct MapSaveOptions {
  FusedGridConfig band;  // height band of the fused 2D view (occupancy_min_z / occupancy_max_z)
  // Also <prefix>.pcd (every known voxel: centre and probability), <prefix>.npy (fusedLogOdds)
  // and <prefix>.png (the 2D view, y up): offline_mapper's files for inspection.
  bool inspection_files = false;
};

// What saveMap wrote.
struct SavedMapFiles {
  int grid_width = 0;  // cells of the fused 2D view (0: no 2D files)
  int grid_height = 0;
  std::size_t octomap_skipped_voxels = 0;  // outside OctoMap's key range, not in .ot / .bt
};

// Called with each read of the map (it takes the map's lock) and how long it took, in ms.
using MapReadTimer = std::function<void(const char* what, double milliseconds)>;

// Saves the map as <prefix>.ot (every log-odds: what load_map reads back exactly), <prefix>.bt
// (occupied / free labels, for OctoMap tools), when the fused 2D view has cells <prefix>.pgm +
// <prefix>.yaml (map_server's format), and <prefix>.laser.npy + <prefix>.laser.yaml (the 2D
// laser layer's log-odds, which load_map resumes with the .ot; layer_files.h); with
// options.inspection_files also the .pcd and, with a 2D view, the .npy and .png. The 2D view and
// the layer are read before the first file is written; the blocks are read one at a time, each
// under the map's shared lock (or from its spill store), into scratch files from which the .ot and
// .bt are both written (octree_files.h), so that the memory does not grow with the map; a save
// while mappers write holds each block as it was when read. Every file is written atomically
// (temporary file, then rename), so each file on disk is either its previous version or the
// complete new one. A map with nothing known (no voxel, no
// layer cell) is not saved: std::runtime_error, and the previous files of the prefix are kept.
// Throws std::runtime_error naming the path of a file that cannot be written; the files completed
// before a failure are appended to *written, in the order above.
SavedMapFiles saveMap(const VoxelMap& voxels, const GridLayer2D& layer, const std::string& prefix,
                      const MapSaveOptions& options, std::vector<std::string>* written,
                      const MapReadTimer& timer = MapReadTimer());

// The log-odds behind the fused 2D view, cell for cell over the same window as `grid` (the view
// of the same inputs): per column, the largest log-odds among the known voxels whose centres lie
// in config's height band and the known layer cells overlapping it; NaN where none is known.
// Classifying it with the model's threshold gives the fused view exactly (its rule "occupied
// wins, then free" is a maximum). Columns are the map's resolution; the layer must have the same
// resolution (a shared map's and a session's do).
LogOddsRaster fusedLogOdds(const VoxelMap& map, const GridLayer2D* layer,
                           const FusedGridConfig& config, const OccupancyRaster& grid);

}  // namespace occupancy_fusion
