// benchmark checkpoint: what a checkpoint of the map to its store costs (VoxelMap::checkpoint),
// against the size of the map and the number of blocks changed since the previous one: the time
// writers wait (the transaction) and the flush to disk after it, beside saving the whole map as
// a .ot file (what ~save_map pays each time).
//
// The map is synthetic: N fully observed 8^3 blocks; a change updates one voxel in each of C
// blocks. Every case starts from an empty store in --folder.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "occupancy_fusion/benchmarks/benchmark_harness.h"
#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

using bench::Clock;
using bench::median;
using bench::millisecondsSince;

std::vector<BlockIndex> blockGrid(int count) {
  std::vector<BlockIndex> blocks;
  for (int i = 0; i < count; ++i) blocks.push_back({i % 100, (i / 100) % 100, i / 10000});
  return blocks;
}

void touch(VoxelMap* map, const std::vector<BlockIndex>& blocks, int count, float delta) {
  const std::vector<BlockIndex> some(blocks.begin(), blocks.begin() + count);
  map->updateBlocks(some, [&](const BlockIndex&, VoxelBlock& block) {
    block.update(7, delta, map->minLogOdds(), map->maxLogOdds());
  });
}

void runCase(const std::string& folder, int blocks, const std::vector<double>& changes,
             int repetitions) {
  std::filesystem::remove_all(folder);
  VoxelMapConfig config;
  config.resolution = 0.05;
  config.spill_folder = folder + "/store";
  config.checkpoint_period = 1.0;  // called here by hand
  VoxelMap map(config);
  if (!map.spillStatus().checkpoints) throw UsageError(map.spillStatus().last_error);
  const std::vector<BlockIndex> grid = blockGrid(blocks);
  map.updateBlocks(grid, [&](const BlockIndex&, VoxelBlock& block) {
    for (int v = 0; v < VoxelBlock::kVolume; ++v) block.update(v, 0.3f, -2.0f, 3.5f);
  });
  const CheckpointResult first = map.checkpoint("first");
  const auto save_start = Clock::now();
  writeOt(map, folder + "/map.ot");
  const double save_ms = millisecondsSince(save_start);
  std::printf("checkpoint blocks=%d changed=all locked_ms=%.2f sync_ms=%.2f save_ot_ms=%.2f\n",
              blocks, 1e3 * first.locked_seconds, 1e3 * first.sync_seconds, save_ms);
  for (double changed : changes) {
    const int count = std::min(blocks, static_cast<int>(changed));
    std::vector<double> locked, synced;
    for (int r = 0; r < repetitions; ++r) {
      touch(&map, grid, count, r % 2 == 0 ? 0.1f : -0.1f);
      const CheckpointResult result = map.checkpoint("change");
      if (!result.written || result.blocks_written != static_cast<std::size_t>(count)) {
        throw std::runtime_error("checkpoint wrote " + std::to_string(result.blocks_written) +
                                 " blocks, expected " + std::to_string(count));
      }
      locked.push_back(1e3 * result.locked_seconds);
      synced.push_back(1e3 * result.sync_seconds);
    }
    std::printf("checkpoint blocks=%d changed=%d locked_ms=%.2f sync_ms=%.2f\n", blocks, count,
                median(locked), median(synced));
  }
  std::filesystem::remove_all(folder);
}

}  // namespace

int runCheckpoint(const CommandLine& args) {
  if (!args.has("folder"))
    throw UsageError("--folder is required (a scratch folder for the store)");
  const std::vector<double> sizes =
      bench::parseNumberList<double>("blocks", args.value("blocks", "2000,20000"), "numbers >= 1",
                                     [](double value) { return value >= 1.0; });
  const std::vector<double> changes =
      bench::parseNumberList<double>("changed", args.value("changed", "10,100,1000"),
                                     "numbers >= 1", [](double value) { return value >= 1.0; });
  const int repetitions = args.intValue("repetitions", 5);
  if (repetitions < 1) throw UsageError("--repetitions must be at least 1");
  std::printf("# checkpoint: fully observed 8^3 blocks at 0.05 m, dense; median of %d\n",
              repetitions);
  for (double blocks : sizes) {
    runCase(args.value("folder"), static_cast<int>(blocks), changes, repetitions);
  }
  return 0;
}

}  // namespace occupancy_fusion
