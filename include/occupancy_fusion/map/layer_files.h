// The 2D laser layer's own files, so that a saved map resumes with its laser cells as well as its
// voxels (the .ot holds voxels only):
//   <prefix>.laser.npy   NumPy format 1.0, '<f4', C order, shape (height, width): the log-odds of
//                        the layer's known window, NaN = unknown, row 0 the lowest y (as writeNpy)
//   <prefix>.laser.yaml  what places the array: the .npy's file name (relative to the yaml) and
//                        its CRC-32 (log_odds_crc32, as zlib.crc32 computes it), resolution,
//                        origin_cell (cell index of array[0, 0]), origin (its lower-left corner in
//                        metres, origin_cell * resolution) and width / height
// Each file is written atomically, the .npy first. On reading, the array must have the yaml's
// CRC-32 (when the yaml gives one) and shape: a yaml and an array of different saves (a crash
// between the two writes, a file copied alone) are refused.
#pragma once

#include <string>

#include "occupancy_fusion/map/grid_layer_2d.h"

namespace occupancy_fusion {

struct LayerFilePaths {
  std::string yaml;  // <prefix>.laser.yaml
  std::string npy;   // <prefix>.laser.npy
};
LayerFilePaths layerFilePaths(const std::string& prefix);

// Writes a layer's known window (GridLayer2D::toLogOddsRaster; an empty layer gives a 0 x 0
// array). Throws std::runtime_error naming the file that cannot be written.
LayerFilePaths writeLayerFiles(const LogOddsRaster& layer_window, const std::string& prefix);
// The same bytes from the layer itself, read one row of tiles at a time (each strip as it is when
// read): a layer whose tiles are in the map's store is written without holding its window.
LayerFilePaths writeLayerFiles(const GridLayer2D& layer, const std::string& prefix);

// Parses the yaml's text and the .npy's bytes into a raster. Throws std::runtime_error saying what
// is wrong: a missing or malformed key, a CRC-32 other than the array's, a .npy that is not a 2D
// '<f4' C-order array, a shape other
// than the yaml's, a size other than the shape's, an infinite value, a window outside the layer's
// coordinate range.
LogOddsRaster parseLayerFiles(const std::string& yaml_text, const std::string& npy_bytes);

// Reads <yaml_path> and the .npy it names. Errors name the file.
LogOddsRaster readLayerFiles(const std::string& yaml_path);

}  // namespace occupancy_fusion
