// Map file loading: .ot / .bt bytes -> octomap::OcTree (parseOcTree, the body of readOcTreeFile,
// src/map/octomap_conversion.cpp) -> VoxelMap (fromOcTree), as readOctomapFile and the map
// server's load_map do. Any input must be rejected with an exception or give a tree of exactly the
// declared node count whose voxels all land in the map.
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "fuzz_input.h"
#include "occupancy_fusion/map/octomap_conversion.h"

namespace occupancy_fusion {
namespace fuzz {
namespace {

// The harness's bound on the voxels a file may cover (the default allows 2^28: too slow here).
constexpr std::size_t kHarnessMaxVoxels = std::size_t{1} << 16;

}  // namespace

void writeSeeds() {
  VoxelMapConfig config;
  config.resolution = 0.1;
  VoxelMap map(config);
  for (int i = 0; i < 24; ++i) {
    map.updateVoxel(VoxelIndex(i % 5 - 2, i / 5 - 2, i % 3), i % 2 ? 1.2f : -0.8f);
  }
  // A whole 2 x 2 x 2 cube of equal values, which prune() merges into one leaf above voxel depth.
  for (int z = 4; z < 6; ++z) {
    for (int y = 4; y < 6; ++y) {
      for (int x = 4; x < 6; ++x) map.updateVoxel(VoxelIndex(x, y, z), 0.4f);
    }
  }
  const std::unique_ptr<octomap::OcTree> tree = toOcTree(map);
  for (bool binary : {false, true}) {
    std::ostringstream out;
    if (binary) {
      tree->writeBinaryConst(out);
    } else {
      tree->write(out);
    }
    const std::string bytes = out.str();
    writeSeed(binary ? "seed_map.bt" : "seed_map.ot",
              std::vector<std::uint8_t>(bytes.begin(), bytes.end()));
  }
}

}  // namespace fuzz
}  // namespace occupancy_fusion

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occupancy_fusion;
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  std::unique_ptr<octomap::OcTree> tree;
  try {
    tree = parseOcTree(bytes, "fuzz input");
  } catch (const std::runtime_error&) {
    return 0;
  }
  try {
    VoxelMapConfig config;
    config.resolution = tree->getResolution();
    VoxelMap map(config);
    fromOcTree(*tree, &map, fuzz::kHarnessMaxVoxels);
    if (map.knownVoxelCount() > fuzz::kHarnessMaxVoxels) std::abort();
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
