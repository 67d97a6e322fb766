// The 2D laser layer under a memory bound with the map's spill store: every read equal to an
// unbounded layer's after the same writes, tiles in memory within the bound, checkpoints that
// resume the layer exactly, and a failing store that loses nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "../../common/test_folder.h"
#include "occupancy_fusion/map/layer_files.h"
#include "occupancy_fusion/map/map_checkpoints.h"

namespace occupancy_fusion {
namespace {

constexpr std::size_t kBoundTiles = 12;

VoxelMapConfig mapConfig(const std::string& folder, double checkpoint_period = 0.0) {
  VoxelMapConfig config;
  config.resolution = 0.05;
  config.spill_folder = folder;
  config.checkpoint_period = checkpoint_period;
  config.layer_max_memory_bytes = kBoundTiles * sizeof(GridTile);
  return config;
}

// A scan's window: width x height increments around `centre`, some cells without information.
struct Scan {
  CellIndex origin;
  int width, height;
  std::vector<float> deltas;
};
Scan scanAt(const CellIndex& centre, std::mt19937* rng) {
  std::uniform_real_distribution<float> delta(-0.6f, 0.9f);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  Scan scan{centre - CellIndex(40, 30), 80, 60, {}};
  for (int i = 0; i < scan.width * scan.height; ++i) {
    scan.deltas.push_back(unit(*rng) < 0.2f ? std::nanf("") : delta(*rng));
  }
  return scan;
}

// Out along x for 600 cells (19 tiles), then back: tiles leave memory and come back.
std::vector<Scan> scansOutAndBack(unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<Scan> scans;
  for (int step = 0; step <= 60; ++step) scans.push_back(scanAt({10 * step, 3 * (step % 7)}, &rng));
  for (int step = 60; step >= 0; step -= 3) scans.push_back(scanAt({10 * step, -20}, &rng));
  return scans;
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

void expectSameLayers(const GridLayer2D& bounded, const GridLayer2D& reference) {
  EXPECT_EQ(bounded.tileCount(), reference.tileCount());
  EXPECT_EQ(bounded.knownCellCount(), reference.knownCellCount());
  const LogOddsRaster a = bounded.toLogOddsRaster(), b = reference.toLogOddsRaster();
  ASSERT_EQ(a.origin_cell, b.origin_cell);
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  std::size_t differing = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) differing += !sameBits(a.data[i], b.data[i]);
  EXPECT_EQ(differing, 0u);
  std::map<std::uint64_t, int> tiles_a, tiles_b;
  bounded.forEachTile(
      [&](const TileIndex& t, const GridTile& tile) { tiles_a[packKey(t)] = tile.known_count; });
  reference.forEachTile(
      [&](const TileIndex& t, const GridTile& tile) { tiles_b[packKey(t)] = tile.known_count; });
  EXPECT_EQ(tiles_a, tiles_b);
  std::size_t cells = 0;
  bounded.forEachKnownCell([&](const CellIndex& cell, float value) {
    const std::optional<float> expected = reference.logOdds(cell);
    ASSERT_TRUE(expected.has_value());
    EXPECT_TRUE(sameBits(value, *expected));
    ++cells;
  });
  EXPECT_EQ(cells, reference.knownCellCount());
  for (int x = -50; x < 650; x += 7) {
    const CellIndex cell(x, (x * 13) % 50 - 25);
    EXPECT_EQ(bounded.logOdds(cell).has_value(), reference.logOdds(cell).has_value());
    EXPECT_EQ(bounded.occupancy(cell), reference.occupancy(cell));
  }
  const std::vector<float> wa = bounded.window({100, -40}, 300, 90);
  const std::vector<float> wb = reference.window({100, -40}, 300, 90);
  for (std::size_t i = 0; i < wa.size(); ++i) ASSERT_TRUE(sameBits(wa[i], wb[i])) << i;
}

std::size_t tilesInMemory(const GridLayer2D& layer) {
  return layer.tileCount() - layer.spillStatus().spilled_tiles;
}

TEST(GridLayerSpill, BoundedLayerReadsAsAnUnboundedOneAndKeepsItsBound) {
  TemporaryFolder folder;
  const VoxelMapConfig config = mapConfig(folder.path("store"));
  VoxelMap voxels(config);
  ASSERT_TRUE(voxels.hasStore());
  GridLayer2D bounded(laserLayerConfig(config));
  MapCheckpoints checkpoints(&voxels, &bounded);  // gives the layer the map's store
  GridLayer2D reference(laserLayerConfig(VoxelMapConfig()));
  std::size_t most_in_memory = 0;
  for (const Scan& scan : scansOutAndBack(5)) {
    bounded.addRaster(scan.origin, scan.width, scan.height, scan.deltas.data());
    reference.addRaster(scan.origin, scan.width, scan.height, scan.deltas.data());
    most_in_memory = std::max(most_in_memory, tilesInMemory(bounded));
  }
  EXPECT_LE(most_in_memory, kBoundTiles);
  // Writes of other kinds reach stored tiles too.
  std::vector<CellUpdate> updates;
  for (int x = 0; x < 600; x += 5) updates.push_back({{x, 2}, 0.4f});
  bounded.applyUpdates(updates);
  reference.applyUpdates(updates);
  bounded.clearBox({0.0, -1.0}, {30.0, 1.0});
  reference.clearBox({0.0, -1.0}, {30.0, 1.0});
  bounded.setLogOdds({-3, -3}, 1.25f);
  reference.setLogOdds({-3, -3}, 1.25f);
  const TileSpillStatus status = bounded.spillStatus();
  EXPECT_TRUE(status.enabled);
  EXPECT_GT(status.spilled_tiles, 0u);
  EXPECT_GT(status.tiles_paged_in, 0u);
  EXPECT_EQ(status.failures, 0u);
  EXPECT_LE(tilesInMemory(bounded), kBoundTiles);
  expectSameLayers(bounded, reference);

  // Its files, written a strip of tiles at a time (most of them from the store), are the bytes of
  // the unbounded layer's whole window written at once; the bound holds while writing them.
  const LayerFilePaths streamed = writeLayerFiles(bounded, folder.path("bounded"));
  const LayerFilePaths whole = writeLayerFiles(reference.toLogOddsRaster(), folder.path("whole"));
  EXPECT_TRUE(readAll(streamed.npy) == readAll(whole.npy));
  const LogOddsRaster read_back = readLayerFiles(streamed.yaml);  // its CRC-32 checked
  EXPECT_EQ(read_back.origin_cell, reference.toLogOddsRaster().origin_cell);
  EXPECT_LE(tilesInMemory(bounded), kBoundTiles);
  GridLayer2D empty(laserLayerConfig(VoxelMapConfig()));
  EXPECT_TRUE(readAll(writeLayerFiles(empty, folder.path("empty")).npy) ==
              readAll(writeLayerFiles(empty.toLogOddsRaster(), folder.path("empty_whole")).npy));
}

TEST(GridLayerSpill, ACheckpointResumesTheLayerExactlyAndLaterSpillsAreDiscarded) {
  TemporaryFolder folder;
  const VoxelMapConfig config = mapConfig(folder.path("store"), 1.0);
  const std::vector<Scan> scans = scansOutAndBack(9);
  GridLayer2D expected(laserLayerConfig(VoxelMapConfig()));
  {
    VoxelMap voxels(config);
    GridLayer2D layer(laserLayerConfig(config));
    MapCheckpoints checkpoints(&voxels, &layer);
    for (std::size_t i = 0; i < scans.size(); ++i) {
      const Scan& scan = scans[i];
      layer.addRaster(scan.origin, scan.width, scan.height, scan.deltas.data());
      if (i < 50) expected.addRaster(scan.origin, scan.width, scan.height, scan.deltas.data());
      // Checkpoints while tiles are stored, the last after scan 49; the scans after it spill
      // tiles that no checkpoint holds.
      if (i == 20 || i == 35 || i == 49) {
        ASSERT_TRUE(checkpoints.checkpoint("t").written);
      }
    }
    ASSERT_GT(layer.spillStatus().tiles_written, 0u);
  }
  VoxelMap voxels(config);
  GridLayer2D resumed(laserLayerConfig(config));
  MapCheckpoints checkpoints(&voxels, &resumed);
  EXPECT_GT(checkpoints.resumedTiles(), 0u);
  EXPECT_LE(tilesInMemory(resumed), kBoundTiles);
  expectSameLayers(resumed, expected);
}

// A store whose writes fail: the tiles stay in memory.
class FailingTileStore : public TileStore {
 public:
  bool put(const std::vector<std::pair<std::uint64_t, const GridTile*>>&) override {
    ++puts;
    return false;
  }
  bool get(std::uint64_t, GridTile*) const override { return false; }
  int puts = 0;
};

TEST(GridLayerSpill, AFailingStoreKeepsEveryTileInMemory) {
  GridLayer2DConfig config;
  config.max_memory_bytes = kBoundTiles * sizeof(GridTile);
  GridLayer2D bounded(config);
  auto store = std::make_unique<FailingTileStore>();
  const FailingTileStore* failing = store.get();
  bounded.setTileStore(std::move(store));
  GridLayer2D reference{GridLayer2DConfig()};
  for (const Scan& scan : scansOutAndBack(3)) {
    bounded.addRaster(scan.origin, scan.width, scan.height, scan.deltas.data());
    reference.addRaster(scan.origin, scan.width, scan.height, scan.deltas.data());
  }
  EXPECT_GT(failing->puts, 0);
  const TileSpillStatus status = bounded.spillStatus();
  EXPECT_EQ(status.spilled_tiles, 0u);
  EXPECT_EQ(status.failures, static_cast<std::size_t>(failing->puts));
  EXPECT_GT(tilesInMemory(bounded), kBoundTiles);  // the bound is exceeded, nothing lost
  expectSameLayers(bounded, reference);
}

}  // namespace
}  // namespace occupancy_fusion
