// Packed 64-bit keys for integer grid indices (3D blocks, 2D tiles and cells), and the hash
// tables keyed by them. Every sparse grid in the package uses this one encoding, so a key
// packed in one place unpacks correctly in another.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include <tsl/robin_map.h>
#include <tsl/robin_set.h>

namespace occupancy_fusion {

// 3D: 21 bits per axis (x lowest), each coordinate stored offset by 2^20, so packing and
// unpacking are exact for coordinates in [-2^20, 2^20 - 1]; kMaxKeyCoordinate3D is the
// symmetric bound |coordinate| <= 2^20 - 1. Outside that range keys alias.
constexpr int kKeyBitsPerAxis3D = 21;
constexpr int kMaxKeyCoordinate3D = (1 << (kKeyBitsPerAxis3D - 1)) - 1;

inline std::uint64_t packKey(const Eigen::Vector3i& index) {
  constexpr std::uint64_t kMask = (std::uint64_t{1} << kKeyBitsPerAxis3D) - 1;
  constexpr int kOffset = kMaxKeyCoordinate3D + 1;
  auto field = [](int v) { return static_cast<std::uint64_t>(v + kOffset) & kMask; };
  return field(index.x()) | (field(index.y()) << kKeyBitsPerAxis3D) |
         (field(index.z()) << (2 * kKeyBitsPerAxis3D));
}

// packKey of (floor(x[k]), floor(y[k]), floor(z[k])) for k < count, count even: the keys of
// many points given in voxels (point / resolution), two per SSE2 instruction on x86-64 (a
// scalar conversion of each coordinate to int takes three instructions in a chain). Exact where
// every coordinate is finite and within +-2^51; elsewhere a meaningless key without undefined
// behaviour (callers read only the keys of usable points).
inline void packFlooredKeys(const double* x, const double* y, const double* z, int count,
                            std::uint64_t* keys) {
  using DoublePair = double __attribute__((vector_size(2 * sizeof(double))));
  using KeyPair = std::uint64_t __attribute__((vector_size(2 * sizeof(std::uint64_t))));
  using MaskPair = std::int64_t __attribute__((vector_size(2 * sizeof(std::int64_t))));
  // v + 1.5 * 2^52 rounds v to its nearest integer (one unit of the sum's last place), and the
  // low bits of the sum's representation are that integer in two's complement: floor(v) is it,
  // one less where the rounding went up.
  constexpr double kRounding = 6755399441055744.0;
  constexpr std::uint64_t kMask = (std::uint64_t{1} << kKeyBitsPerAxis3D) - 1;
  constexpr std::uint64_t kOffset = kMaxKeyCoordinate3D + 1;  // as packKey
  const DoublePair rounding = {kRounding, kRounding};
  const double* const axes[3] = {x, y, z};
  for (int k = 0; k < count; k += 2) {
    KeyPair key = {0, 0};
    for (int axis = 0; axis < 3; ++axis) {
      DoublePair v;
      std::memcpy(&v, axes[axis] + k, sizeof(v));
      const DoublePair nearest = v + rounding;
      const MaskPair rounded_up = (nearest - rounding) > v;  // -1 in those lanes
      // Vector casts reinterpret the bits.
      const KeyPair field = ((KeyPair)nearest + (KeyPair)rounded_up + kOffset) & kMask;
      key |= field << (axis * kKeyBitsPerAxis3D);
    }
    std::memcpy(keys + k, &key, sizeof(key));
  }
}

inline Eigen::Vector3i unpackKey3(std::uint64_t key) {
  constexpr std::uint64_t kMask = (std::uint64_t{1} << kKeyBitsPerAxis3D) - 1;
  constexpr int kOffset = kMaxKeyCoordinate3D + 1;
  auto field = [](std::uint64_t bits) { return static_cast<int>(bits & kMask) - kOffset; };
  return {field(key), field(key >> kKeyBitsPerAxis3D), field(key >> (2 * kKeyBitsPerAxis3D))};
}

// 2D: 32 bits per axis in two's complement (x in the high half): exact for every int pair.
inline std::uint64_t packKey(const Eigen::Vector2i& index) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(index.x())) << 32) |
         static_cast<std::uint32_t>(index.y());
}

inline Eigen::Vector2i unpackKey2(std::uint64_t key) {
  return {static_cast<std::int32_t>(static_cast<std::uint32_t>(key >> 32)),
          static_cast<std::int32_t>(static_cast<std::uint32_t>(key))};
}

// splitmix64 finaliser. std::hash<std::uint64_t> is the identity, and packed keys of nearby
// indices differ mostly in their high fields (y, z; or the low half's sign bits) while the
// table masks the low bits: the mix spreads every field over the bits the table uses.
struct SpatialKeyHash {
  std::size_t operator()(std::uint64_t key) const {
    key ^= key >> 30;
    key *= 0xbf58476d1ce4e5b9ULL;
    key ^= key >> 27;
    key *= 0x94d049bb133111ebULL;
    key ^= key >> 31;
    return static_cast<std::size_t>(key);
  }
};

template <class V>
using SpatialKeyMap = tsl::robin_map<std::uint64_t, V, SpatialKeyHash>;
using SpatialKeySet = tsl::robin_set<std::uint64_t, SpatialKeyHash>;

}  // namespace occupancy_fusion
