#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>
#include <opencv2/imgcodecs.hpp>

#include "../../common/test_folder.h"
#include "occupancy_fusion/map/map_files.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

using MapFiles = TestFolder;

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

float floatAt(const std::string& bytes, std::size_t offset) {
  const auto* b = reinterpret_cast<const unsigned char*>(bytes.data() + offset);
  const std::uint32_t bits = b[0] | (b[1] << 8) | (b[2] << 16) | (std::uint32_t{b[3]} << 24);
  float value;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

VoxelMapConfig mapConfig(double resolution = 0.1) {
  VoxelMapConfig config;
  config.resolution = resolution;
  return config;
}

void fillRandom(VoxelMap* map, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> coordinate(-20, 20);
  std::uniform_real_distribution<float> delta(-2.5f, 4.0f);
  std::vector<VoxelUpdate> updates;
  for (int i = 0; i < 2000; ++i) {
    updates.push_back({{coordinate(rng), coordinate(rng), coordinate(rng) / 4}, delta(rng)});
  }
  map->applyUpdates(updates);
}

// A 4 x 3 raster with known values at known places: row 0 is the lowest y.
OccupancyRaster smallRaster() {
  OccupancyRaster raster;
  raster.resolution = 0.05;
  raster.origin_x = -1.25;
  raster.origin_y = 2.5;
  raster.width = 4;
  raster.height = 3;
  raster.data.assign(12, OccupancyRaster::kUnknown);
  raster.data[0] = OccupancyRaster::kOccupied;          // (0, 0): bottom left
  raster.data[1] = OccupancyRaster::kFree;              // (1, 0)
  raster.data[3 + 4 * 2] = OccupancyRaster::kFree;      // (3, 2): top right
  raster.data[2 + 4 * 1] = OccupancyRaster::kOccupied;  // (2, 1)
  return raster;
}

TEST_F(MapFiles, BtIsReadBackByLiboctomapWithTheSameLabels) {
  VoxelMap map(mapConfig(0.1));
  fillRandom(&map, 11);
  EXPECT_EQ(writeBt(map, path("map.bt")), 0u);
  octomap::OcTree tree(0.5);
  ASSERT_TRUE(tree.readBinary(path("map.bt")));
  EXPECT_DOUBLE_EQ(tree.getResolution(), 0.1);
  std::size_t covered = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const std::size_t side = std::size_t{1} << (tree.getTreeDepth() - it.getDepth());
    covered += side * side * side;
  }
  EXPECT_EQ(covered, map.knownVoxelCount());
  map.forEachKnownVoxel([&](const VoxelIndex& index, float) {
    const Eigen::Vector3d c = map.centerOf(index);
    const octomap::OcTreeNode* node = tree.search(c.x(), c.y(), c.z());
    ASSERT_NE(node, nullptr);
    EXPECT_EQ(tree.isNodeOccupied(node), map.occupancy(index) == Occupancy::kOccupied);
  });

  // Our reader: labels as log-odds at the clamping bounds.
  const std::unique_ptr<VoxelMap> back = readOctomapFile(path("map.bt"), mapConfig(0.7));
  EXPECT_DOUBLE_EQ(back->resolution(), 0.1);
  EXPECT_EQ(back->knownVoxelCount(), map.knownVoxelCount());
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    const bool occupied = map.occupancy(index) == Occupancy::kOccupied;
    ASSERT_TRUE(back->logOdds(index).has_value());
    EXPECT_FLOAT_EQ(*back->logOdds(index), occupied ? map.maxLogOdds() : map.minLogOdds())
        << log_odds;
  });
}

TEST_F(MapFiles, OtKeepsEveryLogOdds) {
  VoxelMap map(mapConfig(0.05));
  fillRandom(&map, 12);
  writeOt(map, path("map.ot"));
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(path("map.ot")));
  ASSERT_NE(read, nullptr);
  auto* tree = dynamic_cast<octomap::OcTree*>(read.get());
  ASSERT_NE(tree, nullptr);
  EXPECT_DOUBLE_EQ(tree->getResolution(), 0.05);
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    const Eigen::Vector3d c = map.centerOf(index);
    const octomap::OcTreeNode* node = tree->search(c.x(), c.y(), c.z());
    ASSERT_NE(node, nullptr);
    EXPECT_FLOAT_EQ(node->getLogOdds(), log_odds);
  });
  // Content decides the kind, not the name.
  fs::rename(path("map.ot"), path("map.bt"));
  const std::unique_ptr<VoxelMap> back = readOctomapFile(path("map.bt"), mapConfig());
  EXPECT_EQ(back->knownVoxelCount(), map.knownVoxelCount());
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    ASSERT_TRUE(back->logOdds(index).has_value());
    EXPECT_FLOAT_EQ(*back->logOdds(index), log_odds);
  });
}

TEST_F(MapFiles, ErrorsNameThePath) {
  { std::ofstream(path("garbage.bt")) << "not a tree\n"; }
  try {
    readOctomapFile(path("garbage.bt"), mapConfig());
    FAIL() << "garbage accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(path("garbage.bt")), std::string::npos);
  }
  VoxelMap map(mapConfig());
  map.updateVoxel({0, 0, 0}, 1.0f);
  const std::string unwritable = path("missing_folder/map.bt");
  try {
    writeBt(map, unwritable);
    FAIL() << "wrote into a missing folder";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(unwritable), std::string::npos);
  }
  EXPECT_THROW(readOctomapFile(path("absent.ot"), mapConfig()), std::runtime_error);
}

TEST_F(MapFiles, MapServerPgmAndYaml) {
  const OccupancyRaster raster = smallRaster();
  writeMapServerFiles(raster, path("floor"));
  writeMapServerFiles(raster, path("floor"));  // overwriting is fine

  const std::string pgm = readAll(path("floor.pgm"));
  std::istringstream header(pgm);
  std::string magic, token;
  header >> magic;
  EXPECT_EQ(magic, "P5");
  std::vector<int> numbers;
  while (numbers.size() < 3 && header >> token) {
    if (token[0] == '#') {
      std::getline(header, token);
      continue;
    }
    numbers.push_back(std::stoi(token));
  }
  ASSERT_EQ(numbers, (std::vector<int>{4, 3, 255}));
  header.get();  // the single whitespace before the pixels
  const std::size_t offset = static_cast<std::size_t>(header.tellg());
  ASSERT_EQ(pgm.size(), offset + 12);
  auto pixel = [&](int x, int y) {  // map cell (x, y): pgm row height - 1 - y
    return static_cast<unsigned char>(pgm[offset + x + 4 * (2 - y)]);
  };
  EXPECT_EQ(pixel(0, 0), 0);    // occupied, bottom row of the map = last pgm row
  EXPECT_EQ(pixel(1, 0), 254);  // free
  EXPECT_EQ(pixel(3, 2), 254);  // top right = first pgm row
  EXPECT_EQ(static_cast<unsigned char>(pgm[offset + 3]), 254);
  EXPECT_EQ(pixel(2, 1), 0);
  EXPECT_EQ(pixel(0, 2), 205);  // unknown
  EXPECT_EQ(pixel(3, 0), 205);

  const YAML::Node yaml = YAML::LoadFile(path("floor.yaml"));
  EXPECT_EQ(yaml["image"].as<std::string>(), "floor.pgm");
  EXPECT_DOUBLE_EQ(yaml["resolution"].as<double>(), 0.05);
  ASSERT_EQ(yaml["origin"].size(), 3u);
  EXPECT_DOUBLE_EQ(yaml["origin"][0].as<double>(), -1.25);
  EXPECT_DOUBLE_EQ(yaml["origin"][1].as<double>(), 2.5);
  EXPECT_DOUBLE_EQ(yaml["origin"][2].as<double>(), 0.0);
  EXPECT_EQ(yaml["negate"].as<int>(), 0);
  EXPECT_DOUBLE_EQ(yaml["occupied_thresh"].as<double>(), 0.65);
  EXPECT_DOUBLE_EQ(yaml["free_thresh"].as<double>(), 0.196);

  EXPECT_THROW(writeMapServerFiles(OccupancyRaster(), path("empty")), std::invalid_argument);
}

TEST_F(MapFiles, NpyHeaderAndValuesByteWise) {
  LogOddsRaster raster;
  raster.resolution = 0.05;
  raster.width = 3;
  raster.height = 2;
  raster.data = {1.5f, std::numeric_limits<float>::quiet_NaN(), -2.0f, 0.0f, 3.25f, -0.125f};
  writeNpy(raster, path("layer.npy"));
  const std::string bytes = readAll(path("layer.npy"));
  ASSERT_GE(bytes.size(), 10u);
  EXPECT_EQ(bytes.substr(0, 6), std::string("\x93NUMPY"));
  EXPECT_EQ(bytes[6], 1);  // version 1.0
  EXPECT_EQ(bytes[7], 0);
  const std::size_t header_length =
      static_cast<unsigned char>(bytes[8]) | (static_cast<unsigned char>(bytes[9]) << 8);
  EXPECT_EQ((10 + header_length) % 64, 0u);
  const std::string header = bytes.substr(10, header_length);
  EXPECT_EQ(header.rfind("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }", 0), 0u)
      << header;
  EXPECT_EQ(header.back(), '\n');
  ASSERT_EQ(bytes.size(), 10 + header_length + 6 * 4);
  const std::size_t data = 10 + header_length;
  EXPECT_EQ(floatAt(bytes, data + 0), 1.5f);
  EXPECT_TRUE(std::isnan(floatAt(bytes, data + 4)));
  EXPECT_EQ(floatAt(bytes, data + 8), -2.0f);
  EXPECT_EQ(floatAt(bytes, data + 12), 0.0f);  // row 1 (the higher y) starts here
  EXPECT_EQ(floatAt(bytes, data + 16), 3.25f);
  EXPECT_EQ(floatAt(bytes, data + 20), -0.125f);
  // Exact little-endian bytes of 1.5f = 0x3fc00000.
  EXPECT_EQ(bytes.substr(data, 4), std::string("\x00\x00\xc0\x3f", 4));
}

// Parses a PCD file written by writePcd; returns (x, y, z) -> probability.
std::map<std::tuple<float, float, float>, float> readPcd(const std::string& path,
                                                         std::string* data_kind) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::size_t points = 0;
  std::map<std::string, std::string> fields;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const std::size_t space = line.find(' ');
    fields[line.substr(0, space)] = line.substr(space + 1);
    if (line.rfind("DATA", 0) == 0) break;
  }
  EXPECT_EQ(fields["VERSION"], "0.7");
  EXPECT_EQ(fields["FIELDS"], "x y z probability");
  EXPECT_EQ(fields["SIZE"], "4 4 4 4");
  EXPECT_EQ(fields["TYPE"], "F F F F");
  EXPECT_EQ(fields["COUNT"], "1 1 1 1");
  EXPECT_EQ(fields["HEIGHT"], "1");
  EXPECT_EQ(fields["WIDTH"], fields["POINTS"]);
  points = std::stoul(fields["POINTS"]);
  *data_kind = fields["DATA"];
  std::map<std::tuple<float, float, float>, float> result;
  for (std::size_t i = 0; i < points; ++i) {
    float v[4];
    if (*data_kind == "binary") {
      char raw[16];
      in.read(raw, 16);
      const std::string bytes(raw, 16);
      for (int k = 0; k < 4; ++k) v[k] = floatAt(bytes, 4 * k);
    } else {
      in >> v[0] >> v[1] >> v[2] >> v[3];
    }
    EXPECT_TRUE(in.good());
    result[{v[0], v[1], v[2]}] = v[3];
  }
  in.peek();
  EXPECT_TRUE(in.eof() || *data_kind == "ascii");
  return result;
}

TEST_F(MapFiles, PcdBinaryAndAsciiParseBack) {
  VoxelMap map(mapConfig(0.1));
  fillRandom(&map, 13);
  for (const PcdEncoding encoding : {PcdEncoding::kBinary, PcdEncoding::kAscii}) {
    writePcd(map, path("map.pcd"), encoding);
    std::string kind;
    const auto points = readPcd(path("map.pcd"), &kind);
    EXPECT_EQ(kind, encoding == PcdEncoding::kBinary ? "binary" : "ascii");
    EXPECT_EQ(points.size(), map.knownVoxelCount());
    map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
      const Eigen::Vector3f c = map.centerOf(index).cast<float>();
      const auto found = points.find({c.x(), c.y(), c.z()});
      ASSERT_NE(found, points.end()) << index.transpose();
      EXPECT_FLOAT_EQ(found->second, 1.0f / (1.0f + std::exp(-log_odds)));
    });
  }
}

// The same voxels written in another order (the mappers' threads create blocks in any order)
// give the same file, byte for byte, with the points in voxel order.
TEST_F(MapFiles, PcdOfTheSameMapIsTheSameFileWhateverOrderItsBlocksWereMadeIn) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> coordinate(-60, 60);
  std::vector<VoxelUpdate> updates;
  for (int i = 0; i < 3000; ++i) {
    updates.push_back({{coordinate(rng), coordinate(rng), coordinate(rng) / 8}, 1.5f});
  }
  VoxelMap forward(mapConfig(0.1)), backward(mapConfig(0.1));
  for (const VoxelUpdate& update : updates) forward.applyUpdates({update});
  for (auto it = updates.rbegin(); it != updates.rend(); ++it) backward.applyUpdates({*it});
  writePcd(forward, path("forward.pcd"), PcdEncoding::kAscii);
  writePcd(backward, path("backward.pcd"), PcdEncoding::kAscii);
  const std::string text = readAll(path("forward.pcd"));
  EXPECT_EQ(text, readAll(path("backward.pcd")));
  // The points follow z, then y, then x.
  std::istringstream lines(text.substr(text.find("DATA ascii\n") + 11));
  std::tuple<float, float, float> previous{-1e9f, -1e9f, -1e9f};
  float x, y, z, probability;
  std::size_t points = 0;
  while (lines >> x >> y >> z >> probability) {
    const std::tuple<float, float, float> current{z, y, x};
    EXPECT_LT(previous, current) << x << " " << y << " " << z;
    previous = current;
    ++points;
  }
  EXPECT_EQ(points, forward.knownVoxelCount());
}

TEST_F(MapFiles, PngIsYUpGreyWhiteBlackAndScaled) {
  const OccupancyRaster raster = smallRaster();
  writePng(raster, path("floor.png"), 3);
  const cv::Mat image = cv::imread(path("floor.png"), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(image.empty());
  ASSERT_EQ(image.type(), CV_8UC1);
  ASSERT_EQ(image.cols, 12);
  ASSERT_EQ(image.rows, 9);
  auto pixel = [&](int x, int y) {  // the centre pixel of cell (x, y)
    return image.at<std::uint8_t>((2 - y) * 3 + 1, x * 3 + 1);
  };
  EXPECT_EQ(pixel(0, 0), 0);
  EXPECT_EQ(image.at<std::uint8_t>(8, 0), 0);  // bottom-left pixel: occupied (0, 0)
  EXPECT_EQ(pixel(1, 0), 255);
  EXPECT_EQ(pixel(3, 2), 255);
  EXPECT_EQ(image.at<std::uint8_t>(0, 11), 255);  // top-right pixel: free (3, 2)
  EXPECT_EQ(pixel(2, 1), 0);
  EXPECT_EQ(pixel(0, 2), 128);
  EXPECT_THROW(writePng(raster, path("bad.png"), 0), std::invalid_argument);
}

}  // namespace
}  // namespace occupancy_fusion
