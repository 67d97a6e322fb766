// Map files: OctoMap .bt/.ot, map_server's .pgm + .yaml, NumPy .npy, PCL .pcd and .png pictures.
// Every writer is atomic (a temporary file in the same folder, then a rename, so a reader never
// sees half a file) and throws std::runtime_error naming the path when it fails.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

// Calls write(stream) on a temporary file beside `path`, then renames it to `path`.
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

// OctoMap files of the map: the bytes liboctomap writes for toOcTree's tree, streamed from the
// blocks one at a time (octree_files.h), so also for a map larger than memory. .bt holds labels
// only (occupied / free, pruned to maximum likelihood); .ot holds every log-odds. Return the
// number of voxels skipped because they lie outside OctoMap's 16-bit key range.
std::size_t writeBt(const VoxelMap& map, const std::string& path);
std::size_t writeOt(const VoxelMap& map, const std::string& path);

// Reads a .bt or .ot file (kind from the file's content) into a new map whose resolution is the
// file's and whose other settings are `base`'s. A .bt file's occupied voxels get base's maximum
// log-odds and its free ones the minimum.
std::unique_ptr<VoxelMap> readOctomapFile(const std::string& path, const VoxelMapConfig& base);

// map_server's format (what map_saver writes): <prefix>.pgm (P5, 8 bit; occupied 0, free 254,
// unknown 205; the first row is the top of the map, i.e. the highest y) and <prefix>.yaml
// (image: the pgm's file name relative to the yaml, resolution, origin [x, y, 0.0], negate: 0,
// occupied_thresh: 0.65, free_thresh: 0.196). Throws std::invalid_argument for an empty raster.
void writeMapServerFiles(const OccupancyRaster& raster, const std::string& prefix);

// NumPy .npy, format version 1.0: dtype '<f4', C order, shape (height, width), NaN = unknown.
// Row 0 is the lowest y (the raster's origin row), so array[y, x] is raster.at(x, y).
void writeNpy(const LogOddsRaster& raster, const std::string& path);
// The bytes writeNpy writes. Throws std::invalid_argument for a data size not width x height.
std::string encodeNpy(const LogOddsRaster& raster);
// Its parts, for an array written in pieces: the header of a '<f4' C-order (rows, columns)
// array, and values appended as little-endian float32.
std::string npyFloatHeader(int rows, int columns);
void appendLittleEndianFloats(const std::vector<float>& values, std::string* bytes);

// PCD v0.7 with fields x y z probability (float32): the centre and occupancy probability of every
// known voxel, in voxel order (z, then y, then x). WIDTH = number of points, HEIGHT = 1.
enum class PcdEncoding { kBinary, kAscii };
void writePcd(const VoxelMap& map, const std::string& path,
              PcdEncoding encoding = PcdEncoding::kBinary);

// The raster as an 8-bit grey picture, y up (the first image row is the highest y): unknown
// grey (128), free white (255), occupied black (0). Each cell becomes scale x scale pixels, to make
// small maps visible. The format follows the file name (OpenCV imencode), normally .png.
// Throws std::invalid_argument for an empty raster or scale < 1.
void writePng(const OccupancyRaster& raster, const std::string& path, int scale = 1);

}  // namespace occupancy_fusion
