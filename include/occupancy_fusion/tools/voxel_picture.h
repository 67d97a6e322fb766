// A picture of a map's occupied voxels in 3D, for the demo and offline_mapper: an oblique
// orthographic view (a parallel projection keeps sizes comparable across the map), each voxel a
// z-buffered square coloured by its height.
#pragma once

#include <cstddef>
#include <opencv2/core.hpp>

#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

struct VoxelPictureConfig {
  int width = 1000;     // px
  int height = 700;     // px
  double yaw = -2.2;    // rad, direction the view looks along, counter-clockwise from +x
  double pitch = 0.75;  // rad, how far the view looks down from the horizontal
  double min_z = -1e9;  // m, voxels below this centre height are left out
  double max_z = 1e9;   // m, and above this (e.g. a ceiling that hides the rest)

  void validate() const;  // throws std::invalid_argument naming the bad field
};

struct VoxelPicture {
  cv::Mat image;           // BGR, white background
  std::size_t voxels = 0;  // occupied voxels drawn
};

// The occupied voxels (VoxelMap::classify) between min_z and max_z, scaled to fit the picture
// with a margin; colours run from blue (lowest drawn voxel) to red (highest), with a darker
// outline where a voxel is at least 4 px wide. An empty map gives a white picture.
VoxelPicture renderOccupiedVoxels(const VoxelMap& map, const VoxelPictureConfig& config = {});

}  // namespace occupancy_fusion
