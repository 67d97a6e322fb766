// A mapping process for the checkpoint test (test/unit/map/test_voxel_map_checkpoint.cpp), which
// kills it with SIGKILL: random writes around a wandering focus into a map with a memory bound,
// a spill store and checkpoints, resumed from the store in `folder`. Before each checkpoint it
// prints "begin N DIGEST" (the map's digest, which the checkpoint holds if it commits), after it
// "done N"; at start "resumed BLOCKS DIGEST". Usage: checkpoint_writer FOLDER SEED
// FRAMES_PER_CHECKPOINT
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "../common/map_digest.h"
#include "occupancy_fusion/map/voxel_map.h"

int main(int argc, char** argv) {
  using namespace occupancy_fusion;
  if (argc != 4) {
    std::fprintf(stderr, "usage: checkpoint_writer FOLDER SEED FRAMES_PER_CHECKPOINT\n");
    return 2;
  }
  VoxelMapConfig config;
  config.resolution = 0.1;
  config.max_memory_bytes = 40 * sizeof(VoxelBlock);
  config.spill_folder = argv[1];
  config.checkpoint_period = 1.0;  // called by hand here
  VoxelMap map(config);
  const SpillStatus status = map.spillStatus();
  if (!status.checkpoints) {
    std::fprintf(stderr, "no checkpoints: %s\n", status.last_error.c_str());
    return 1;
  }
  std::printf("resumed %zu %s\n", status.resumed_blocks, digestOf(map).text().c_str());
  std::fflush(stdout);

  std::mt19937 rng(static_cast<unsigned>(std::strtoul(argv[2], nullptr, 10)));
  const int every = std::atoi(argv[3]);
  constexpr int kRegionBlocks = 24;
  std::uniform_int_distribution<int> step(-2, 2), offset(-8, 15), z(0, 15);
  std::uniform_real_distribution<float> delta(-1.2f, 1.6f);
  BlockIndex focus(kRegionBlocks / 2, kRegionBlocks / 2, 0);
  const double edge = map.resolution() * VoxelBlock::kSide;
  // A bounded run in case nobody kills it.
  for (int frame = 0, checkpoint = 0; checkpoint < 2000; ++frame) {
    focus.x() = std::clamp(focus.x() + step(rng), 1, kRegionBlocks - 2);
    focus.y() = std::clamp(focus.y() + step(rng), 1, kRegionBlocks - 2);
    map.setFocus((focus.cast<double>().array() + 0.5) * edge);
    const VoxelIndex base = focus * VoxelBlock::kSide;
    std::vector<VoxelUpdate> updates;
    for (int i = 0; i < 300; ++i) {
      updates.push_back({base + VoxelIndex(offset(rng), offset(rng), z(rng)), delta(rng)});
    }
    map.applyUpdates(updates);
    if (frame % every != every - 1) continue;
    ++checkpoint;
    std::printf("begin %d %s\n", checkpoint, digestOf(map).text().c_str());
    std::fflush(stdout);
    if (!map.checkpoint("checkpoint " + std::to_string(checkpoint)).written) {
      std::fprintf(stderr, "checkpoint failed: %s\n", map.spillStatus().last_error.c_str());
      return 1;
    }
    std::printf("done %d\n", checkpoint);
    std::fflush(stdout);
  }
  return 0;
}
