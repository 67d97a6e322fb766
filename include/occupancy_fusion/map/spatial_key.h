// Packed 64-bit keys for integer grid indices (3D blocks, 2D tiles and cells), and the hash
// tables keyed by them. Every sparse grid in the package uses this one encoding, so a key
// packed in one place unpacks correctly in another.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>

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
