#include "occupancy_fusion/map/octomap_conversion.h"

#include <cmath>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "occupancy_fusion/map/spatial_key.h"

namespace occupancy_fusion {
namespace {

constexpr char kBinaryHeader[] = "# Octomap OcTree binary file";
constexpr char kFullHeader[] = "# Octomap OcTree file";

bool startsWith(const std::string& text, const std::string& prefix) {
  return text.compare(0, prefix.size(), prefix) == 0;
}

VoxelIndex indexOfKey(const octomap::OcTreeKey& key) {
  return {static_cast<int>(key[0]) - kOctomapKeyOffset,
          static_cast<int>(key[1]) - kOctomapKeyOffset,
          static_cast<int>(key[2]) - kOctomapKeyOffset};
}

// Voxel writes grouped per block, so the import allocates and fills each block once.
struct BlockWrites {
  std::vector<std::pair<int, float>> values;  // (linear index in block, log-odds)
};

}  // namespace

bool isOctomapRepresentable(const VoxelIndex& index) {
  return (index.array() >= -kOctomapKeyOffset).all() && (index.array() < kOctomapKeyOffset).all();
}

void applyModel(const OccupancyModel& model, octomap::OcTree* tree) {
  tree->setProbHit(model.prob_hit);
  tree->setProbMiss(model.prob_miss);
  tree->setClampingThresMin(model.clamp_min);
  tree->setClampingThresMax(model.clamp_max);
  tree->setOccupancyThres(model.occupancy_threshold);
}

std::unique_ptr<octomap::OcTree> toOcTree(const VoxelMap& map, std::size_t* skipped_voxels) {
  auto tree = std::make_unique<octomap::OcTree>(map.resolution());
  applyModel(map.model(), tree.get());
  std::size_t skipped = 0;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    if (!isOctomapRepresentable(index)) {
      ++skipped;
      return;
    }
    // The key of the voxel's centre, computed exactly: floor(((i + 0.5) r) / r) + 32768.
    const octomap::OcTreeKey key(static_cast<octomap::key_type>(index.x() + kOctomapKeyOffset),
                                 static_cast<octomap::key_type>(index.y() + kOctomapKeyOffset),
                                 static_cast<octomap::key_type>(index.z() + kOctomapKeyOffset));
    tree->setNodeValue(key, log_odds, /*lazy_eval=*/true);
  });
  tree->updateInnerOccupancy();
  tree->prune();
  if (skipped_voxels != nullptr) *skipped_voxels = skipped;
  return tree;
}

void fromOcTree(const octomap::OcTree& tree, VoxelMap* map) {
  const double resolution = map->resolution();
  if (std::abs(tree.getResolution() - resolution) > 1e-9 * resolution) {
    throw std::invalid_argument(
        "fromOcTree: the tree's resolution (" + std::to_string(tree.getResolution()) +
        " m) differs from the map's (" + std::to_string(resolution) + " m)");
  }
  const int max_depth = static_cast<int>(tree.getTreeDepth());
  SpatialKeyMap<BlockWrites> writes;  // keyed by packKey(block)
  std::vector<BlockIndex> blocks;
  auto add_voxel = [&](const VoxelIndex& index, float log_odds) {
    const BlockIndex block = VoxelMap::blockOf(index);
    auto [it, inserted] = writes.try_emplace(packKey(block));
    if (inserted) blocks.push_back(block);
    it.value().values.emplace_back(VoxelMap::linearIndexInBlock(index), log_odds);
  };
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const float log_odds = it->getLogOdds();
    const int depth = static_cast<int>(it.getDepth());
    if (depth == max_depth) {
      add_voxel(indexOfKey(it.getKey()), log_odds);
      continue;
    }
    // A leaf at depth d < 16 with key k covers keys [k - n/2, k + n/2) per axis, n = 2^(16-d)
    // (the iterator's child keys are the parent's +- 32768 >> depth).
    const int side = 1 << (max_depth - depth);
    const VoxelIndex first = indexOfKey(it.getKey()) - VoxelIndex::Constant(side / 2);
    for (int z = 0; z < side; ++z) {
      for (int y = 0; y < side; ++y) {
        for (int x = 0; x < side; ++x) add_voxel(first + VoxelIndex(x, y, z), log_odds);
      }
    }
  }
  map->updateBlocks(blocks, [&](const BlockIndex& block, VoxelBlock& target) {
    const auto found = writes.find(packKey(block));
    for (const auto& [linear, value] : found->second.values) target.set(linear, value);
  });
}

std::unique_ptr<octomap::OcTree> readOcTreeFile(const std::string& path,
                                                const OccupancyModel& model) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open octomap file " + path);
  std::string first_line;
  std::getline(in, first_line);
  in.seekg(0);
  std::unique_ptr<octomap::OcTree> tree;
  if (startsWith(first_line, kBinaryHeader)) {
    tree = std::make_unique<octomap::OcTree>(0.1);  // readBinary takes the file's resolution
    // Binary leaves are read as the clamping bounds: set them before reading.
    applyModel(model, tree.get());
    if (!tree->readBinary(in)) throw std::runtime_error("cannot parse binary octomap file " + path);
  } else if (startsWith(first_line, kFullHeader)) {
    std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(in));
    if (!read) throw std::runtime_error("cannot parse octomap file " + path);
    auto* as_octree = dynamic_cast<octomap::OcTree*>(read.get());
    if (as_octree == nullptr) {
      throw std::runtime_error("octomap file " + path + " holds a " + read->getTreeType() +
                               ", not an OcTree");
    }
    read.release();
    tree.reset(as_octree);
    applyModel(model, tree.get());
  } else {
    throw std::runtime_error("not an octomap .bt or .ot file (first line \"" +
                             first_line.substr(0, 40) + "\"): " + path);
  }
  return tree;
}

}  // namespace occupancy_fusion
