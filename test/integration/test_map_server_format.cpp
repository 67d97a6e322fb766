// The .pgm + .yaml this package writes, read back the way map_server reads a map (ROS wiki
// map_server, "Map format"), by a reader written here from that description and not from our
// writer: YAML keys image (relative to the YAML's folder), resolution, origin [x, y, yaw],
// occupied_thresh, free_thresh, negate, optional mode; the image a binary PGM (P5, 8 bit) whose
// first row is the top of the map (highest y); origin the pose of the lower-left pixel; and the
// trinary rule p = (255 - value) / 255 (value / 255 with negate 1), occupied if
// p > occupied_thresh, free if p < free_thresh, else unknown. Debian ships no map_server package,
// so its loader cannot run here.
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

// nav_msgs/OccupancyGrid as map_server fills it: data[x + width * y], y = 0 the lowest row, cell
// (x, y)'s lower-left corner at origin + (x, y) * resolution.
struct LoadedMap {
  double resolution = 0.0;
  double origin_x = 0.0;
  double origin_y = 0.0;
  double origin_yaw = 0.0;
  int width = 0;
  int height = 0;
  std::vector<std::int8_t> data;  // 100 occupied, 0 free, -1 unknown

  std::int8_t at(int x, int y) const { return data[static_cast<std::size_t>(x + width * y)]; }
  // The cell holding a map-frame point (yaw 0).
  std::int8_t atPoint(double x, double y) const {
    const int column = static_cast<int>(std::floor((x - origin_x) / resolution));
    const int row = static_cast<int>(std::floor((y - origin_y) / resolution));
    if (column < 0 || row < 0 || column >= width || row >= height) {
      throw std::out_of_range("point outside the loaded map");
    }
    return at(column, row);
  }
};

// Netpbm header fields are separated by whitespace; '#' starts a comment to the end of the line.
int readHeaderNumber(const std::string& file, std::size_t* offset) {
  while (*offset < file.size()) {
    const char c = file[*offset];
    if (c == '#') {
      while (*offset < file.size() && file[*offset] != '\n') ++*offset;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++*offset;
    } else {
      break;
    }
  }
  const std::size_t start = *offset;
  while (*offset < file.size() && std::isdigit(static_cast<unsigned char>(file[*offset]))) {
    ++*offset;
  }
  if (start == *offset) throw std::runtime_error("PGM header: number expected");
  return std::stoi(file.substr(start, *offset - start));
}

struct Pgm {
  int width = 0;
  int height = 0;
  int max_value = 0;
  std::vector<std::uint8_t> pixels;  // row-major, row 0 at the top
};

Pgm readPgm(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path.string());
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (file.compare(0, 2, "P5") != 0) throw std::runtime_error("not a binary PGM (P5)");
  std::size_t offset = 2;
  Pgm pgm;
  pgm.width = readHeaderNumber(file, &offset);
  pgm.height = readHeaderNumber(file, &offset);
  pgm.max_value = readHeaderNumber(file, &offset);
  // Exactly one whitespace character separates maxval from the raster.
  if (offset >= file.size() || !std::isspace(static_cast<unsigned char>(file[offset]))) {
    throw std::runtime_error("PGM header: whitespace expected after maxval");
  }
  ++offset;
  const std::size_t size = static_cast<std::size_t>(pgm.width) * pgm.height;
  if (file.size() - offset != size) throw std::runtime_error("PGM raster size mismatch");
  pgm.pixels.assign(file.begin() + static_cast<std::ptrdiff_t>(offset), file.end());
  return pgm;
}

LoadedMap loadLikeMapServer(const fs::path& yaml_path) {
  const YAML::Node yaml = YAML::LoadFile(yaml_path.string());
  LoadedMap map;
  map.resolution = yaml["resolution"].as<double>();
  const YAML::Node origin = yaml["origin"];
  if (!origin.IsSequence() || origin.size() != 3) throw std::runtime_error("origin: [x, y, yaw]");
  map.origin_x = origin[0].as<double>();
  map.origin_y = origin[1].as<double>();
  map.origin_yaw = origin[2].as<double>();
  const bool negate = yaml["negate"].as<int>() != 0;
  const double occupied_thresh = yaml["occupied_thresh"].as<double>();
  const double free_thresh = yaml["free_thresh"].as<double>();
  if (yaml["mode"] && yaml["mode"].as<std::string>() != "trinary") {
    throw std::runtime_error("only trinary mode is read here");
  }
  fs::path image = yaml["image"].as<std::string>();
  if (image.is_relative()) image = yaml_path.parent_path() / image;

  const Pgm pgm = readPgm(image);
  if (pgm.max_value != 255) throw std::runtime_error("8-bit PGM expected");
  map.width = pgm.width;
  map.height = pgm.height;
  map.data.assign(pgm.pixels.size(), -1);
  for (int row = 0; row < pgm.height; ++row) {
    for (int column = 0; column < pgm.width; ++column) {
      const double value = pgm.pixels[static_cast<std::size_t>(column + pgm.width * row)];
      const double p = negate ? value / 255.0 : (255.0 - value) / 255.0;
      std::int8_t cell = -1;
      if (p > occupied_thresh) {
        cell = 100;
      } else if (p < free_thresh) {
        cell = 0;
      }
      // Image row 0 is the top of the map: grid row height - 1.
      map.data[static_cast<std::size_t>(column + map.width * (map.height - 1 - row))] = cell;
    }
  }
  return map;
}

constexpr double kResolution = 0.1;  // m, the test map's cells

class MapServerFormat : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = fs::temp_directory_path() / ("map_server_format_" + std::to_string(::getpid()));
    fs::create_directories(directory_ / "maps");
  }
  void TearDown() override { fs::remove_all(directory_); }

  // Voxels (z index 0) over cells x -6..8, y -3..4: free, except three occupied cells at
  // asymmetric places and two never-observed holes; and an occupied cell of the laser layer at
  // (9, -3), which widens the map by one column that is otherwise unknown. Cell (i, j) covers
  // [i, i + 1) x [j, j + 1) times the resolution.
  void buildMap() {
    for (int x = -6; x <= 8; ++x) {
      for (int y = -3; y <= 4; ++y) {
        if ((x == 0 && y == 0) || (x == -5 && y == -3)) continue;  // unknown holes
        const bool occupied = (x == -6 && y == 4) || (x == 7 && y == -3) || (x == 2 && y == 1);
        voxels_.updateVoxel(VoxelIndex(x, y, 0), occupied ? 2.0f : -2.0f);
      }
    }
    layer_.updateCell(CellIndex(9, -3), 2.0f);
  }

  static VoxelMapConfig voxelConfig() {
    VoxelMapConfig config;
    config.resolution = kResolution;
    return config;
  }
  static GridLayer2DConfig layerConfig() {
    GridLayer2DConfig config;
    config.resolution = kResolution;
    return config;
  }

  fs::path directory_;
  VoxelMap voxels_{voxelConfig()};
  GridLayer2D layer_{layerConfig()};
};

// The centre of cell (x, y) of the designed map.
double centre(int index) { return (index + 0.5) * kResolution; }

TEST_F(MapServerFormat, LoadsAsTheSameGridCellByCell) {
  buildMap();
  FusedGridView view;
  const OccupancyRaster raster = view.update(voxels_, &layer_);
  writeMapServerFiles(raster, (directory_ / "maps" / "floor").string());

  // Loaded from another working directory: the image path is resolved against the YAML's folder.
  const LoadedMap loaded = loadLikeMapServer(directory_ / "maps" / "floor.yaml");
  ASSERT_EQ(loaded.width, raster.width);
  ASSERT_EQ(loaded.height, raster.height);
  EXPECT_DOUBLE_EQ(loaded.resolution, raster.resolution);
  EXPECT_DOUBLE_EQ(loaded.origin_x, raster.origin_x);
  EXPECT_DOUBLE_EQ(loaded.origin_y, raster.origin_y);
  EXPECT_EQ(loaded.origin_yaw, 0.0);
  const YAML::Node yaml = YAML::LoadFile((directory_ / "maps" / "floor.yaml").string());
  EXPECT_LE(0.0, yaml["free_thresh"].as<double>());  // thresholds map_server accepts
  EXPECT_LT(yaml["free_thresh"].as<double>(), yaml["occupied_thresh"].as<double>());
  EXPECT_LE(yaml["occupied_thresh"].as<double>(), 1.0);
  int mismatches = 0;
  for (int y = 0; y < raster.height; ++y) {
    for (int x = 0; x < raster.width; ++x) {
      if (loaded.at(x, y) != raster.at(x, y)) {
        ADD_FAILURE() << "cell (" << x << ", " << y << "): map_server reads "
                      << int(loaded.at(x, y)) << ", the grid holds " << int(raster.at(x, y));
        if (++mismatches > 5) return;
      }
    }
  }
}

TEST_F(MapServerFormat, PlacesEachCellAtItsMapFramePosition) {
  buildMap();
  FusedGridView view;
  writeMapServerFiles(view.update(voxels_, &layer_), (directory_ / "maps" / "floor").string());
  const LoadedMap loaded = loadLikeMapServer(directory_ / "maps" / "floor.yaml");

  // The known area is cells x -6..9, y -3..4: 16 x 8 cells whose lower-left corner is the origin.
  EXPECT_EQ(loaded.width, 16);
  EXPECT_EQ(loaded.height, 8);
  EXPECT_NEAR(loaded.origin_x, -0.6, 1e-9);
  EXPECT_NEAR(loaded.origin_y, -0.3, 1e-9);
  EXPECT_NEAR(loaded.resolution, kResolution, 1e-12);

  // Occupied cells: top-left corner, bottom right, an inner one, and the laser layer's.
  EXPECT_EQ(loaded.atPoint(centre(-6), centre(4)), 100);
  EXPECT_EQ(loaded.atPoint(centre(7), centre(-3)), 100);
  EXPECT_EQ(loaded.atPoint(centre(2), centre(1)), 100);
  EXPECT_EQ(loaded.atPoint(centre(9), centre(-3)), 100);
  // Their mirror images (a flipped axis) and neighbours (an origin off by one cell) are free.
  EXPECT_EQ(loaded.atPoint(centre(-6), centre(-3)), 0);
  EXPECT_EQ(loaded.atPoint(centre(8), centre(4)), 0);
  EXPECT_EQ(loaded.atPoint(centre(-6), centre(3)), 0);
  EXPECT_EQ(loaded.atPoint(centre(-5), centre(4)), 0);
  EXPECT_EQ(loaded.atPoint(centre(3), centre(1)), 0);
  EXPECT_EQ(loaded.atPoint(centre(2), centre(2)), 0);
  // Never observed: the two holes and the rest of the laser layer's column.
  EXPECT_EQ(loaded.atPoint(centre(0), centre(0)), -1);
  EXPECT_EQ(loaded.atPoint(centre(-5), centre(-3)), -1);
  EXPECT_EQ(loaded.atPoint(centre(9), centre(-2)), -1);
  EXPECT_EQ(loaded.atPoint(centre(9), centre(4)), -1);

  // Every cell agrees with the voxel map or the layer at the same map-frame point.
  int occupied = 0;
  int free = 0;
  int unknown = 0;
  for (int y = 0; y < loaded.height; ++y) {
    for (int x = 0; x < loaded.width; ++x) {
      const Eigen::Vector2d point(loaded.origin_x + (x + 0.5) * kResolution,
                                  loaded.origin_y + (y + 0.5) * kResolution);
      const Occupancy voxel = voxels_.occupancyAt({point.x(), point.y(), 0.5 * kResolution});
      const Occupancy cell = layer_.occupancyAt(point);
      std::int8_t expected = -1;
      if (voxel == Occupancy::kOccupied || cell == Occupancy::kOccupied) {
        expected = 100;
      } else if (voxel == Occupancy::kFree || cell == Occupancy::kFree) {
        expected = 0;
      }
      EXPECT_EQ(loaded.at(x, y), expected) << "at (" << point.x() << ", " << point.y() << ")";
      occupied += loaded.at(x, y) == 100;
      free += loaded.at(x, y) == 0;
      unknown += loaded.at(x, y) == -1;
    }
  }
  EXPECT_EQ(occupied, 4);
  EXPECT_EQ(unknown, 2 + 7);
  EXPECT_EQ(free, 16 * 8 - 4 - 9);
}

}  // namespace
}  // namespace occupancy_fusion
