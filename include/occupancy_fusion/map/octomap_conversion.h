// Conversion between the voxel map and liboctomap's OcTree (for .bt/.ot files and the octomap
// binary message). The OcTree is an export format here, not the live store.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

// OctoMap keys are 16 bit: voxel index i maps to key i + 32768, so only indices in
// [-32768, 32767] per axis can be exported.
constexpr int kOctomapKeyOffset = 32768;
bool isOctomapRepresentable(const VoxelIndex& index);

// Every known voxel becomes a leaf at full depth holding its log-odds (OcTree::setNodeValue, which
// clamps to the tree's thresholds, set equal to the map's), then inner nodes are updated and equal
// siblings pruned. The tree's hit/miss/clamping/occupancy parameters are the map's model.
// Voxels outside the key range are skipped; their number goes to *skipped_voxels if given.
// The map is read through VoxelMap::copyBlocks, so its lock is held only for the copy.
std::unique_ptr<octomap::OcTree> toOcTree(const VoxelMap& map,
                                          std::size_t* skipped_voxels = nullptr);
// The same from blocks already copied (callers that time or reuse the copy).
std::unique_ptr<octomap::OcTree> toOcTree(const std::vector<VoxelMap::BlockCopy>& blocks,
                                          double resolution, const OccupancyModel& model,
                                          std::size_t* skipped_voxels = nullptr);

// Writes every leaf of the tree into the map (setLogOdds semantics: values as stored, existing
// voxels overwritten, others untouched). A leaf above full depth (a pruned subtree) expands to
// all voxels it covers. Throws std::invalid_argument, leaving the map untouched, if the
// resolutions differ or the leaves cover more than max_voxels voxels (the default, 2^28, about
// 3 GiB while importing, refuses absurd files: one root leaf covers 2^48 voxels).
constexpr std::size_t kMaxImportedVoxels = std::size_t{1} << 28;
void fromOcTree(const octomap::OcTree& tree, VoxelMap* map,
                std::size_t max_voxels = kMaxImportedVoxels);

// Sets the tree's hit/miss/clamping/occupancy parameters from the model.
void applyModel(const OccupancyModel& model, octomap::OcTree* tree);

// Reads a .bt (binary: labels only; liboctomap sets occupied leaves to the clamping maximum and
// free ones to the minimum, here those of `model`) or .ot (full log-odds) file; the tree gets the
// model's parameters. The kind is taken from the file's first line, not its name. The node data
// is checked before liboctomap reads it: it must hold exactly the number of nodes the header
// declares (liboctomap alone returns part of the tree from a truncated file), none below voxel
// depth, and (.ot) finite log-odds. Throws std::runtime_error naming the path and what is wrong,
// also if the file holds another tree type.
std::unique_ptr<octomap::OcTree> readOcTreeFile(const std::string& path,
                                                const OccupancyModel& model = OccupancyModel());
// The same for the file's bytes; `name` goes into the messages.
std::unique_ptr<octomap::OcTree> parseOcTree(const std::string& bytes, const std::string& name,
                                             const OccupancyModel& model = OccupancyModel());

}  // namespace occupancy_fusion
