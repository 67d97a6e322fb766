// Resuming a saved map (the MapServer's load_map, offline_mapper's --load-map): the voxels from an
// OctoMap file and, beside it, the 2D laser layer from <prefix>.laser.yaml / .laser.npy (see
// layer_files.h), as ~save_map, save_on_shutdown and offline_mapper write them.
#pragma once

#include <cstddef>
#include <string>

#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

struct ResumedMap {
  std::size_t known_voxels_before = 0;  // the map was not empty: the file's voxels replaced these
  std::size_t known_voxels = 0;         // after loading
  bool labels_only = false;             // a .bt file: occupied / free at the clamping bounds
  std::string layer_yaml;               // the laser layer files looked for
  bool layer_found = false;             // absent: saved without a layer (older save, other tool)
  std::size_t layer_cells = 0;          // known layer cells after loading
};

// The laser layer's yaml that belongs to a saved map file: <path without .ot/.bt>.laser.yaml.
std::string layerYamlBeside(const std::string& octomap_path);

// Reads `path` (.ot: every log-odds exactly; .bt: labels) into `voxels` in one write, and the
// layer files beside it, when present, into `layer`. Both files are read and checked before either
// is touched. Throws std::runtime_error naming the file and what is wrong (missing, truncated,
// another resolution, damaged layer files).
ResumedMap resumeSavedMap(const std::string& path, VoxelMap* voxels, GridLayer2D* layer);

}  // namespace occupancy_fusion
