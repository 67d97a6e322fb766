#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "occupancy_fusion/map/grid_layer_2d.h"

namespace occupancy_fusion {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

GridLayer2D makeLayer(double resolution = 0.05) {
  GridLayer2DConfig config;
  config.resolution = resolution;
  return GridLayer2D(config);
}

TEST(GridLayer2D, ValidateNamesTheBadField) {
  GridLayer2DConfig config;
  config.resolution = 0.0;
  try {
    config.validate();
    FAIL() << "resolution 0 accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("resolution"), std::string::npos);
  }
  config.resolution = 0.1;
  config.model.clamp_min = 0.99;
  EXPECT_THROW(config.validate(), std::invalid_argument);
}

TEST(GridLayer2D, IndicesFloorAndCentresAreMidCell) {
  const GridLayer2D layer = makeLayer(0.05);
  EXPECT_EQ(layer.indexOf({0.01, -0.01}), CellIndex(0, -1));
  EXPECT_EQ(layer.indexOf({0.12, -0.26}), CellIndex(2, -6));
  EXPECT_TRUE(layer.centerOf({-1, 2}).isApprox(Eigen::Vector2d(-0.025, 0.125)));
  EXPECT_EQ(GridLayer2D::tileOf({-1, 32}), TileIndex(-1, 1));
  EXPECT_EQ(GridLayer2D::cellIndex({-1, 1}, GridLayer2D::linearIndexInTile({-1, 32})),
            CellIndex(-1, 32));
}

TEST(GridLayer2D, UnknownIsNotFree) {
  GridLayer2D layer = makeLayer();
  const CellIndex cell(3, -4);
  EXPECT_FALSE(layer.logOdds(cell).has_value());
  EXPECT_EQ(layer.occupancy(cell), Occupancy::kUnknown);
  // Log-odds 0 (p = 0.5) is a known value, classified free (at or below the threshold).
  layer.setLogOdds(cell, 0.0f);
  ASSERT_TRUE(layer.logOdds(cell).has_value());
  EXPECT_EQ(layer.occupancy(cell), Occupancy::kFree);
  layer.updateCell({5, 5}, layer.model().missLogOdds());
  EXPECT_FLOAT_EQ(*layer.logOdds({5, 5}), std::log(0.4f / 0.6f));
  EXPECT_EQ(layer.occupancy({5, 6}), Occupancy::kUnknown);
  EXPECT_EQ(layer.knownCellCount(), 2u);
}

TEST(GridLayer2D, RepeatedHitsAndMissesClampAtOctomapBounds) {
  GridLayer2D layer = makeLayer();
  const float hit = std::log(0.7f / 0.3f);
  for (int i = 0; i < 4; ++i) layer.updateCell({0, 0}, hit);
  EXPECT_NEAR(*layer.logOdds({0, 0}), 4 * hit, 1e-5);  // 3.389 < logit(0.971)
  layer.updateCell({0, 0}, hit);
  EXPECT_NEAR(*layer.logOdds({0, 0}), std::log(0.971 / 0.029), 1e-5);
  for (int i = 0; i < 20; ++i) layer.updateCell({0, 0}, hit);
  EXPECT_NEAR(*layer.logOdds({0, 0}), 3.51103, 1e-4);
  std::vector<CellUpdate> misses(30, CellUpdate{{0, 0}, std::log(0.4f / 0.6f)});
  layer.applyUpdates(misses);
  EXPECT_NEAR(*layer.logOdds({0, 0}), -1.99993, 1e-4);  // logit(0.1192)
  EXPECT_EQ(layer.occupancy({0, 0}), Occupancy::kFree);
}

TEST(GridLayer2D, AddRasterSkipsNaNAndSpansTiles) {
  GridLayer2D layer = makeLayer();
  // 40 x 3 window across the tile boundary at x = 0 and y = 0, with NaN holes.
  const CellIndex origin(-20, -1);
  const int width = 40, height = 3;
  std::vector<float> deltas(width * height);
  int expected_known = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const bool hole = (x + 2 * y) % 5 == 0;
      deltas[x + width * y] = hole ? kNaN : 0.01f * (x - 20) + 0.1f * y;
      expected_known += hole ? 0 : 1;
    }
  }
  layer.addRaster(origin, width, height, deltas.data());
  layer.addRaster(origin, width, height, deltas.data());  // accumulates
  EXPECT_EQ(layer.knownCellCount(), static_cast<std::size_t>(expected_known));
  EXPECT_EQ(layer.tileCount(), 4u);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const std::optional<float> value = layer.logOdds(origin + CellIndex(x, y));
      if (std::isnan(deltas[x + width * y])) {
        EXPECT_FALSE(value.has_value()) << x << "," << y;
      } else {
        ASSERT_TRUE(value.has_value()) << x << "," << y;
        EXPECT_NEAR(*value, 2 * deltas[x + width * y], 1e-6);
      }
    }
  }
  EXPECT_FALSE(layer.logOdds(origin + CellIndex(width, 0)).has_value());
  EXPECT_FALSE(layer.logOdds(origin - CellIndex(0, 1)).has_value());

  // window() reads back the same layout.
  const std::vector<float> copy = layer.window(origin, width, height);
  for (int i = 0; i < width * height; ++i) {
    if (std::isnan(deltas[i])) {
      EXPECT_TRUE(std::isnan(copy[i]));
    } else {
      EXPECT_NEAR(copy[i], 2 * deltas[i], 1e-6);
    }
  }
  const std::optional<CellBox> box = layer.knownBounds();
  ASSERT_TRUE(box.has_value());
  EXPECT_EQ(box->min, CellIndex(-20, -1));
  EXPECT_EQ(box->max, CellIndex(19, 1));
  const LogOddsRaster raster = layer.toLogOddsRaster();
  EXPECT_EQ(raster.origin_cell, box->min);
  EXPECT_EQ(raster.width, 40);
  EXPECT_EQ(raster.height, 3);
  EXPECT_NEAR(raster.at(3, 2), 2 * deltas[3 + width * 2], 1e-6);
  EXPECT_TRUE(std::isnan(raster.at(0, 0)));  // a hole
}

TEST(GridLayer2D, ClearBoxFreesKnownCellsWithCentresInside) {
  GridLayer2D layer = makeLayer(0.1);
  for (int x = -5; x < 5; ++x) layer.updateCell({x, 0}, 3.0f);
  // Centres at x = -0.25 .. 0.25 (cells -3 .. 2); cell 3's centre 0.35 is outside.
  const std::size_t changed = layer.clearBox({-0.26, -0.1}, {0.3, 0.1});
  EXPECT_EQ(changed, 6u);
  for (int x = -5; x < 5; ++x) {
    const bool inside = x >= -3 && x <= 2;
    EXPECT_FLOAT_EQ(*layer.logOdds({x, 0}), inside ? layer.minLogOdds() : 3.0f) << x;
  }
  EXPECT_FALSE(layer.logOdds({0, 1}).has_value());  // unknown stays unknown
}

TEST(GridLayer2D, ChangeLogAndReset) {
  GridLayer2D layer = makeLayer();
  EXPECT_TRUE(layer.changesSince(0).full_rebuild);
  const std::uint64_t start = layer.version();
  layer.updateCell({40, -3}, 1.0f);
  layer.updateCell({41, -3}, 1.0f);
  GridChanges changes = layer.changesSince(start);
  EXPECT_FALSE(changes.full_rebuild);
  ASSERT_FALSE(changes.changed.empty());
  for (const TileIndex& tile : changes.changed) EXPECT_EQ(tile, TileIndex(1, -1));
  EXPECT_TRUE(layer.changesSince(changes.version).changed.empty());

  const std::size_t memory = layer.memoryBytes();
  layer.reset();
  EXPECT_TRUE(layer.changesSince(changes.version).full_rebuild);
  EXPECT_EQ(layer.knownCellCount(), 0u);
  EXPECT_EQ(layer.occupancy({40, -3}), Occupancy::kUnknown);
  EXPECT_LT(layer.memoryBytes(), memory);
  EXPECT_FALSE(layer.knownBounds().has_value());
}

}  // namespace
}  // namespace occupancy_fusion
