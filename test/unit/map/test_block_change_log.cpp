#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "occupancy_fusion/map/block_change_log.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {
namespace {

struct Recorded {
  std::uint64_t version;
  std::uint64_t key;
  bool removed;
};

// What a consumer at `since` must hear of, from the full, never compacted history: every key
// with an entry at or after `since`, classified by its newest entry.
void bruteForce(const std::vector<Recorded>& history, std::uint64_t since,
                std::set<std::uint64_t>* changed, std::set<std::uint64_t>* removed) {
  std::map<std::uint64_t, bool> newest_removed;
  for (const Recorded& entry : history) {
    if (entry.version >= since) newest_removed[entry.key] = entry.removed;
  }
  for (const auto& [key, was_removed] : newest_removed) {
    (was_removed ? removed : changed)->insert(key);
  }
}

TEST(BlockChangeLog, CompactedLogAnswersLikeTheFullHistory) {
  BlockChangeLog log;
  std::vector<Recorded> history;
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::uint64_t> key(0, 300);
  std::uniform_int_distribution<int> percent(0, 99);
  std::uint64_t version = 1;
  for (int write = 0; write < 20000; ++write, ++version) {
    const int entries = 1 + percent(rng) % 8;
    for (int i = 0; i < entries; ++i) {
      const bool removed = percent(rng) < 10;
      const std::uint64_t k = key(rng);
      removed ? log.recordRemoval(version, k) : log.recordChange(version, k);
      history.push_back({version, k, removed});
    }
    log.finishWrite();
    if (write % 997 == 0) {
      for (std::uint64_t since :
           {std::uint64_t{1}, std::max<std::uint64_t>(1, version / 2), version, version + 1}) {
        std::vector<std::uint64_t> changed, removed;
        ASSERT_TRUE(log.collectSince(since, &changed, &removed));
        std::set<std::uint64_t> want_changed, want_removed;
        bruteForce(history, since, &want_changed, &want_removed);
        EXPECT_EQ(std::set<std::uint64_t>(changed.begin(), changed.end()), want_changed);
        EXPECT_EQ(std::set<std::uint64_t>(removed.begin(), removed.end()), want_removed);
        EXPECT_EQ(changed.size() + removed.size(), want_changed.size() + want_removed.size())
            << "a key listed twice";
      }
    }
  }
  // 90 000 entries were recorded over 301 keys; the log keeps about one per key.
  EXPECT_GT(history.size(), 80000u);
  EXPECT_LE(log.size(), 2 * 301u + 8 * 2);
}

TEST(BlockChangeLog, ASmallMapsLogStaysSmall) {
  // Eight blocks written by every frame (a small room at a coarse voxel size): the log must not
  // grow to hundreds of entries, a multiple of the blocks' own memory, before compacting.
  BlockChangeLog log;
  std::size_t peak = 0;
  for (std::uint64_t version = 1; version <= 1000; ++version) {
    for (std::uint64_t key = 0; key < 8; ++key) log.recordChange(version, key);
    log.finishWrite();
    peak = std::max(peak, log.size());
  }
  EXPECT_LE(peak, 4 * 8u);
  std::vector<std::uint64_t> changed;
  ASSERT_TRUE(log.collectSince(1, &changed, nullptr));
  EXPECT_EQ(changed.size(), 8u);
}

TEST(BlockChangeLog, ClearMakesOlderConsumersRebuild) {
  BlockChangeLog log;
  log.recordChange(1, 7);
  log.finishWrite();
  log.clear(3);
  std::vector<std::uint64_t> changed;
  EXPECT_FALSE(log.collectSince(2, &changed, nullptr));
  EXPECT_TRUE(log.collectSince(3, &changed, nullptr));
  EXPECT_TRUE(changed.empty());
}

TEST(VoxelMap, MemoryDoesNotGrowWithRepeatedWritesToTheSameBlocks) {
  VoxelMapConfig config;
  config.resolution = 0.1;
  VoxelMap map(config);
  // The log's size cycles between compactions; its peak must not grow with the frame count.
  auto peak_memory_over = [&](int frames) {
    std::size_t peak = 0;
    for (int frame = 0; frame < frames; ++frame) {
      std::vector<VoxelUpdate> updates;
      for (int block = 0; block < 16; ++block) updates.push_back({{block * 8, 0, 0}, 0.0f});
      map.applyUpdates(updates);
      peak = std::max(peak, map.memoryBytes());
    }
    return peak;
  };
  const std::size_t first_peak = peak_memory_over(1000);
  const std::size_t later_peak = peak_memory_over(20000);
  EXPECT_LE(later_peak, first_peak);
  EXPECT_LT(later_peak,
            16 * sizeof(VoxelBlock) + 4 * 16 * sizeof(BlockChangeLog::Entry) + (1u << 12));
}

}  // namespace
}  // namespace occupancy_fusion
