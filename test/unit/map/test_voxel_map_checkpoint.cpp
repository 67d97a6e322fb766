// VoxelMap checkpoints (VoxelMap, "Checkpoints"): a map constructed on the store resumes exactly
// the last checkpoint, whatever was written and spilled after it; a checkpoint writes the blocks
// changed since the previous one; a mapping process killed with SIGKILL at any moment resumes
// its last committed checkpoint.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "../../common/map_digest.h"
#include "../../common/test_folder.h"
#include "occupancy_fusion/map/map_checkpoints.h"
#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {
namespace {

using VoxelMapCheckpoint = TestFolder;
using Key = std::tuple<int, int, int>;

constexpr std::size_t kBoundBlocks = 40;

std::map<Key, float> knownVoxels(const VoxelMap& map) {
  std::map<Key, float> values;
  map.forEachKnownVoxel([&](const VoxelIndex& i, float v) { values[{i.x(), i.y(), i.z()}] = v; });
  return values;
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

VoxelMapConfig checkpointConfig(const std::string& folder, BlockStorage storage,
                                std::size_t bound_blocks) {
  VoxelMapConfig config;
  config.resolution = 0.1;
  config.block_storage = storage;
  config.max_memory_bytes = bound_blocks * sizeof(VoxelBlock);
  config.spill_folder = folder;
  config.checkpoint_period = 1.0;  // called by hand here
  return config;
}

// Random writes around a focus that wanders over 24 x 24 blocks: point updates, block callbacks
// and now and then a cleared box, the same in every map given.
class Writer {
 public:
  explicit Writer(unsigned seed) : rng_(seed) {}
  void frame(const std::vector<VoxelMap*>& maps) {
    std::uniform_int_distribution<int> step(-2, 2), offset(-8, 15), z(0, 15), kind(0, 19);
    std::uniform_real_distribution<float> delta(-1.2f, 1.6f);
    focus_.x() = std::clamp(focus_.x() + step(rng_), 1, 22);
    focus_.y() = std::clamp(focus_.y() + step(rng_), 1, 22);
    const double edge = 0.1 * VoxelBlock::kSide;
    const VoxelIndex base = focus_ * VoxelBlock::kSide;
    std::vector<VoxelUpdate> updates;
    for (int i = 0; i < 200; ++i) {
      updates.push_back({base + VoxelIndex(offset(rng_), offset(rng_), z(rng_)), delta(rng_)});
    }
    const int what = kind(rng_);
    const float plane_step = delta(rng_);
    for (VoxelMap* map : maps) {
      map->setFocus((focus_.cast<double>().array() + 0.5) * edge);
      map->applyUpdates(updates);
      if (what == 0) {
        const Eigen::Vector3d lo = (focus_.cast<double>().array() - 1.0) * edge;
        map->clearBox(lo, lo + Eigen::Vector3d(1.5 * edge, 0.7 * edge, 0.5 * edge));
      } else if (what < 4) {
        map->updateBlocks({focus_ + BlockIndex(0, 0, 2)}, [&](const BlockIndex&, VoxelBlock& b) {
          for (int x = 0; x < VoxelBlock::kSide; ++x)
            b.update(VoxelBlock::linearIndex(x, what, 1), plane_step, -2.0f, 3.5f);
        });
      }
    }
  }

 private:
  std::mt19937 rng_;
  BlockIndex focus_{12, 12, 0};
};

void resumesTheLastCheckpoint(BlockStorage storage, const std::string& folder) {
  const std::string store = folder + "/store";
  VoxelMapConfig unbounded_config;
  unbounded_config.resolution = 0.1;
  VoxelMap at_checkpoint(unbounded_config);  // the writes up to the last checkpoint
  {
    VoxelMap map(checkpointConfig(store, storage, kBoundBlocks));
    ASSERT_TRUE(map.spillStatus().checkpoints) << map.spillStatus().last_error;
    Writer writer(storage == BlockStorage::kDense ? 3 : 4);
    for (int frame = 0; frame < 300; ++frame) {
      writer.frame({&map, &at_checkpoint});
      if (frame == 149) {
        ASSERT_TRUE(map.checkpoint("first").written);
      }
    }
    const CheckpointResult last = map.checkpoint("second");
    ASSERT_TRUE(last.written);
    EXPECT_GT(last.blocks_written, 0u);
    // Written after the checkpoint, and mostly spilled (the map outgrows its bound many times).
    const std::size_t spilled_before = map.spillStatus().blocks_written;
    for (int frame = 0; frame < 100; ++frame) writer.frame({&map});
    EXPECT_GT(map.spillStatus().blocks_written, spilled_before + 50);
    EXPECT_GT(map.spillStatus().unsaved_blocks, 0u);
    EXPECT_NE(digestOf(map), digestOf(at_checkpoint));
  }
  VoxelMap resumed(checkpointConfig(store, storage, kBoundBlocks));
  const SpillStatus status = resumed.spillStatus();
  ASSERT_TRUE(status.checkpoints) << status.last_error;
  EXPECT_EQ(status.resumed_stamp, "second");
  EXPECT_EQ(status.resumed_blocks, at_checkpoint.blockCount());
  EXPECT_GT(status.spilled_blocks, at_checkpoint.blockCount() / 2);  // beyond the bound: stored
  EXPECT_EQ(resumed.blockCount(), at_checkpoint.blockCount());
  EXPECT_EQ(resumed.knownVoxelCount(), at_checkpoint.knownVoxelCount());
  const std::map<Key, float> expected = knownVoxels(at_checkpoint);
  ASSERT_GT(expected.size(), 10000u);
  EXPECT_TRUE(knownVoxels(resumed) == expected);
  writeOt(resumed, folder + "/resumed.ot");
  writeOt(at_checkpoint, folder + "/expected.ot");
  EXPECT_TRUE(readAll(folder + "/resumed.ot") == readAll(folder + "/expected.ot"));
}

TEST_F(VoxelMapCheckpoint, DenseMapResumesExactlyTheLastCheckpoint) {
  resumesTheLastCheckpoint(BlockStorage::kDense, folder_.string());
}

TEST_F(VoxelMapCheckpoint, HybridMapResumesExactlyTheLastCheckpoint) {
  resumesTheLastCheckpoint(BlockStorage::kHybrid, folder_.string());
}

// One voxel in each of `blocks` blocks along x from `first`.
void touchBlocks(VoxelMap* map, int first, int blocks, float delta) {
  std::vector<VoxelUpdate> updates;
  for (int b = first; b < first + blocks; ++b)
    updates.push_back({{b * VoxelBlock::kSide, 0, 0}, delta});
  map->applyUpdates(updates);
}

TEST_F(VoxelMapCheckpoint, WritesOnlyWhatChangedSinceThePreviousOne) {
  const std::string store = path("store");
  VoxelMapConfig config = checkpointConfig(store, BlockStorage::kDense, 0);  // no memory bound
  {
    VoxelMap map(config);
    ASSERT_TRUE(map.spillStatus().checkpoints) << map.spillStatus().last_error;
    touchBlocks(&map, 0, 50, 0.8f);
    EXPECT_EQ(map.checkpoint("a").blocks_written, 50u);
    touchBlocks(&map, 48, 3, -0.4f);  // two old blocks, one new
    EXPECT_EQ(map.spillStatus().unsaved_blocks, 3u);
    EXPECT_EQ(map.checkpoint("b").blocks_written, 3u);
    const CheckpointResult nothing = map.checkpoint("c");
    EXPECT_TRUE(nothing.written);
    EXPECT_EQ(nothing.blocks_written, 0u);
    EXPECT_EQ(map.spillStatus().checkpoints_written, 3u);
  }
  {
    VoxelMap resumed(config);
    EXPECT_EQ(resumed.spillStatus().resumed_stamp, "c");
    EXPECT_EQ(resumed.blockCount(), 51u);
    EXPECT_EQ(resumed.spillStatus().spilled_blocks, 0u);  // no bound: all in memory
    EXPECT_FLOAT_EQ(*resumed.logOdds({48 * VoxelBlock::kSide, 0, 0}), 0.4f);
    EXPECT_FLOAT_EQ(*resumed.logOdds({50 * VoxelBlock::kSide, 0, 0}), -0.4f);
    // A reset empties the store: nothing to resume.
    resumed.reset();
  }
  VoxelMap after_reset(config);
  EXPECT_EQ(after_reset.blockCount(), 0u);
  EXPECT_EQ(after_reset.spillStatus().resumed_blocks, 0u);
}

TEST_F(VoxelMapCheckpoint, BlocksEvictedUnchangedAreNotWrittenAgain) {
  VoxelMap map(checkpointConfig(path("store"), BlockStorage::kDense, kBoundBlocks));
  touchBlocks(&map, 0, 30, 0.8f);
  EXPECT_EQ(map.checkpoint("a").blocks_written, 30u);
  // 30 blocks far away: the first 30, unchanged since the checkpoint, leave memory unwritten.
  map.setFocus({1000 * 0.8, 0.0, 0.0});
  touchBlocks(&map, 1000, 30, 0.8f);
  const SpillStatus status = map.spillStatus();
  EXPECT_GE(status.spilled_blocks, 20u);
  EXPECT_EQ(status.blocks_written, 0u);
  for (int b = 0; b < 30; ++b) EXPECT_FLOAT_EQ(*map.logOdds({b * VoxelBlock::kSide, 0, 0}), 0.8f);
  EXPECT_EQ(map.checkpoint("b").blocks_written, 30u);
}

// The laser layer's tiles go into the same checkpoint: a layer beside a resumed map gets the
// checkpoint's cells back, and a checkpoint writes only the tiles changed since the previous one.
TEST_F(VoxelMapCheckpoint, LaserLayerResumesWithTheMap) {
  const std::string store = path("store");
  VoxelMapConfig config = checkpointConfig(store, BlockStorage::kDense, 0);
  GridLayer2DConfig layer_config;
  layer_config.resolution = config.resolution;
  // 300 cells from x = first, 7 apart; returns how many tiles they touch.
  auto scan = [](GridLayer2D* layer, int first, float delta) {
    std::vector<CellUpdate> updates;
    std::set<std::pair<int, int>> tiles;
    for (int i = 0; i < 300; ++i) {
      const CellIndex cell(first + 7 * i, (i * 13) % 97 - 40);
      updates.push_back({cell, delta});
      const TileIndex tile = GridLayer2D::tileOf(cell);
      tiles.insert({tile.x(), tile.y()});
    }
    layer->applyUpdates(updates);
    return tiles.size();
  };
  LogOddsRaster at_checkpoint;
  {
    VoxelMap map(config);
    GridLayer2D layer(layer_config);
    MapCheckpoints checkpoints(&map, &layer);
    EXPECT_EQ(checkpoints.resumedTiles(), 0u);
    touchBlocks(&map, 0, 5, 0.8f);
    const std::size_t first_tiles = scan(&layer, 0, 0.6f);
    const CheckpointResult a = checkpoints.checkpoint("a");
    ASSERT_TRUE(a.written);
    EXPECT_EQ(a.layer_records, first_tiles);
    const std::size_t second_tiles = scan(&layer, 3, -0.3f);  // most of them again
    const CheckpointResult b = checkpoints.checkpoint("b");
    ASSERT_TRUE(b.written);
    EXPECT_EQ(b.layer_records, second_tiles);
    EXPECT_EQ(b.blocks_written, 0u);
    EXPECT_EQ(checkpoints.checkpoint("c").layer_records, 0u);
    at_checkpoint = layer.toLogOddsRaster();
    scan(&layer, 5000, 0.9f);  // after the last checkpoint: lost
    EXPECT_GT(layer.tileCount(), 0u);
  }
  VoxelMap map(config);
  GridLayer2D layer(layer_config);
  const MapCheckpoints checkpoints(&map, &layer);
  const LogOddsRaster resumed = layer.toLogOddsRaster();
  EXPECT_GT(checkpoints.resumedTiles(), 10u);
  EXPECT_EQ(resumed.origin_cell, at_checkpoint.origin_cell);
  ASSERT_EQ(resumed.width, at_checkpoint.width);
  ASSERT_EQ(resumed.height, at_checkpoint.height);
  ASSERT_EQ(resumed.data.size(), at_checkpoint.data.size());
  std::size_t known = 0;
  for (std::size_t i = 0; i < resumed.data.size(); ++i) {
    const float a = resumed.data[i], b = at_checkpoint.data[i];
    ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << i;
    known += !std::isnan(a);
  }
  EXPECT_EQ(known, 600u);  // both checkpointed scans' cells (x = 7 i and 7 i + 3: none shared)
  EXPECT_EQ(map.blockCount(), 5u);
}

// Reads lines from the checkpoint writer's standard output.
class ChildOutput {
 public:
  explicit ChildOutput(int fd) : file_(fdopen(fd, "r")) {}
  ~ChildOutput() {
    if (file_ != nullptr) std::fclose(file_);
  }
  bool next(std::string* line) {
    char buffer[256];
    if (std::fgets(buffer, sizeof(buffer), file_) == nullptr) return false;
    *line = buffer;
    return true;
  }

 private:
  FILE* file_;
};

pid_t startWriter(const std::string& folder, int seed, int* read_fd) {
  int fds[2];
  if (pipe(fds) != 0) return -1;
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], STDOUT_FILENO);
    close(fds[0]);
    close(fds[1]);
    const std::string seed_text = std::to_string(seed);
    execl(CHECKPOINT_WRITER_PATH, CHECKPOINT_WRITER_PATH, folder.c_str(), seed_text.c_str(), "7",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  close(fds[1]);
  *read_fd = fds[0];
  return pid;
}

// The writer is killed at a random moment after its n-th checkpoint began (mid-checkpoint, or
// while it writes and spills after one), three times on one store: each restart resumes the last
// checkpoint that committed (the one that began, if its transaction was through, else the one
// before), and goes on from there.
TEST_F(VoxelMapCheckpoint, ProcessKilledWithSigkillResumesItsLastCheckpoint) {
  const std::string store = path("store");
  std::mt19937 rng(17);
  MapDigest expected;  // empty before the first checkpoint
  for (int round = 0; round < 4; ++round) {
    int fd = -1;
    const pid_t pid = startWriter(store, 100 + round, &fd);
    ASSERT_GT(pid, 0);
    ChildOutput output(fd);
    std::string line;
    ASSERT_TRUE(output.next(&line));
    MapDigest resumed_digest;
    std::size_t resumed_blocks = 0;
    char text[64];
    ASSERT_EQ(std::sscanf(line.c_str(), "resumed %zu %63s", &resumed_blocks, text), 2) << line;
    ASSERT_TRUE(MapDigest::parse(text, &resumed_digest));
    EXPECT_EQ(resumed_digest, expected) << "round " << round << ": " << line;
    if (round == 3) {  // the last start only checks the resume
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
      break;
    }
    const int kill_after = 3 + round;
    const int delay_us = std::uniform_int_distribution<int>(0, 3000)(rng);
    MapDigest committed = expected, pending;
    bool has_pending = false;
    // Until the kill, and then what the writer printed before it died (it runs ahead of this
    // reader): its last committed checkpoint, and the one it began after.
    bool killed = false;
    while (output.next(&line)) {
      int number = 0;
      if (std::sscanf(line.c_str(), "begin %d %63s", &number, text) == 2) {
        ASSERT_TRUE(MapDigest::parse(text, &pending));
        has_pending = true;
        if (number >= kill_after && !killed) {
          std::this_thread::sleep_for(std::chrono::microseconds(delay_us));
          ASSERT_EQ(kill(pid, SIGKILL), 0);
          killed = true;
        }
      } else if (std::sscanf(line.c_str(), "done %d", &number) == 1) {
        committed = pending;
        has_pending = false;
      }
    }
    ASSERT_TRUE(killed) << "round " << round << ": the writer ended before its checkpoint "
                        << kill_after;
    int wait_status = 0;
    ASSERT_EQ(waitpid(pid, &wait_status, 0), pid);
    ASSERT_TRUE(WIFSIGNALED(wait_status)) << "round " << round << ": the writer ended itself";
    // What the store holds now, as a map that resumes it.
    VoxelMap resumed(checkpointConfig(store, BlockStorage::kDense, kBoundBlocks));
    ASSERT_TRUE(resumed.spillStatus().checkpoints) << resumed.spillStatus().last_error;
    const MapDigest now = digestOf(resumed);
    EXPECT_GT(now.voxels, 1000u);
    EXPECT_TRUE(now == committed || (has_pending && now == pending))
        << "round " << round << ": resumed " << now.text() << ", last committed "
        << committed.text() << ", pending " << (has_pending ? pending.text() : "none");
    expected = now;
  }
}

}  // namespace
}  // namespace occupancy_fusion
