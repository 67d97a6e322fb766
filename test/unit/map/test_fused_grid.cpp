#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#include "occupancy_fusion/map/fused_grid.h"

namespace occupancy_fusion {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kOccupied = 2.0f;
constexpr float kFree = -1.0f;

VoxelMapConfig mapConfig(double resolution = 0.1) {
  VoxelMapConfig config;
  config.resolution = resolution;
  return config;
}

GridLayer2DConfig layerConfig(double resolution) {
  GridLayer2DConfig config;
  config.resolution = resolution;
  return config;
}

FusedGridConfig band(double min_z, double max_z) {
  FusedGridConfig config;
  config.min_z = min_z;
  config.max_z = max_z;
  return config;
}

// Value of the column containing the map point (x, y); unknown outside the raster.
int valueAt(const OccupancyRaster& raster, double x, double y) {
  const int cx = static_cast<int>(std::floor((x - raster.origin_x) / raster.resolution + 1e-9));
  const int cy = static_cast<int>(std::floor((y - raster.origin_y) / raster.resolution + 1e-9));
  if (cx < 0 || cy < 0 || cx >= raster.width || cy >= raster.height) return -1;
  return raster.at(cx, cy);
}

void expectSameRaster(const OccupancyRaster& actual, const OccupancyRaster& expected,
                      const std::string& where) {
  ASSERT_EQ(actual.width, expected.width) << where;
  ASSERT_EQ(actual.height, expected.height) << where;
  EXPECT_DOUBLE_EQ(actual.resolution, expected.resolution) << where;
  EXPECT_NEAR(actual.origin_x, expected.origin_x, 1e-12) << where;
  EXPECT_NEAR(actual.origin_y, expected.origin_y, 1e-12) << where;
  int differences = 0;
  for (std::size_t i = 0; i < expected.data.size(); ++i) {
    differences += actual.data[i] != expected.data[i] ? 1 : 0;
  }
  EXPECT_EQ(differences, 0) << where;
}

TEST(FusedGridConfig, RejectsInvertedBand) {
  EXPECT_THROW(band(1.0, 0.0).validate(), std::invalid_argument);
  EXPECT_THROW(band(std::nan(""), 0.0).validate(), std::invalid_argument);
  EXPECT_NO_THROW(band(0.5, 0.5).validate());
}

TEST(FusedGrid, OccupiedWinsThenFreeElseUnknown) {
  VoxelMap map(mapConfig(0.1));
  GridLayer2D layer(layerConfig(0.1));
  // Column (0, 0): occupied and free voxels -> occupied.
  map.setLogOdds({0, 0, 0}, kFree);
  map.setLogOdds({0, 0, 1}, kOccupied);
  // Column (1, 0): free voxels only -> free.
  map.setLogOdds({1, 0, 0}, kFree);
  map.setLogOdds({1, 0, 3}, kFree);
  // Column (2, 0): free voxel, occupied laser cell -> occupied.
  map.setLogOdds({2, 0, 0}, kFree);
  layer.setLogOdds({2, 0}, kOccupied);
  // Column (3, 0): free laser cell only -> free. Column (4, 0): occupied voxel, free laser -> occ.
  layer.setLogOdds({3, 0}, kFree);
  map.setLogOdds({4, 0, 2}, kOccupied);
  layer.setLogOdds({4, 0}, kFree);
  // Column (0, 2): occupied voxel above the band only -> unknown, but inside the raster.
  map.setLogOdds({0, 2, 30}, kOccupied);
  layer.setLogOdds({0, 3}, kFree);  // stretches the raster to y = 3

  const FusedGridConfig config = band(-1.0, 1.0);
  FusedGridView view(config);
  for (const OccupancyRaster& raster :
       {projectToRaster(map, &layer, config), view.update(map, &layer)}) {
    EXPECT_EQ(raster.width, 5);
    EXPECT_EQ(raster.height, 4);
    EXPECT_DOUBLE_EQ(raster.origin_x, 0.0);
    EXPECT_DOUBLE_EQ(raster.origin_y, 0.0);
    EXPECT_EQ(raster.at(0, 0), 100);
    EXPECT_EQ(raster.at(1, 0), 0);
    EXPECT_EQ(raster.at(2, 0), 100);
    EXPECT_EQ(raster.at(3, 0), 0);
    EXPECT_EQ(raster.at(4, 0), 100);
    EXPECT_EQ(raster.at(0, 2), -1);
    EXPECT_EQ(raster.at(0, 3), 0);
    EXPECT_EQ(raster.at(2, 1), -1);
  }
  // Without the layer, the laser-only columns are unknown.
  const OccupancyRaster map_only = projectToRaster(map, nullptr, config);
  EXPECT_EQ(map_only.width, 5);
  EXPECT_EQ(map_only.height, 1);
  EXPECT_EQ(map_only.at(2, 0), 0);
  EXPECT_EQ(map_only.at(3, 0), -1);
  expectSameRaster(view.update(map, nullptr), map_only, "layer removed");
}

TEST(FusedGrid, HeightBandIncludesVoxelCentresOnItsEdges) {
  VoxelMap map(mapConfig(0.1));
  map.setLogOdds({-3, 5, 2}, kOccupied);  // centre z = 0.25
  const double centre = map.centerOf({-3, 5, 2}).z();
  struct Case {
    double min_z, max_z;
    bool included;
  };
  for (const Case& c :
       {Case{centre, 1.0, true}, Case{-1.0, centre, true}, Case{centre, centre, true},
        Case{centre + 1e-9, 1.0, false}, Case{-1.0, centre - 1e-9, false}}) {
    const FusedGridConfig config = band(c.min_z, c.max_z);
    FusedGridView view(config);
    for (const OccupancyRaster& raster :
         {projectToRaster(map, nullptr, config), view.update(map, nullptr)}) {
      if (c.included) {
        ASSERT_EQ(raster.width, 1);
        EXPECT_EQ(raster.at(0, 0), 100);
        EXPECT_NEAR(raster.origin_x, -0.3, 1e-12);
        EXPECT_NEAR(raster.origin_y, 0.5, 1e-12);
      } else {
        EXPECT_TRUE(raster.empty());
      }
    }
  }
}

TEST(FusedGrid, ResamplesFinerAndCoarserLayersByArea) {
  VoxelMap map(mapConfig(0.1));
  map.setLogOdds({0, 0, 0}, kFree);
  GridLayer2D fine(layerConfig(0.05));
  fine.setLogOdds({3, 1}, kOccupied);  // [0.15, 0.2) x [0.05, 0.1): column (1, 0) only
  OccupancyRaster raster = projectToRaster(map, &fine, FusedGridConfig());
  ASSERT_EQ(raster.width, 2);
  ASSERT_EQ(raster.height, 1);
  EXPECT_EQ(raster.at(0, 0), 0);
  EXPECT_EQ(raster.at(1, 0), 100);

  GridLayer2D coarse(layerConfig(0.25));
  coarse.setLogOdds({-1, 0}, kOccupied);  // [-0.25, 0) x [0, 0.25): columns x -3..-1, y 0..2
  raster = projectToRaster(map, &coarse, FusedGridConfig());
  EXPECT_NEAR(raster.origin_x, -0.3, 1e-12);
  EXPECT_EQ(raster.width, 4);
  EXPECT_EQ(raster.height, 3);
  EXPECT_EQ(valueAt(raster, -0.29, 0.01), 100);
  EXPECT_EQ(valueAt(raster, -0.01, 0.29), 100);
  EXPECT_EQ(valueAt(raster, 0.05, 0.05), 0);
  EXPECT_EQ(valueAt(raster, 0.05, 0.15), -1);
  FusedGridView view;
  expectSameRaster(view.update(map, &coarse), raster, "coarse layer");
}

// Random writes, clears, resets, evictions and layer swaps: after each step the incremental view
// must equal the reference, and it must not rebuild from scratch unless the log says so.
void runRandomSequence(double layer_resolution, std::size_t map_memory_bound, unsigned seed,
                       BlockStorage storage = BlockStorage::kHybrid) {
  VoxelMapConfig config = mapConfig(0.1);
  config.max_memory_bytes = map_memory_bound;
  config.block_storage = storage;
  VoxelMap map(config);
  GridLayer2D layer(layerConfig(layer_resolution));
  const FusedGridConfig band_config = band(-0.3, 0.45);
  FusedGridView view(band_config);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> coordinate(-40, 40);
  std::uniform_int_distribution<int> height(-8, 10);
  std::uniform_real_distribution<float> delta(-1.5f, 1.5f);
  std::uniform_int_distribution<int> operation(0, 99);
  bool use_layer = true;
  int incremental_steps = 0;
  for (int step = 0; step < 120; ++step) {
    const int op = operation(rng);
    bool expect_map_rebuild = false;
    if (op < 45) {
      std::vector<VoxelUpdate> updates;
      const VoxelIndex centre(coordinate(rng), coordinate(rng), height(rng));
      for (int i = 0; i < 60; ++i) {
        updates.push_back(
            {centre + VoxelIndex(coordinate(rng) / 8, coordinate(rng) / 8, height(rng) / 3),
             delta(rng)});
      }
      map.setFocus(map.centerOf(centre));
      map.applyUpdates(updates);
    } else if (op < 75) {
      const int width = 1 + std::abs(coordinate(rng)) / 2, rows = 1 + std::abs(coordinate(rng)) / 3;
      std::vector<float> deltas(width * rows);
      for (float& value : deltas) value = operation(rng) < 20 ? kNaN : delta(rng);
      layer.addRaster({coordinate(rng), coordinate(rng)}, width, rows, deltas.data());
    } else if (op < 83) {
      const Eigen::Vector3d lo(coordinate(rng) * 0.1, coordinate(rng) * 0.1, -0.2);
      map.clearBox(lo, lo + Eigen::Vector3d(1.0, 1.0, 0.4));
    } else if (op < 90) {
      const Eigen::Vector2d lo(coordinate(rng) * 0.1, coordinate(rng) * 0.1);
      layer.clearBox(lo, lo + Eigen::Vector2d(1.5, 0.7));
    } else if (op < 93) {
      map.reset();
      expect_map_rebuild = true;
    } else if (op < 96) {
      layer.reset();
    } else {
      use_layer = !use_layer;
    }
    const GridLayer2D* layer_used = use_layer ? &layer : nullptr;
    const std::string where = "step " + std::to_string(step) + " op " + std::to_string(op);
    expectSameRaster(view.update(map, layer_used), projectToRaster(map, layer_used, band_config),
                     where);
    if (step > 0) {
      EXPECT_EQ(view.lastUpdateStats().map_rebuilt, expect_map_rebuild) << where;
      incremental_steps += view.lastUpdateStats().map_rebuilt ? 0 : 1;
    }
  }
  EXPECT_GT(incremental_steps, 100);
  if (map_memory_bound > 0) {
    EXPECT_GT(map.evictedBlockCount(), 0u);
  }
}

TEST(FusedGrid, IncrementalEqualsReferenceAlignedLayer) { runRandomSequence(0.1, 0, 1); }
TEST(FusedGrid, IncrementalEqualsReferenceFinerUnalignedLayer) { runRandomSequence(0.07, 0, 2); }
TEST(FusedGrid, IncrementalEqualsReferenceCoarserLayer) { runRandomSequence(0.25, 0, 3); }
TEST(FusedGrid, IncrementalEqualsReferenceWithEvictions) {
  runRandomSequence(0.1, 60 * sizeof(VoxelBlock), 4, BlockStorage::kDense);
  // Scattered updates leave most blocks sparse, at a fraction of a dense block's bytes.
  runRandomSequence(0.1, 10 * sizeof(VoxelBlock), 4, BlockStorage::kHybrid);
}

TEST(FusedGrid, UpdateTouchesOnlyChangedBlocks) {
  VoxelMap map(mapConfig(0.1));
  GridLayer2D layer(layerConfig(0.05));
  for (int x = 0; x < 100; x += 4) map.updateVoxel({x, x, 0}, kOccupied);
  layer.updateCell({0, 0}, kFree);
  FusedGridView view;
  view.update(map, &layer);
  EXPECT_TRUE(view.lastUpdateStats().map_rebuilt);
  map.updateVoxel({1, 1, 0}, kFree);
  const OccupancyRaster raster = view.update(map, &layer);
  EXPECT_FALSE(view.lastUpdateStats().map_rebuilt);
  EXPECT_FALSE(view.lastUpdateStats().layer_rebuilt);
  EXPECT_EQ(view.lastUpdateStats().map_blocks_processed, 1u);
  EXPECT_EQ(view.lastUpdateStats().layer_tiles_processed, 0u);
  EXPECT_EQ(raster.at(1, 1), 0);
  view.update(map, &layer);
  EXPECT_EQ(view.lastUpdateStats().map_blocks_processed, 0u);
}

}  // namespace
}  // namespace occupancy_fusion
