#include "occupancy_fusion/map/octomap_conversion.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <streambuf>
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

// OcTree nodes sit at depths 0 (the root) to 16 (voxels); liboctomap's readers would follow a
// file's child bits to any depth.
constexpr unsigned kOcTreeDepth = 16;

// The text header of .bt and .ot files, read as liboctomap's AbstractOcTree::readHeader does:
// white-space separated keywords "id", "size", "res", "#" comment lines, unknown keywords
// skipped to the end of their line, and "data" ending the header at the end of its line.
struct OctomapHeader {
  bool binary = false;
  std::string id;
  std::size_t declared_nodes = 0;
  double resolution = 0.0;
  std::size_t data_offset = 0;  // first byte of the node data
};

// A read-only stream buffer over bytes held elsewhere (no copy of a large map file).
class MemoryBuffer : public std::streambuf {
 public:
  MemoryBuffer(const char* begin, const char* end) {
    char* first = const_cast<char*>(begin);  // never written: the buffer is only read
    setg(first, first, first + (end - begin));
  }
};

class HeaderCursor {
 public:
  explicit HeaderCursor(const std::string& bytes, std::size_t at) : bytes_(bytes), at_(at) {}
  std::string token() {
    while (at_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[at_]))) ++at_;
    const std::size_t begin = at_;
    while (at_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[at_]))) ++at_;
    return bytes_.substr(begin, at_ - begin);
  }
  void skipLine() {
    const std::size_t end = bytes_.find('\n', at_);
    at_ = end == std::string::npos ? bytes_.size() : end + 1;
  }
  std::size_t position() const { return at_; }

 private:
  const std::string& bytes_;
  std::size_t at_;
};

double headerNumber(const std::string& token, const char* key) {
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);
  if (token.empty() || end != token.c_str() + token.size()) {
    throw std::runtime_error(std::string("header: bad ") + key + " '" + token.substr(0, 20) + "'");
  }
  return value;
}

OctomapHeader parseOctomapHeader(const std::string& bytes) {
  OctomapHeader header;
  const std::string first_line = bytes.substr(0, bytes.find('\n'));
  if (startsWith(first_line, kBinaryHeader)) {
    header.binary = true;
  } else if (!startsWith(first_line, kFullHeader)) {
    throw std::runtime_error("not an octomap .bt or .ot file (first line \"" +
                             first_line.substr(0, 40) + "\")");
  }
  HeaderCursor cursor(bytes, 0);
  cursor.skipLine();
  bool has_size = false;
  while (true) {
    const std::string token = cursor.token();
    if (token.empty()) throw std::runtime_error("header: no \"data\" line");
    if (token == "data") {
      cursor.skipLine();
      break;
    }
    if (token == "id") {
      header.id = cursor.token();
    } else if (token == "res") {
      header.resolution = headerNumber(cursor.token(), "res");
    } else if (token == "size") {
      const double size = headerNumber(cursor.token(), "size");
      if (!(size >= 0.0 && size <= 4294967295.0 && size == std::floor(size))) {
        throw std::runtime_error("header: bad size " + std::to_string(size));
      }
      header.declared_nodes = static_cast<std::size_t>(size);
      has_size = true;
    } else {
      cursor.skipLine();  // a comment or an unknown keyword
    }
  }
  // liboctomap renames the binary format's deprecated id "1".
  if (header.id != "OcTree" && !(header.binary && header.id == "1")) {
    throw std::runtime_error("holds a '" + header.id.substr(0, 40) + "', not an OcTree");
  }
  if (!(std::isfinite(header.resolution) && header.resolution > 0.0)) {
    throw std::runtime_error("header: resolution must be positive, got " +
                             std::to_string(header.resolution));
  }
  if (!has_size) throw std::runtime_error("header: no size");
  header.data_offset = cursor.position();
  return header;
}

// Walks the node data as liboctomap's readers do (.ot: per node its float log-odds and a byte of
// child flags, depth first; .bt: per node two bytes of 2-bit child codes, 01 free leaf, 10
// occupied leaf, 11 inner node read next), counting nodes. Throws std::runtime_error unless the
// data holds exactly the nodes the header declares, none below voxel depth and (.ot) every
// log-odds finite: liboctomap itself would return part of the tree from a truncated file, and
// follow garbage flags read past its end.
class NodeDataCheck {
 public:
  NodeDataCheck(const std::string& bytes, std::size_t offset) : bytes_(bytes), at_(offset) {}

  std::size_t countFullNodes(unsigned depth) {
    float log_odds;
    std::memcpy(&log_odds, take(sizeof(log_odds)), sizeof(log_odds));
    if (!std::isfinite(log_odds))
      throw std::runtime_error("node " + std::to_string(nodes_) + " has a non-finite log-odds");
    const auto children = static_cast<unsigned char>(*take(1));
    ++nodes_;
    std::size_t count = 1;
    if (children != 0) requireChildDepth(depth + 1);
    for (int i = 0; i < 8; ++i) {
      if (children & (1u << i)) count += countFullNodes(depth + 1);
    }
    return count;
  }

  // The node at `depth` exists; counts its children and their subtrees.
  std::size_t countBinaryChildren(unsigned depth) {
    const char* codes = take(2);
    std::size_t count = 0;
    unsigned inner = 0;  // bit i: child i is an inner node, read after the two bytes
    for (int i = 0; i < 8; ++i) {
      const unsigned code = (static_cast<unsigned char>(codes[i / 4]) >> (2 * (i % 4))) & 3u;
      if (code == 0) continue;
      requireChildDepth(depth + 1);
      ++count;
      if (code == 3) inner |= 1u << i;
    }
    // liboctomap would turn a childless inner node into a leaf of log-odds -FLT_MAX.
    if (depth > 0 && count == 0) throw std::runtime_error("an inner node without children");
    nodes_ += count;
    for (int i = 0; i < 8; ++i) {
      if (inner & (1u << i)) {
        requireChildDepth(depth + 2);  // an inner node has children of its own
        count += countBinaryChildren(depth + 1);
      }
    }
    return count;
  }

 private:
  const char* take(std::size_t count) {
    if (bytes_.size() - at_ < count) {
      throw std::runtime_error("the data ends after " + std::to_string(nodes_) +
                               " nodes (a truncated file)");
    }
    const char* here = bytes_.data() + at_;
    at_ += count;
    return here;
  }
  void requireChildDepth(unsigned depth) const {
    if (depth > kOcTreeDepth) {
      throw std::runtime_error("node " + std::to_string(nodes_) + " has children below depth " +
                               std::to_string(kOcTreeDepth));
    }
  }

  const std::string& bytes_;
  std::size_t at_;
  std::size_t nodes_ = 0;
};

void requireCompleteData(const OctomapHeader& header, const std::string& bytes) {
  if (header.declared_nodes == 0) return;  // liboctomap reads no data for an empty tree
  NodeDataCheck check(bytes, header.data_offset);
  const std::size_t found =
      header.binary ? 1 + check.countBinaryChildren(0) : check.countFullNodes(0);
  if (found != header.declared_nodes) {
    throw std::runtime_error("the header declares " + std::to_string(header.declared_nodes) +
                             " nodes, the data holds " + std::to_string(found));
  }
}

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
  return toOcTree(map.copyBlocks(), map.resolution(), map.model(), skipped_voxels);
}

std::unique_ptr<octomap::OcTree> toOcTree(const std::vector<VoxelMap::BlockCopy>& blocks,
                                          double resolution, const OccupancyModel& model,
                                          std::size_t* skipped_voxels) {
  auto tree = std::make_unique<octomap::OcTree>(resolution);
  applyModel(model, tree.get());
  std::size_t skipped = 0;
  for (const auto& [block_index, block] : blocks) {
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
      const float log_odds = block.log_odds[linear];
      if (!VoxelBlock::isKnown(log_odds)) continue;
      const VoxelIndex index = VoxelMap::voxelIndex(block_index, linear);
      if (!isOctomapRepresentable(index)) {
        ++skipped;
        continue;
      }
      // The key of the voxel's centre, computed exactly: floor(((i + 0.5) r) / r) + 32768.
      const octomap::OcTreeKey key(static_cast<octomap::key_type>(index.x() + kOctomapKeyOffset),
                                   static_cast<octomap::key_type>(index.y() + kOctomapKeyOffset),
                                   static_cast<octomap::key_type>(index.z() + kOctomapKeyOffset));
      tree->setNodeValue(key, log_odds, /*lazy_eval=*/true);
    }
  }
  tree->updateInnerOccupancy();
  tree->prune();
  if (skipped_voxels != nullptr) *skipped_voxels = skipped;
  return tree;
}

void fromOcTree(const octomap::OcTree& tree, VoxelMap* map, std::size_t max_voxels) {
  const double resolution = map->resolution();
  if (std::abs(tree.getResolution() - resolution) > 1e-9 * resolution) {
    throw std::invalid_argument(
        "fromOcTree: the tree's resolution (" + std::to_string(tree.getResolution()) +
        " m) differs from the map's (" + std::to_string(resolution) + " m)");
  }
  const int max_depth = static_cast<int>(tree.getTreeDepth());
  // A pruned leaf at depth d stands for 8^(16 - d) voxels: count before expanding, so that a
  // small file cannot ask for the whole key space (a root leaf is 2^48 voxels).
  double voxels = 0.0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    voxels += std::pow(8.0, max_depth - static_cast<int>(it.getDepth()));
  }
  if (voxels > static_cast<double>(max_voxels)) {
    throw std::invalid_argument("fromOcTree: the tree's leaves cover " + std::to_string(voxels) +
                                " voxels, more than the " + std::to_string(max_voxels) +
                                " allowed");
  }
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

std::unique_ptr<octomap::OcTree> parseOcTree(const std::string& bytes, const std::string& name,
                                             const OccupancyModel& model) {
  OctomapHeader header;
  try {
    header = parseOctomapHeader(bytes);
    requireCompleteData(header, bytes);
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(name + ": " + error.what());
  }
  auto tree = std::make_unique<octomap::OcTree>(header.resolution);
  // Binary leaves are read as the clamping bounds: set them before reading.
  applyModel(model, tree.get());
  if (header.declared_nodes > 0) {
    // The data was checked above: liboctomap reads exactly the nodes counted there.
    MemoryBuffer buffer(bytes.data() + header.data_offset, bytes.data() + bytes.size());
    std::istream data(&buffer);
    if (header.binary) {
      tree->readBinaryData(data);
    } else {
      tree->readData(data);
    }
  }
  if (tree->size() != header.declared_nodes) {  // a check of the check above
    throw std::runtime_error(name + ": liboctomap read " + std::to_string(tree->size()) +
                             " nodes, the header declares " +
                             std::to_string(header.declared_nodes));
  }
  return tree;
}

std::unique_ptr<octomap::OcTree> readOcTreeFile(const std::string& path,
                                                const OccupancyModel& model) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open octomap file " + path);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in) throw std::runtime_error("cannot read octomap file " + path);
  return parseOcTree(bytes.str(), path, model);
}

}  // namespace occupancy_fusion
