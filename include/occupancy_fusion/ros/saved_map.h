// Resuming a saved map (the MapServer's load_map): the voxels from an OctoMap file and, beside it,
// the 2D laser layer from <prefix>.laser.yaml / .laser.npy (see layer_files.h), as ~save_map and
// save_on_shutdown write them (saveMapFiles).
#pragma once

#include <cstddef>
#include <string>

#include "occupancy_fusion/ros/map_registry.h"

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

// Reads `path` (.ot: every log-odds exactly; .bt: labels) into the map's voxels in one write, and
// the layer files beside it, when present, into its 2D layer. Both files are read and checked
// before the map is touched. Throws std::runtime_error naming the file and what is wrong (missing,
// truncated, another resolution, damaged layer files).
ResumedMap resumeSavedMap(const std::string& path, SharedMap* map);

}  // namespace occupancy_fusion
