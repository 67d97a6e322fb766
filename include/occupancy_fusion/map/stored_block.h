// How VoxelMap stores one block: dense (a VoxelBlock, 2 KB) or sparse (only the 2^3-voxel
// bricks of the block that hold a known voxel). Readers and writers outside the map always see a
// dense VoxelBlock; this is the map's private storage, in a header of its own so that its
// layout can be tested directly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <new>
#include <utility>
#include <vector>

#include "occupancy_fusion/map/voxel_block.h"

namespace occupancy_fusion {

// A block's 8^3 voxels as 4^3 bricks of 2^3 voxels. A thin surface crosses few bricks of the
// blocks it passes through, so keeping only those bricks stores it at a fraction of a dense block.
struct BrickLayout {
  static constexpr int kBrickSide = 2;
  static constexpr int kBrickVolume = kBrickSide * kBrickSide * kBrickSide;             // 8 voxels
  static constexpr int kBricksPerSide = VoxelBlock::kSide / kBrickSide;                 // 4
  static constexpr int kBrickCount = kBricksPerSide * kBricksPerSide * kBricksPerSide;  // 64
  static_assert(VoxelBlock::kSideLog2 == 3 && kBrickCount == 64,
                "the brick mask is one 64-bit word: 8^3 blocks of 2^3 bricks");

  // VoxelBlock::linearIndex is x + 8 (y + 8 z): bits 0-2 are x, 3-5 y, 6-8 z. A brick takes the
  // high two bits of each axis, the voxel within it the low one.
  static int brickOf(int linear) {
    return ((linear >> 1) & 3) | (((linear >> 4) & 3) << 2) | (((linear >> 7) & 3) << 4);
  }
  static int offsetInBrick(int linear) {
    return (linear & 1) | ((linear >> 2) & 2) | ((linear >> 4) & 4);
  }
  // The linear index of a brick's first voxel (its x pair is contiguous in a VoxelBlock).
  static int firstVoxelOf(int brick) {
    const int x = (brick & 3) * 2;
    const int y = ((brick >> 2) & 3) * 2;
    const int z = (brick >> 4) * 2;
    return VoxelBlock::linearIndex(x, y, z);
  }
  // Of a brick's first voxel, the offsets (in a VoxelBlock's log_odds) of its four x pairs, in
  // the order of offsetInBrick: (y, z) = (0, 0), (1, 0), (0, 1), (1, 1).
  static constexpr int kPairOffsets[4] = {0, VoxelBlock::kSide,
                                          VoxelBlock::kSide* VoxelBlock::kSide,
                                          VoxelBlock::kSide* VoxelBlock::kSide + VoxelBlock::kSide};

  // Bit b set: brick b holds at least one known voxel. (In stored_block.cpp: the one loop over
  // a whole block that hybrid storage adds to a write.)
  static std::uint64_t knownBricks(const VoxelBlock& block);
  static int countBits(std::uint64_t mask) { return __builtin_popcountll(mask); }

  // The bricks of `mask`, in increasing brick order and each in offsetInBrick order, between a
  // block and a packed array of countBits(mask) * kBrickVolume floats: the layout of a
  // SparseBlock's bricks and of a block in the spill store (BrickEncoding).
  static void packBricks(const VoxelBlock& block, std::uint64_t mask, float* bricks) {
    for (std::uint64_t left = mask; left != 0; left &= left - 1) {
      const float* first = &block.log_odds[firstVoxelOf(__builtin_ctzll(left))];
      for (int pair = 0; pair < 4; ++pair, bricks += 2) {
        std::memcpy(bricks, first + kPairOffsets[pair], 2 * sizeof(float));
      }
    }
  }
  // Writes the bricks into `block`; its other voxels are left as they are.
  static void expandBricks(std::uint64_t mask, const float* bricks, VoxelBlock* block) {
    for (std::uint64_t left = mask; left != 0; left &= left - 1) {
      float* first = &block->log_odds[firstVoxelOf(__builtin_ctzll(left))];
      for (int pair = 0; pair < 4; ++pair, bricks += 2) {
        std::memcpy(first + kPairOffsets[pair], bricks, 2 * sizeof(float));
      }
    }
  }
};

// A block as bytes, for the spill store (block_store.h): the sparse form without its header, i.e.
// the 64-bit brick mask (host byte order) followed by the non-empty bricks as packBricks lays
// them out. A block with every brick non-empty takes 8 + 2048 bytes, a thin surface far less.
struct BrickEncoding {
  static std::size_t sizeFor(std::uint64_t mask) {
    return sizeof(mask) + static_cast<std::size_t>(BrickLayout::countBits(mask)) *
                              BrickLayout::kBrickVolume * sizeof(float);
  }
  // Replaces `out` with the encoding of `block`.
  static void encode(const VoxelBlock& block, std::vector<unsigned char>* out);
  // The block of an encoding, its known_count recounted and version 0. False, leaving `out`
  // unspecified, when the bytes are no encoding (a length that does not match the mask).
  static bool decode(const void* bytes, std::size_t size, VoxelBlock* out);
};

// The sparse form: a header followed, in the same allocation, by `capacity` bricks of 8 floats.
// The bricks of `mask` are stored in increasing brick order, each in offsetInBrick order.
struct SparseBlock {
  std::uint64_t mask = 0;
  std::uint64_t version = 0;
  int known_count = 0;
  int capacity = 0;  // bricks allocated

  float* bricks() { return reinterpret_cast<float*>(this + 1); }
  const float* bricks() const { return reinterpret_cast<const float*>(this + 1); }
  static std::size_t bytesFor(int capacity) {
    return sizeof(SparseBlock) +
           static_cast<std::size_t>(capacity) * BrickLayout::kBrickVolume * sizeof(float);
  }
  static SparseBlock* allocate(int capacity) {
    SparseBlock* block = new (::operator new(bytesFor(capacity))) SparseBlock;
    block->capacity = capacity;
    return block;
  }
  static void release(SparseBlock* block) {
    block->~SparseBlock();
    ::operator delete(block);
  }
};
static_assert(sizeof(SparseBlock) % alignof(float) == 0, "bricks follow the header");

// One owning handle, the size of a pointer (the map's hash table stores it): either a
// VoxelBlock* or, tagged in the lowest bit, a SparseBlock*. Move-only.
class StoredBlock {
 public:
  StoredBlock() = default;
  static StoredBlock newDense() { return StoredBlock(new VoxelBlock, false); }
  StoredBlock(StoredBlock&& other) noexcept : bits_(std::exchange(other.bits_, 0)) {}
  StoredBlock& operator=(StoredBlock&& other) noexcept {
    if (this != &other) {
      release();
      bits_ = std::exchange(other.bits_, 0);
    }
    return *this;
  }
  StoredBlock(const StoredBlock&) = delete;
  StoredBlock& operator=(const StoredBlock&) = delete;
  ~StoredBlock() { release(); }

  bool isDense() const { return (bits_ & kSparseTag) == 0; }
  VoxelBlock* dense() const { return reinterpret_cast<VoxelBlock*>(bits_); }
  SparseBlock* sparse() const { return reinterpret_cast<SparseBlock*>(bits_ & ~kSparseTag); }

  int knownCount() const { return isDense() ? dense()->known_count : sparse()->known_count; }
  std::uint64_t version() const { return isDense() ? dense()->version : sparse()->version; }
  void setVersion(std::uint64_t version) {
    if (isDense()) {
      dense()->version = version;
    } else {
      sparse()->version = version;
    }
  }
  // Heap bytes this block holds (a sparse block's allocated bricks, not only its used ones).
  std::size_t bytes() const {
    return isDense() ? sizeof(VoxelBlock) : SparseBlock::bytesFor(sparse()->capacity);
  }
  int brickCount() const {
    return isDense() ? BrickLayout::kBrickCount : BrickLayout::countBits(sparse()->mask);
  }

  // One voxel's log-odds, NaN where unknown.
  float at(int linear) const {
    if (isDense()) return dense()->log_odds[linear];
    const SparseBlock& block = *sparse();
    const int brick = BrickLayout::brickOf(linear);
    if (((block.mask >> brick) & 1) == 0) return VoxelBlock::kUnknown;
    const int rank = BrickLayout::countBits(block.mask & ((std::uint64_t{1} << brick) - 1));
    return block.bricks()[rank * BrickLayout::kBrickVolume + BrickLayout::offsetInBrick(linear)];
  }

  // The whole block, dense: this block itself, or `scratch` filled from its bricks.
  const VoxelBlock& view(VoxelBlock* scratch) const {
    if (isDense()) return *dense();
    expandInto(scratch);
    return *scratch;
  }
  void copyTo(VoxelBlock* out) const {
    if (isDense()) {
      *out = *dense();
    } else {
      expandInto(out);
    }
  }

  // Stored dense from now on (for writes through a VoxelBlock&).
  VoxelBlock& makeDense() {
    if (isDense()) return *dense();
    auto* block = new VoxelBlock;
    expandInto(block);
    reset(block, false);
    return *block;
  }

  // After a write of this (dense) block: stored sparse if it has at most max_sparse_bricks
  // non-empty bricks. Returns the change of bytes().
  std::ptrdiff_t settle(int max_sparse_bricks) {
    // More known voxels than fit in max_sparse_bricks bricks: no need to look at them.
    if (!isDense() || dense()->known_count > max_sparse_bricks * BrickLayout::kBrickVolume) {
      return 0;
    }
    const std::uint64_t mask = BrickLayout::knownBricks(*dense());
    if (BrickLayout::countBits(mask) > max_sparse_bricks) return 0;
    const std::size_t before = bytes();
    SparseBlock* packed = pack(*dense(), mask, nullptr);
    reset(packed, true);
    return static_cast<std::ptrdiff_t>(bytes()) - static_cast<std::ptrdiff_t>(before);
  }

  // After `written` (this block's contents, written in a scratch VoxelBlock) replaces this
  // block: stored sparse if it has at most max_sparse_bricks non-empty bricks, else dense.
  // Returns the change of bytes().
  std::ptrdiff_t storeFrom(const VoxelBlock& written, int max_sparse_bricks) {
    const std::size_t before = bytes();
    const std::uint64_t mask = written.known_count > max_sparse_bricks * BrickLayout::kBrickVolume
                                   ? ~std::uint64_t{0}
                                   : BrickLayout::knownBricks(written);
    if (BrickLayout::countBits(mask) > max_sparse_bricks) {
      reset(new VoxelBlock(written), false);
    } else {
      // The bricks of a block only come and go together with its known voxels, which a map
      // mostly gains: repack in place while the allocation is large enough.
      SparseBlock* reuse = isDense() ? nullptr : sparse();
      SparseBlock* packed = pack(written, mask, reuse);
      if (packed != reuse) reset(packed, true);
    }
    return static_cast<std::ptrdiff_t>(bytes()) - static_cast<std::ptrdiff_t>(before);
  }

 private:
  static constexpr std::uintptr_t kSparseTag = 1;
  static_assert(alignof(SparseBlock) > 1 && alignof(VoxelBlock) > 1, "the tag is the low bit");

  StoredBlock(void* block, bool sparse)
      : bits_(reinterpret_cast<std::uintptr_t>(block) | (sparse ? kSparseTag : 0)) {}
  void reset(void* block, bool sparse) {
    release();
    bits_ = reinterpret_cast<std::uintptr_t>(block) | (sparse ? kSparseTag : 0);
  }
  void release() {
    if (bits_ == 0) return;
    if (isDense()) {
      delete dense();
    } else {
      SparseBlock::release(sparse());
    }
    bits_ = 0;
  }

  // Packs the bricks of `mask` from `block` into `reuse` when it has room, else into a new
  // allocation of exactly the bricks needed.
  static SparseBlock* pack(const VoxelBlock& block, std::uint64_t mask, SparseBlock* reuse) {
    const int count = BrickLayout::countBits(mask);
    SparseBlock* out =
        reuse != nullptr && reuse->capacity >= count ? reuse : SparseBlock::allocate(count);
    out->mask = mask;
    out->version = block.version;
    out->known_count = block.known_count;
    BrickLayout::packBricks(block, mask, out->bricks());
    return out;
  }

  void expandInto(VoxelBlock* out) const {
    const SparseBlock& block = *sparse();
    out->log_odds.fill(VoxelBlock::kUnknown);
    out->known_count = block.known_count;
    out->version = block.version;
    BrickLayout::expandBricks(block.mask, block.bricks(), out);
  }

  std::uintptr_t bits_ = 0;
};

}  // namespace occupancy_fusion
