// The map's OctoMap files written from its blocks one at a time, without building liboctomap's
// OcTree: .ot (every log-odds) and .bt (maximum likelihood) byte for byte as OcTree::write and
// OcTree::writeBinary write the tree toOcTree builds, with a few dozen bytes of memory a block
// whatever the map's size, so that a map larger than memory (VoxelMap's spill store) is saved
// without holding it all.
//
// An 8^3 voxel block is exactly one node at depth 13 of OctoMap's 16-level tree (its keys are the
// voxel index + 32768, a multiple of 8). The blocks are read once, in the tree's depth-first
// order; what each contributes below its node goes to a scratch file beside the output, what
// lies above is worked out from a summary per block, then each file is written in order: the
// node count its header declares comes before the nodes.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "occupancy_fusion/map/occupancy_model.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

// The blocks to save and how to read one.
struct OctreeBlockSource {
  std::vector<BlockIndex> blocks;  // any order, each once
  // Reads one block; false: it is gone (nothing of it is saved).
  std::function<bool(const BlockIndex&, VoxelBlock*)> read;
};
// Every block of a map, in memory or spilled, each read under the map's shared lock when its turn
// comes: a save of a map being written holds each block as it was when read.
OctreeBlockSource blockSourceOf(const VoxelMap& map);
// Blocks copied before (VoxelMap::copyBlocks); they must outlive the source.
OctreeBlockSource blockSourceOf(const std::vector<VoxelMap::BlockCopy>& blocks);

struct OctreeFilePaths {
  std::string ot;  // empty: not written
  std::string bt;  // empty: not written
};

struct OctreeFilesWritten {
  std::size_t ot_nodes = 0;        // the nodes the .ot declares (the tree pruned of equal siblings)
  std::size_t bt_nodes = 0;        // the nodes the .bt declares (pruned to maximum likelihood)
  std::size_t skipped_voxels = 0;  // outside OctoMap's 16-bit key range, not saved
};

// Writes the files (each atomically, see writeFileAtomically); the tree's clamping and occupancy
// thresholds are the model's, as toOcTree's. Throws std::runtime_error naming the path when a
// file or its scratch file cannot be written.
OctreeFilesWritten writeOctreeFiles(const OctreeBlockSource& source, double resolution,
                                    const OccupancyModel& model, const OctreeFilePaths& paths);

}  // namespace occupancy_fusion
