// The laser layer's files (layer_files.h): a saved layer reads back bit-exact at the same cells,
// the .npy is the documented array (checked here by reading its bytes independently), an import
// replaces only the cells it contains and is seen by the change log, and every kind of damage is
// refused with a message saying what is wrong.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "../../common/test_folder.h"
#include "occupancy_fusion/map/layer_files.h"
#include "occupancy_fusion/map/map_files.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

constexpr float kInf = std::numeric_limits<float>::infinity();

using CellValues = std::map<std::pair<int, int>, float>;

GridLayer2DConfig layerConfig() {
  GridLayer2DConfig config;
  config.resolution = 0.05;
  return config;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

// CRC-32 as zlib.crc32 (reflected polynomial 0xEDB88320), bit by bit: independent of the
// library the writer uses.
std::uint32_t bitwiseCrc32(const std::string& bytes) {
  std::uint32_t crc = 0xffffffffu;
  for (const char byte : bytes) {
    crc ^= static_cast<unsigned char>(byte);
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// Scattered cells on both sides of both axes, with values inside and outside the clamping bounds
// (setLogOdds does not clamp: an import must keep whatever was saved).
CellValues fillRandom(GridLayer2D* layer, unsigned seed, int cells) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> x(-97, 61);
  std::uniform_int_distribution<int> y(-33, 118);
  std::uniform_real_distribution<float> value(-6.0f, 6.0f);
  CellValues written;
  for (int i = 0; i < cells; ++i) {
    const CellIndex cell(x(random), y(random));
    const float log_odds = value(random);
    layer->setLogOdds(cell, log_odds);
    written[{cell.x(), cell.y()}] = log_odds;
  }
  return written;
}

using LayerFiles = TestFolder;

TEST_F(LayerFiles, SavedLayerReadsBackBitExactAtTheSameCells) {
  GridLayer2D saved(layerConfig());
  const CellValues written = fillRandom(&saved, 7, 2500);
  const LayerFilePaths paths = writeLayerFiles(saved.toLogOddsRaster(), path("site"));
  EXPECT_EQ(paths.yaml, path("site.laser.yaml"));
  EXPECT_EQ(paths.npy, path("site.laser.npy"));

  GridLayer2D resumed(layerConfig());
  resumed.importRaster(readLayerFiles(paths.yaml));
  EXPECT_EQ(resumed.knownCellCount(), written.size());
  std::size_t mismatches = 0;
  for (const auto& [cell, value] : written) {
    const std::optional<float> back = resumed.logOdds(CellIndex(cell.first, cell.second));
    if (!back || !sameBits(*back, value)) ++mismatches;
  }
  EXPECT_EQ(mismatches, 0u);
}

// The .npy read byte by byte as NumPy would: shape (rows = y extent, columns = x extent), row 0
// the lowest y, NaN where nothing was written; the yaml places array[0, 0] at the lowest cell.
TEST_F(LayerFiles, ArrayIsTheDocumentedNumpyLayout) {
  GridLayer2D layer(layerConfig());
  const CellValues written = fillRandom(&layer, 11, 400);
  int min_x = 1 << 30, min_y = 1 << 30, max_x = -(1 << 30), max_y = -(1 << 30);
  for (const auto& entry : written) {
    min_x = std::min(min_x, entry.first.first);
    max_x = std::max(max_x, entry.first.first);
    min_y = std::min(min_y, entry.first.second);
    max_y = std::max(max_y, entry.first.second);
  }
  const int width = max_x - min_x + 1;
  const int height = max_y - min_y + 1;
  const LayerFilePaths paths = writeLayerFiles(layer.toLogOddsRaster(), path("site"));

  const std::string npy = readBytes(paths.npy);
  ASSERT_EQ(npy.compare(0, 8, std::string("\x93NUMPY\x01\x00", 8)), 0);
  const std::size_t header_length =
      static_cast<unsigned char>(npy[8]) |
      (static_cast<std::size_t>(static_cast<unsigned char>(npy[9])) << 8);
  const std::string header = npy.substr(10, header_length);
  EXPECT_NE(header.find("'descr': '<f4'"), std::string::npos) << header;
  EXPECT_NE(header.find("'shape': (" + std::to_string(height) + ", " + std::to_string(width) + ")"),
            std::string::npos)
      << header;
  const std::size_t data = 10 + header_length;
  EXPECT_EQ(data % 64, 0u);
  ASSERT_EQ(npy.size(), data + 4u * width * height);
  std::size_t known = 0;
  for (int row = 0; row < height; ++row) {
    for (int column = 0; column < width; ++column) {
      float value;
      std::memcpy(&value, npy.data() + data + 4 * (row * width + column), sizeof(value));
      const auto found = written.find({min_x + column, min_y + row});
      if (found == written.end()) {
        EXPECT_TRUE(std::isnan(value)) << row << ", " << column;
      } else {
        ++known;
        EXPECT_TRUE(sameBits(value, found->second)) << row << ", " << column;
      }
    }
  }
  EXPECT_EQ(known, written.size());

  const std::string yaml = readBytes(paths.yaml);
  EXPECT_NE(yaml.find("log_odds: site.laser.npy\n"), std::string::npos) << yaml;
  EXPECT_EQ(bitwiseCrc32("123456789"), 0xcbf43926u);  // the CRC-32 check value
  char crc_text[32];
  std::snprintf(crc_text, sizeof(crc_text), "log_odds_crc32: 0x%08x", bitwiseCrc32(npy));
  EXPECT_NE(yaml.find(crc_text), std::string::npos) << crc_text << "\n" << yaml;
  EXPECT_NE(yaml.find("resolution: 0.05\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("origin_cell: [" + std::to_string(min_x) + ", " + std::to_string(min_y)),
            std::string::npos)
      << yaml;
  const LogOddsRaster parsed = parseLayerFiles(yaml, npy);
  EXPECT_NEAR(parsed.origin_cell.x() * parsed.resolution, min_x * 0.05, 1e-12);
}

TEST_F(LayerFiles, EmptyLayerSavesAnEmptyArrayAndImportsNothing) {
  const GridLayer2D empty(layerConfig());
  const LayerFilePaths paths = writeLayerFiles(empty.toLogOddsRaster(), path("empty"));
  const LogOddsRaster back = readLayerFiles(paths.yaml);
  EXPECT_EQ(back.width, 0);
  EXPECT_EQ(back.height, 0);
  GridLayer2D layer(layerConfig());
  layer.setLogOdds({3, 4}, 1.0f);
  layer.importRaster(back);
  EXPECT_EQ(layer.knownCellCount(), 1u);
}

// What load_map does to a live layer: the file's known cells replace the layer's, the others
// stay, and every written tile is reported to the publishers.
TEST_F(LayerFiles, ImportReplacesOnlyItsKnownCellsAndIsLogged) {
  LogOddsRaster raster;
  raster.resolution = 0.05;
  raster.origin_cell = CellIndex(-40, 10);
  raster.width = 50;  // cells x -40..9, y 10..12: tiles x -2..0, y 0
  raster.height = 3;
  raster.data.assign(150, std::numeric_limits<float>::quiet_NaN());
  raster.data[0] = 2.5f;         // cell (-40, 10)
  raster.data[49 + 50] = -1.0f;  // cell (9, 11)

  GridLayer2D live(layerConfig());
  live.setLogOdds({-40, 10}, -3.0f);  // replaced
  live.setLogOdds({-39, 10}, 1.25f);  // unknown in the file: kept
  live.setLogOdds({200, 200}, 0.5f);  // outside the window: kept
  const std::uint64_t watched_from = live.version();
  live.importRaster(raster);

  EXPECT_EQ(*live.logOdds({-40, 10}), 2.5f);
  EXPECT_EQ(*live.logOdds({9, 11}), -1.0f);
  EXPECT_EQ(*live.logOdds({-39, 10}), 1.25f);
  EXPECT_EQ(*live.logOdds({200, 200}), 0.5f);
  EXPECT_EQ(live.knownCellCount(), 4u);
  const GridChanges changes = live.changesSince(watched_from);
  EXPECT_FALSE(changes.full_rebuild);
  std::set<std::pair<int, int>> tiles;
  for (const TileIndex& tile : changes.changed) tiles.insert({tile.x(), tile.y()});
  EXPECT_EQ(tiles, (std::set<std::pair<int, int>>{{-2, 0}, {0, 0}}));

  raster.resolution = 0.1;
  EXPECT_THROW(live.importRaster(raster), std::invalid_argument);
}

TEST_F(LayerFiles, DamagedFilesAreRefusedSayingWhatIsWrong) {
  GridLayer2D layer(layerConfig());
  fillRandom(&layer, 3, 50);
  const LayerFilePaths paths = writeLayerFiles(layer.toLogOddsRaster(), path("site"));
  const std::string yaml = readBytes(paths.yaml);
  const std::string npy = readBytes(paths.npy);
  ASSERT_NO_THROW(parseLayerFiles(yaml, npy));

  const auto replaced = [](std::string text, const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? text : text.replace(at, from.size(), to);
  };
  // The yaml with the line of `key` replaced.
  const auto withLine = [&](const std::string& key, const std::string& line) {
    const std::size_t at = yaml.find("\n" + key + ": ");
    EXPECT_NE(at, std::string::npos) << key;
    std::string text = yaml;
    return text.replace(at + 1, yaml.find('\n', at + 1) - at - 1, line);
  };
  const std::size_t data = npy.size() - 4 * layer.toLogOddsRaster().data.size();
  std::string infinite = npy;
  std::memcpy(&infinite[data + 4], &kInf, sizeof(kInf));
  // The array of another save with the same window: only the CRC-32 can tell.
  GridLayer2D other(layerConfig());
  fillRandom(&other, 3, 50);
  other.updateCell(layer.knownBounds()->min, 0.25f);
  const std::string other_npy = encodeNpy(other.toLogOddsRaster());
  ASSERT_EQ(other_npy.size(), npy.size());
  ASSERT_NE(other_npy, npy);
  // Without the optional CRC line, damage inside the array reaches the .npy checks.
  const std::string unchecked = withLine("log_odds_crc32", "# no CRC");
  ASSERT_NO_THROW(parseLayerFiles(unchecked, npy));

  const std::vector<std::tuple<std::string, std::string, std::string, std::string>> cases = {
      {"array of another save, same shape", yaml, other_npy, "different saves"},
      {"truncated array", yaml, npy.substr(0, npy.size() - 6), "CRC-32"},
      {"CRC not a number", withLine("log_odds_crc32", "log_odds_crc32: 0xfoo"), npy,
       "'log_odds_crc32'"},
      {"truncated array, no CRC", unchecked, npy.substr(0, npy.size() - 6), "data bytes"},
      {"truncated header", unchecked, npy.substr(0, 40), "truncated header"},
      {"not npy", unchecked, "P5 3 3 255", "not .npy"},
      {"float64", unchecked, replaced(npy, "<f4", "<f8"), "float32"},
      {"Fortran order", unchecked, replaced(npy, "False", "True "), "C order"},
      {"3D array", unchecked, replaced(npy, "'shape': (", "'shape': (1, "), "2D"},
      {"shape of another save", withLine("width", "width: 3"), npy, "different saves"},
      {"infinite cell", unchecked, infinite, "infinite"},
      {"no origin_cell", withLine("origin_cell", "cell: [0, 0]"), npy, "'origin_cell'"},
      {"origin edited", withLine("origin", "origin: [1000, 0]"), npy, "origin does not equal"},
      {"zero resolution", replaced(yaml, "resolution: 0.05", "resolution: 0"), npy, "resolution"},
      {"negative width", withLine("width", "width: -2"), npy, "negative"},
      {"beyond the coordinate range", withLine("origin_cell", "origin_cell: [1073741800, 0]"), npy,
       "coordinate range"},
      {"not YAML", "log_odds: [", npy, "YAML"},
  };
  for (const auto& [name, yaml_text, npy_bytes, expected] : cases) {
    try {
      parseLayerFiles(yaml_text, npy_bytes);
      ADD_FAILURE() << name << " was accepted";
    } catch (const std::runtime_error& error) {
      EXPECT_NE(std::string(error.what()).find(expected), std::string::npos)
          << name << ": " << error.what();
    }
  }

  // From files, the message names the file at fault.
  fs::remove(paths.npy);
  try {
    readLayerFiles(paths.yaml);
    ADD_FAILURE() << "a yaml without its array was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(paths.npy), std::string::npos) << error.what();
  }
  writeBytes(path("bad.laser.yaml"), "resolution: 0.05\n");
  try {
    readLayerFiles(path("bad.laser.yaml"));
    ADD_FAILURE() << "a yaml without log_odds was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(path("bad.laser.yaml")), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("'log_odds'"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace occupancy_fusion
