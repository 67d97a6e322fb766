#include "occupancy_fusion/map/stored_block.h"

#include <array>
#include <cmath>
#include <cstring>

namespace occupancy_fusion {

namespace {

// Bit i set: voxel i of a row of VoxelBlock::kSide voxels is known. (A loop the compiler turns
// into a vector compare.)
unsigned knownInRow(const float* row) {
  unsigned bits = 0;
  for (int i = 0; i < VoxelBlock::kSide; ++i) {
    bits |= static_cast<unsigned>(!std::isnan(row[i])) << i;
  }
  return bits;
}

}  // namespace

std::uint64_t BrickLayout::knownBricks(const VoxelBlock& block) {
  constexpr int kRow = VoxelBlock::kSide;
  constexpr int kSlice = VoxelBlock::kSide * VoxelBlock::kSide;
  const float* voxels = block.log_odds.data();
  std::uint64_t mask = 0;
  for (int bz = 0; bz < kBricksPerSide; ++bz) {
    for (int by = 0; by < kBricksPerSide; ++by) {
      // The four rows of voxels (y, z pairs) that the row of bricks (by, bz) spans.
      const float* first = voxels + 2 * bz * kSlice + 2 * by * kRow;
      const unsigned rows = knownInRow(first) | knownInRow(first + kRow) |
                            knownInRow(first + kSlice) | knownInRow(first + kSlice + kRow);
      // Brick bx holds voxels 2 bx and 2 bx + 1 of each row.
      const unsigned pairs = (rows | (rows >> 1)) & 0x55u;
      const unsigned bricks =
          (pairs & 1u) | ((pairs >> 1) & 2u) | ((pairs >> 2) & 4u) | ((pairs >> 3) & 8u);
      mask |= static_cast<std::uint64_t>(bricks)
              << (by * kBricksPerSide + bz * kBricksPerSide * kBricksPerSide);
    }
  }
  return mask;
}

void BrickEncoding::encode(const VoxelBlock& block, std::vector<unsigned char>* out) {
  const std::uint64_t mask = BrickLayout::knownBricks(block);
  out->resize(sizeFor(mask));
  std::memcpy(out->data(), &mask, sizeof(mask));
  BrickLayout::packBricks(block, mask, reinterpret_cast<float*>(out->data() + sizeof(mask)));
}

bool BrickEncoding::decode(const void* bytes, std::size_t size, VoxelBlock* out) {
  std::uint64_t mask = 0;
  if (size < sizeof(mask)) return false;
  std::memcpy(&mask, bytes, sizeof(mask));
  if (size != sizeFor(mask)) return false;
  // The bytes may be unaligned for floats (they come from a store): copy them out first.
  const std::size_t floats = (size - sizeof(mask)) / sizeof(float);
  std::array<float, VoxelBlock::kVolume> bricks;
  std::memcpy(bricks.data(), static_cast<const unsigned char*>(bytes) + sizeof(mask),
              floats * sizeof(float));
  out->log_odds.fill(VoxelBlock::kUnknown);
  BrickLayout::expandBricks(mask, bricks.data(), out);
  out->known_count = 0;
  for (std::size_t i = 0; i < floats; ++i) out->known_count += VoxelBlock::isKnown(bricks[i]);
  out->version = 0;
  return true;
}

}  // namespace occupancy_fusion
