// A digest of a map's known voxels that does not depend on the order a map visits them in (blocks
// in memory first, then those in its store): the count and the wrapping sum of a mix of each
// voxel's index and log-odds bits. Equal contents give equal digests; a voxel changed, added or
// lost changes the sum but for a 2^-64 chance.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/sim/deterministic_random.h"

namespace occupancy_fusion {

struct MapDigest {
  std::uint64_t sum = 0;
  std::uint64_t voxels = 0;

  bool operator==(const MapDigest& other) const {
    return sum == other.sum && voxels == other.voxels;
  }
  bool operator!=(const MapDigest& other) const { return !(*this == other); }
  std::string text() const {
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "%016llx/%llu", static_cast<unsigned long long>(sum),
                  static_cast<unsigned long long>(voxels));
    return buffer;
  }
  static bool parse(const char* text, MapDigest* out) {
    unsigned long long sum = 0, voxels = 0;
    if (std::sscanf(text, "%16llx/%llu", &sum, &voxels) != 2) return false;
    out->sum = sum;
    out->voxels = voxels;
    return true;
  }
};

inline MapDigest digestOf(const VoxelMap& map) {
  MapDigest digest;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float value) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &value, sizeof(bits));
    const std::uint64_t position = (static_cast<std::uint64_t>(index.x() & 0xfffff) << 40) |
                                   (static_cast<std::uint64_t>(index.y() & 0xfffff) << 20) |
                                   static_cast<std::uint64_t>(index.z() & 0xfffff);
    digest.sum += sim::hashKey({position, bits});
    ++digest.voxels;
  });
  return digest;
}

}  // namespace occupancy_fusion
