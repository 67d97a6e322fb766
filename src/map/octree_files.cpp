#include "occupancy_fusion/map/octree_files.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <octomap/OcTree.h>

#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/map/octomap_conversion.h"
#include "occupancy_fusion/map/spatial_key.h"

namespace occupancy_fusion {
namespace {

constexpr int kBlockDepth = 13;  // an 8^3 block's node in the 16-level tree
constexpr int kBlockKeyOffset = kOctomapKeyOffset / VoxelBlock::kSide;
static_assert(VoxelBlock::kSide == 8, "a block is one node three levels above the voxels");

// The tree's thresholds as liboctomap holds them (floats), set from the model as toOcTree does.
struct TreeThresholds {
  float clamp_min = 0, clamp_max = 0, occupied = 0;
};
TreeThresholds thresholdsOf(double resolution, const OccupancyModel& model) {
  octomap::OcTree tree(resolution);
  applyModel(model, &tree);
  return {tree.getClampingThresMinLog(), tree.getClampingThresMaxLog(),
          tree.getOccupancyThresLog()};
}

// A child's two bits in a .bt node: unknown, free leaf, occupied leaf, inner node.
constexpr std::uint8_t kNone = 0, kFree = 1, kOccupied = 2, kInner = 3;

std::uint8_t likelihoodCode(float log_odds, const TreeThresholds& thresholds) {
  return log_odds >= thresholds.occupied ? kOccupied : kFree;  // OcTree::isNodeOccupied
}

bool inKeyRange(const BlockIndex& block) {
  return (block.array() >= -kBlockKeyOffset).all() && (block.array() < kBlockKeyOffset).all();
}

// The block's node's place in the tree's depth-first order: from the root down, the child index
// liboctomap computes at each depth (the key's bit for that depth: x bit 0, y bit 1, z bit 2).
std::uint64_t treeOrder(const BlockIndex& block) {
  const unsigned x = block.x() + kBlockKeyOffset, y = block.y() + kBlockKeyOffset,
                 z = block.z() + kBlockKeyOffset;
  std::uint64_t order = 0;
  for (int bit = kBlockDepth - 1; bit >= 0; --bit) {
    order = (order << 3) | ((x >> bit) & 1u) | (((y >> bit) & 1u) << 1) | (((z >> bit) & 1u) << 2);
  }
  return order;
}

// The child, at depth + 1, of the node at `depth` (< 13) that holds the block.
int childAt(std::uint64_t order, int depth) {
  return static_cast<int>((order >> (3 * (kBlockDepth - 1 - depth))) & 7u);
}

// ---- Below a block's node: its subtree, levels 0 (the block's node, depth 13) to 3 (voxels).
// Node k of a level has children 8k .. 8k + 7 on the next level, in liboctomap's child order.
constexpr int kLevelStart[5] = {0, 1, 9, 73, 585};
constexpr int kSubtreeNodes = kLevelStart[4];
constexpr int kInnerNodes = kLevelStart[3];  // the block's node and the two levels below it

// A voxel's slot on level 3: the child indices of depths 13, 14 and 15 (key bits 2, 1, 0).
int voxelSlot(int linear) {
  const Eigen::Vector3i local = VoxelBlock::localIndex(linear);
  int slot = 0;
  for (int bit = 2; bit >= 0; --bit) {
    slot = slot * 8 + (((local.x() >> bit) & 1) | (((local.y() >> bit) & 1) << 1) |
                       (((local.z() >> bit) & 1) << 2));
  }
  return slot;
}

const std::array<int, VoxelBlock::kVolume>& voxelSlots() {
  static const std::array<int, VoxelBlock::kVolume> slots = [] {
    std::array<int, VoxelBlock::kVolume> table{};
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) table[linear] = voxelSlot(linear);
    return table;
  }();
  return slots;
}

// The subtree as toOcTree's tree holds it after updateInnerOccupancy and prune: values clamped
// (setNodeValue), an inner node's value the maximum of its children's, and a node whose eight
// children are leaves of one value pruned to a leaf of that value.
struct ExactSubtree {
  std::array<float, kSubtreeNodes> value;
  std::array<bool, kSubtreeNodes> exists;
  std::array<bool, kSubtreeNodes> leaf;

  ExactSubtree(const VoxelBlock& block, const TreeThresholds& thresholds) {
    value.fill(0.0f);
    exists.fill(false);
    leaf.fill(false);
    const auto& slots = voxelSlots();
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
      const float log_odds = block.log_odds[linear];
      if (!VoxelBlock::isKnown(log_odds)) continue;
      const int node = kLevelStart[3] + slots[linear];
      value[node] = std::min(std::max(log_odds, thresholds.clamp_min), thresholds.clamp_max);
      exists[node] = leaf[node] = true;
    }
    for (int level = 2; level >= 0; --level) {
      for (int k = 0; k < kLevelStart[level + 1] - kLevelStart[level]; ++k) summarise(level, k);
    }
  }
  int child(int level, int k, int c) const { return kLevelStart[level + 1] + 8 * k + c; }
  std::uint8_t childMask(int level, int k) const {
    std::uint8_t mask = 0;
    for (int c = 0; c < 8; ++c) mask |= exists[child(level, k, c)] ? (1u << c) : 0u;
    return static_cast<std::uint8_t>(mask);
  }

 private:
  void summarise(int level, int k) {
    const int node = kLevelStart[level] + k;
    const int first = child(level, k, 0);
    bool all_equal_leaves = true;
    for (int c = 0; c < 8; ++c) {
      const int i = first + c;
      if (!exists[i]) {
        all_equal_leaves = false;
        continue;
      }
      value[node] = exists[node] ? std::max(value[node], value[i]) : value[i];
      exists[node] = true;
      all_equal_leaves &= leaf[i] && value[i] == value[first];
    }
    leaf[node] = all_equal_leaves;
  }
};

void appendRecord(float value, std::uint8_t children, std::string* out) {
  char bytes[sizeof(float) + 1];
  std::memcpy(bytes, &value, sizeof(float));  // as OcTreeDataNode::writeData: the float's bytes
  bytes[sizeof(float)] = static_cast<char>(children);
  out->append(bytes, sizeof(bytes));
}

// OcTreeBaseImpl::writeNodesRecurs: the node's value and child bits, then its children.
void appendExactNode(const ExactSubtree& tree, int level, int k, std::string* out) {
  const int node = kLevelStart[level] + k;
  const bool leaf = level == 3 || tree.leaf[node];  // voxels are leaves
  appendRecord(tree.value[node], leaf ? 0 : tree.childMask(level, k), out);
  if (leaf) return;
  for (int c = 0; c < 8; ++c) {
    if (tree.exists[tree.child(level, k, c)]) appendExactNode(tree, level + 1, 8 * k + c, out);
  }
}

constexpr std::size_t kRecordBytes = sizeof(float) + 1;

// What the .bt needs of a block, a fixed size in its scratch file: each voxel's maximum-
// likelihood code (2 bits, slot order) and which of the nodes above them are leaves already.
struct BlockLikelihood {
  std::array<std::uint8_t, kSubtreeNodes - kInnerNodes> codes{};  // one byte a voxel: simple
  std::array<std::uint8_t, kInnerNodes> exact_leaf{};

  BlockLikelihood() = default;
  BlockLikelihood(const ExactSubtree& tree, const TreeThresholds& thresholds) {
    for (int slot = 0; slot < kSubtreeNodes - kInnerNodes; ++slot) {
      const int node = kInnerNodes + slot;
      codes[slot] = tree.exists[node] ? likelihoodCode(tree.value[node], thresholds) : kNone;
    }
    for (int node = 0; node < kInnerNodes; ++node)
      exact_leaf[node] = tree.exists[node] && tree.leaf[node];
  }
};
constexpr std::size_t kLikelihoodBytes = sizeof(BlockLikelihood);
static_assert(kLikelihoodBytes == kSubtreeNodes, "no padding: written as it is");

// The subtree after AbstractOccupancyOcTree::writeBinary's toMaxLikelihood and prune, where that
// prune collapses nodes at depths deeper than `cutoff` only (see Counts below).
struct LikelihoodSubtree {
  std::array<std::uint8_t, kSubtreeNodes> code{};  // kNone: no node
  std::array<bool, kSubtreeNodes> leaf{};

  // new_prunes[level]: nodes that this prune collapses (not leaves already), with cutoff 0.
  LikelihoodSubtree(const BlockLikelihood& block, int cutoff,
                    std::array<std::uint64_t, 3>* new_prunes = nullptr) {
    for (int slot = 0; slot < kSubtreeNodes - kInnerNodes; ++slot) {
      code[kInnerNodes + slot] = block.codes[slot];
      leaf[kInnerNodes + slot] = true;
    }
    for (int level = 2; level >= 0; --level) {
      const bool prunes = kBlockDepth + level > cutoff;
      for (int k = 0; k < kLevelStart[level + 1] - kLevelStart[level]; ++k) {
        const int node = kLevelStart[level] + k;
        const int first = kLevelStart[level + 1] + 8 * k;
        bool collapsible = true;
        std::uint8_t highest = kNone;
        for (int i = first; i < first + 8; ++i) {
          highest = std::max(highest, code[i]);
          collapsible &= code[i] != kNone && leaf[i] && code[i] == code[first];
        }
        code[node] = highest;  // the maximum's likelihood: occupied if any child is
        const bool exact_leaf = block.exact_leaf[node] != 0;
        leaf[node] = exact_leaf || (prunes && collapsible);
        if (new_prunes != nullptr && highest != kNone && !exact_leaf && collapsible) {
          ++(*new_prunes)[level];
        }
      }
    }
  }
  std::size_t nodesBelow(int level, int k) const {
    if (leaf[kLevelStart[level] + k]) return 0;
    std::size_t count = 0;
    for (int c = 0; c < 8; ++c) {
      const int i = kLevelStart[level + 1] + 8 * k + c;
      if (code[i] != kNone) count += 1 + (level + 1 < 3 ? nodesBelow(level + 1, 8 * k + c) : 0);
    }
    return count;
  }
};

// OccupancyOcTreeBase::writeBinaryNode: two bytes of children's codes (children 0-3, then 4-7,
// two bits each from the lowest), then the inner children.
void appendChildCodes(const std::array<std::uint8_t, 8>& codes, std::string* out) {
  char bytes[2] = {0, 0};
  for (int c = 0; c < 8; ++c)
    bytes[c / 4] = static_cast<char>(bytes[c / 4] | codes[c] << (2 * (c % 4)));
  out->append(bytes, 2);
}

void appendLikelihoodNode(const LikelihoodSubtree& tree, int level, int k, std::string* out) {
  std::array<std::uint8_t, 8> codes{};
  const int first = kLevelStart[level + 1] + 8 * k;
  for (int c = 0; c < 8; ++c) {
    const int i = first + c;
    codes[c] = tree.code[i] == kNone ? kNone : (tree.leaf[i] ? tree.code[i] : kInner);
  }
  appendChildCodes(codes, out);
  for (int c = 0; c < 8; ++c) {
    if (codes[c] == kInner && level + 1 < 3) appendLikelihoodNode(tree, level + 1, 8 * k + c, out);
  }
}

// Prunes at depths deeper than the cutoff fall into four classes within a block (depths 13-15).
int cutoffClass(int cutoff) { return std::clamp(cutoff, kBlockDepth - 1, kBlockDepth + 2) - 12; }
int cutoffOfClass(int cutoff_class) { return cutoff_class + kBlockDepth - 1; }

// ---- Per block, in memory: what the levels above need.
struct BlockSummary {
  std::uint64_t order = 0;
  std::uint64_t exact_offset = 0;  // its bytes below its node in the .ot scratch file
  float value = 0;                 // its node's log-odds: the maximum of its voxels
  std::uint16_t exact_below = 0;   // .ot nodes below its node
  std::array<std::uint16_t, 4> likelihood_below{};  // .bt nodes below it, per cutoff class
  std::uint8_t child_mask = 0;
  bool exact_leaf = false;
  std::uint8_t likelihood_leaf = 0;  // bit c: a leaf of the .bt for cutoff class c
};

// A node above the blocks, from its blocks' summaries.
struct NodeSummary {
  float value = 0;
  bool exact_leaf = false;
  std::uint8_t child_mask = 0;
  std::uint8_t code = kNone;  // maximum likelihood
  bool likelihood_leaf = false;
  std::uint64_t exact_nodes = 0;       // the node and those below it, .ot
  std::uint64_t likelihood_nodes = 0;  // the same, .bt
};

using Range = std::pair<std::size_t, std::size_t>;

class UpperTree {
 public:
  UpperTree(const std::vector<BlockSummary>& blocks, const TreeThresholds& thresholds)
      : blocks_(blocks), thresholds_(thresholds) {}

  std::array<Range, 8> children(int depth, Range range) const {
    std::array<Range, 8> ranges;
    std::size_t at = range.first;
    for (int c = 0; c < 8; ++c) {
      const std::size_t begin = at;
      while (at < range.second && childAt(blocks_[at].order, depth) == c) ++at;
      ranges[c] = {begin, at};
    }
    return ranges;
  }

  // The node at `depth` over the blocks in `range` (not empty), the .bt pruned at depths deeper
  // than `cutoff`; new_prunes[depth]: nodes that prune collapses that are not leaves already.
  NodeSummary summarise(int depth, Range range, int cutoff,
                        std::array<std::uint64_t, 17>* new_prunes = nullptr) const {
    if (depth == kBlockDepth) return blockNode(blocks_[range.first], cutoff);
    NodeSummary node;
    bool first = true, exact_equal = true, likelihood_equal = true;
    float first_value = 0;
    std::uint8_t first_code = kNone;
    std::uint64_t exact_below = 0, likelihood_below = 0;
    const std::array<Range, 8> ranges = children(depth, range);
    for (int c = 0; c < 8; ++c) {
      if (ranges[c].first == ranges[c].second) continue;
      const NodeSummary child = summarise(depth + 1, ranges[c], cutoff, new_prunes);
      node.child_mask |= static_cast<std::uint8_t>(1u << c);
      node.value = first ? child.value : std::max(node.value, child.value);
      node.code = std::max(node.code, child.code);
      if (first) {
        first_value = child.value;
        first_code = child.code;
        first = false;
      }
      exact_equal &= child.exact_leaf && child.value == first_value;
      likelihood_equal &= child.likelihood_leaf && child.code == first_code;
      exact_below += child.exact_nodes;
      likelihood_below += child.likelihood_nodes;
    }
    // OcTreeBaseImpl::prune never collapses the root (depth 0).
    const bool all_children = node.child_mask == 0xff && depth > 0;
    node.exact_leaf = all_children && exact_equal;
    const bool collapsible = all_children && likelihood_equal;
    node.likelihood_leaf = node.exact_leaf || (depth > cutoff && collapsible);
    if (new_prunes != nullptr && !node.exact_leaf && collapsible) ++(*new_prunes)[depth];
    node.exact_nodes = 1 + (node.exact_leaf ? 0 : exact_below);
    node.likelihood_nodes = 1 + (node.likelihood_leaf ? 0 : likelihood_below);
    return node;
  }

 private:
  NodeSummary blockNode(const BlockSummary& block, int cutoff) const {
    const int c = cutoffClass(cutoff);
    NodeSummary node;
    node.value = block.value;
    node.exact_leaf = block.exact_leaf;
    node.child_mask = block.child_mask;
    node.code = likelihoodCode(block.value, thresholds_);
    node.likelihood_leaf = (block.likelihood_leaf >> c) & 1u;
    node.exact_nodes = 1 + block.exact_below;
    node.likelihood_nodes = 1 + block.likelihood_below[c];
    return node;
  }

  const std::vector<BlockSummary>& blocks_;
  TreeThresholds thresholds_;
};

// A scratch file beside an output, removed with this object.
class ScratchFile {
 public:
  explicit ScratchFile(const std::string& beside) {
    static std::atomic<unsigned> counter{0};
    path_ = beside + ".scratch" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
    out_.open(path_, std::ios::binary | std::ios::trunc);
    if (!out_) fail("cannot create");
  }
  ~ScratchFile() { std::remove(path_.c_str()); }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  void append(const char* bytes, std::size_t size) {
    out_.write(bytes, static_cast<std::streamsize>(size));
    if (!out_) fail("cannot write");
    written_ += size;
  }
  std::uint64_t written() const { return written_; }
  // Done writing: reads may begin.
  void finish() {
    out_.close();
    if (out_.fail()) fail("cannot write");
    in_.open(path_, std::ios::binary);
    if (!in_) fail("cannot read");
  }
  void read(std::uint64_t offset, std::size_t size, std::string* out) {
    out->resize(size);
    in_.seekg(static_cast<std::streamoff>(offset));
    in_.read(out->data(), static_cast<std::streamsize>(size));
    if (!in_) fail("cannot read");
  }

 private:
  [[noreturn]] void fail(const char* what) const {
    throw std::runtime_error(std::string(what) + " scratch file " + path_ + ": " +
                             std::strerror(errno));
  }
  std::string path_;
  std::ofstream out_;
  std::ifstream in_;
  std::uint64_t written_ = 0;
};

std::string treeHeader(bool binary, std::size_t nodes, double resolution) {
  // AbstractOcTree::write and AbstractOccupancyOcTree::writeBinaryConst.
  std::ostringstream header;
  header << (binary ? "# Octomap OcTree binary file" : "# Octomap OcTree file")
         << "\n# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
         << "id OcTree\n"
         << "size " << nodes << "\n"
         << "res " << resolution << "\n"
         << "data\n";
  return header.str();
}

// Pass 1: every block read once, in tree order.
struct BlockPass {
  std::vector<BlockSummary> blocks;
  std::array<std::uint64_t, 17> new_prunes{};  // per depth, the .bt's prune without a cutoff
  std::size_t skipped_voxels = 0;
};

BlockPass readBlocks(const OctreeBlockSource& source, const TreeThresholds& thresholds,
                     ScratchFile* exact, ScratchFile* likelihood) {
  BlockPass pass;
  std::vector<std::pair<std::uint64_t, BlockIndex>> order;
  order.reserve(source.blocks.size());
  VoxelBlock block;
  for (const BlockIndex& index : source.blocks) {
    if (inKeyRange(index)) {
      order.emplace_back(treeOrder(index), index);
    } else if (source.read(index, &block)) {
      for (const float log_odds : block.log_odds)
        pass.skipped_voxels += VoxelBlock::isKnown(log_odds);
    }
  }
  std::sort(order.begin(), order.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  pass.blocks.reserve(order.size());
  std::string bytes;
  for (const auto& [tree_order, index] : order) {
    if (!source.read(index, &block)) continue;
    const ExactSubtree tree(block, thresholds);
    if (!tree.exists[0]) continue;  // no known voxel: no node
    BlockSummary summary;
    summary.order = tree_order;
    summary.value = tree.value[0];
    summary.exact_leaf = tree.leaf[0];
    summary.child_mask = tree.childMask(0, 0);
    bytes.clear();
    if (!tree.leaf[0]) {
      for (int c = 0; c < 8; ++c) {
        if (tree.exists[tree.child(0, 0, c)]) appendExactNode(tree, 1, c, &bytes);
      }
    }
    summary.exact_below = static_cast<std::uint16_t>(bytes.size() / kRecordBytes);
    if (exact != nullptr) {
      summary.exact_offset = exact->written();
      exact->append(bytes.data(), bytes.size());
    }
    const BlockLikelihood codes(tree, thresholds);
    for (int c = 0; c < 4; ++c) {
      std::array<std::uint64_t, 3> new_prunes{};
      const LikelihoodSubtree pruned(codes, cutoffOfClass(c), c == 0 ? &new_prunes : nullptr);
      summary.likelihood_leaf |= static_cast<std::uint8_t>(pruned.leaf[0] ? 1u << c : 0u);
      summary.likelihood_below[c] = static_cast<std::uint16_t>(pruned.nodesBelow(0, 0));
      for (int level = 0; level < 3; ++level)
        pass.new_prunes[kBlockDepth + level] += new_prunes[level];
    }
    if (likelihood != nullptr) {
      likelihood->append(reinterpret_cast<const char*>(&codes), kLikelihoodBytes);
    }
    pass.blocks.push_back(summary);
  }
  return pass;
}

// AbstractOccupancyOcTree::writeBinary prunes from depth 15 upwards and stops at the first depth
// where nothing collapses: the .bt collapses nodes deeper than that depth only.
int likelihoodCutoff(const UpperTree& upper, BlockPass* pass) {
  if (pass->blocks.empty()) return 0;
  upper.summarise(0, {0, pass->blocks.size()}, 0, &pass->new_prunes);
  for (int depth = 15; depth > 0; --depth) {
    if (pass->new_prunes[depth] == 0) return depth;
  }
  return 0;
}

class ExactWriter {
 public:
  ExactWriter(const UpperTree& upper, const std::vector<BlockSummary>& blocks, ScratchFile* scratch,
              std::ostream* out)
      : upper_(upper), blocks_(blocks), scratch_(scratch), out_(out) {}

  void node(int depth, Range range, const NodeSummary& self) {
    std::string bytes;
    appendRecord(self.value, self.exact_leaf ? 0 : self.child_mask, &bytes);
    if (depth == kBlockDepth) {
      const BlockSummary& block = blocks_[range.first];
      out_->write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      scratch_->read(block.exact_offset, block.exact_below * kRecordBytes, &bytes);
      out_->write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      return;
    }
    out_->write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (self.exact_leaf) return;
    const std::array<Range, 8> ranges = upper_.children(depth, range);
    for (int c = 0; c < 8; ++c) {
      if (ranges[c].first == ranges[c].second) continue;
      node(depth + 1, ranges[c], upper_.summarise(depth + 1, ranges[c], 0));
    }
  }

 private:
  const UpperTree& upper_;
  const std::vector<BlockSummary>& blocks_;
  ScratchFile* scratch_;
  std::ostream* out_;
};

class LikelihoodWriter {
 public:
  LikelihoodWriter(const UpperTree& upper, int cutoff, ScratchFile* scratch, std::ostream* out)
      : upper_(upper), cutoff_(cutoff), scratch_(scratch), out_(out) {}

  // An inner node (not a leaf of the .bt).
  void node(int depth, Range range) {
    std::string bytes;
    if (depth == kBlockDepth) {
      scratch_->read(range.first * kLikelihoodBytes, kLikelihoodBytes, &bytes);
      BlockLikelihood codes;
      std::memcpy(&codes, bytes.data(), kLikelihoodBytes);
      bytes.clear();
      appendLikelihoodNode(LikelihoodSubtree(codes, cutoff_), 0, 0, &bytes);
      out_->write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      return;
    }
    const std::array<Range, 8> ranges = upper_.children(depth, range);
    std::array<std::uint8_t, 8> codes{};
    for (int c = 0; c < 8; ++c) {
      if (ranges[c].first == ranges[c].second) continue;
      const NodeSummary child = upper_.summarise(depth + 1, ranges[c], cutoff_);
      codes[c] = child.likelihood_leaf ? child.code : kInner;
    }
    appendChildCodes(codes, &bytes);
    out_->write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    for (int c = 0; c < 8; ++c) {
      if (codes[c] == kInner) node(depth + 1, ranges[c]);
    }
  }

 private:
  const UpperTree& upper_;
  int cutoff_;
  ScratchFile* scratch_;
  std::ostream* out_;
};

}  // namespace

OctreeBlockSource blockSourceOf(const VoxelMap& map) {
  return {map.blockIndices(),
          [&map](const BlockIndex& index, VoxelBlock* out) { return map.copyBlock(index, out); }};
}

OctreeBlockSource blockSourceOf(const std::vector<VoxelMap::BlockCopy>& blocks) {
  auto positions = std::make_shared<SpatialKeyMap<std::size_t>>();
  OctreeBlockSource source;
  source.blocks.reserve(blocks.size());
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    source.blocks.push_back(blocks[i].first);
    positions->emplace(packKey(blocks[i].first), i);
  }
  source.read = [&blocks, positions](const BlockIndex& index, VoxelBlock* out) {
    const auto found = positions->find(packKey(index));
    if (found == positions->end()) return false;
    *out = blocks[found->second].second;
    return true;
  };
  return source;
}

OctreeFilesWritten writeOctreeFiles(const OctreeBlockSource& source, double resolution,
                                    const OccupancyModel& model, const OctreeFilePaths& paths) {
  const TreeThresholds thresholds = thresholdsOf(resolution, model);
  std::unique_ptr<ScratchFile> exact_scratch, likelihood_scratch;
  if (!paths.ot.empty()) exact_scratch = std::make_unique<ScratchFile>(paths.ot);
  if (!paths.bt.empty()) likelihood_scratch = std::make_unique<ScratchFile>(paths.bt);
  BlockPass pass = readBlocks(source, thresholds, exact_scratch.get(), likelihood_scratch.get());
  const UpperTree upper(pass.blocks, thresholds);
  const Range all{0, pass.blocks.size()};
  const int cutoff = likelihoodCutoff(upper, &pass);
  OctreeFilesWritten written;
  written.skipped_voxels = pass.skipped_voxels;
  if (!pass.blocks.empty()) {
    const NodeSummary root = upper.summarise(0, all, cutoff);
    written.ot_nodes = root.exact_nodes;
    written.bt_nodes = root.likelihood_nodes;
  }
  if (exact_scratch) {
    exact_scratch->finish();
    writeFileAtomically(paths.ot, [&](std::ostream& out) {
      out << treeHeader(false, written.ot_nodes, resolution);
      if (pass.blocks.empty()) return;
      ExactWriter(upper, pass.blocks, exact_scratch.get(), &out)
          .node(0, all, upper.summarise(0, all, 0));
    });
  }
  if (likelihood_scratch) {
    likelihood_scratch->finish();
    writeFileAtomically(paths.bt, [&](std::ostream& out) {
      out << treeHeader(true, written.bt_nodes, resolution);
      if (pass.blocks.empty()) return;
      LikelihoodWriter(upper, cutoff, likelihood_scratch.get(), &out).node(0, all);
    });
  }
  return written;
}

}  // namespace occupancy_fusion
