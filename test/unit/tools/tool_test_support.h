// Helpers of the tools' end-to-end tests: a simulated recording to map, running a built tool, and
// independent readers of the files it writes (PGM, NPY, OctoMap leaves as voxel centres).
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <Eigen/Core>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <octomap/OcTree.h>
#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "occupancy_fusion/tools/simulated_recording.h"

namespace occupancy_fusion {
namespace test_support {

namespace fs = std::filesystem;

// Per topic of a bag, its connection header's "latching" ("" where absent): what rosbag play
// reads to latch a topic.
inline std::map<std::string, std::string> latchingByTopic(const fs::path& bag_path) {
  rosbag::Bag bag(bag_path.string(), rosbag::bagmode::Read);
  rosbag::View view(bag);
  std::map<std::string, std::string> latching;
  for (const rosbag::ConnectionInfo* connection : view.getConnections()) {
    const auto found = connection->header->find("latching");
    latching[connection->topic] = found == connection->header->end() ? "" : found->second;
  }
  return latching;
}

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline std::string readText(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

// Runs a built tool with the arguments (already shell-quoted where needed).
inline RunResult runTool(const std::string& tool, const std::string& arguments,
                         const fs::path& dir) {
  const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string command =
      "'" + tool + "' " + arguments + " > '" + out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(command.c_str());
  RunResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = readText(out);
  result.err = readText(err);
  return result;
}

inline fs::path makeTempDir() {
  std::string pattern = (fs::temp_directory_path() / "offline_mapper_test_XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  return pattern;
}

// A fresh folder holding the mapper's parameters as mapper.yaml and room.bag: `frames` frames of
// the room scene at 4 Hz from `sensors`.
inline fs::path makeRoomRecordingDir(const std::string& mapper_yaml, int frames,
                                     const std::vector<std::unique_ptr<SimulatedSensor>>& sensors) {
  ros::Time::init();
  const fs::path dir = makeTempDir();
  std::ofstream(dir / "mapper.yaml") << mapper_yaml;
  SimulatedRecordingConfig config;
  config.scene = "room";
  config.frames = frames;
  config.rate_hz = 4.0;
  writeSimulatedRecording(config, sensors, (dir / "room.bag").string());
  return dir;
}

struct Pgm {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  // row 0 = top of the map (highest y)
};

inline Pgm readPgm(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::string magic;
  file >> magic;
  EXPECT_EQ(magic, "P5");
  auto nextNumber = [&file] {
    file >> std::ws;
    while (file.peek() == '#') {
      std::string comment;
      std::getline(file, comment);
      file >> std::ws;
    }
    int value = 0;
    file >> value;
    return value;
  };
  Pgm pgm;
  pgm.width = nextNumber();
  pgm.height = nextNumber();
  EXPECT_EQ(nextNumber(), 255);
  file.get();  // the single whitespace before the raster
  pgm.pixels.resize(static_cast<std::size_t>(pgm.width) * pgm.height);
  file.read(reinterpret_cast<char*>(pgm.pixels.data()), pgm.pixels.size());
  EXPECT_TRUE(file.good());
  return pgm;
}

struct Npy {
  int rows = 0;
  int cols = 0;
  std::vector<float> values;  // row 0 = lowest y
};

inline Npy readNpy(const fs::path& path) {
  const std::string bytes = readText(path);
  EXPECT_EQ(bytes.substr(0, 6), "\x93NUMPY");
  const std::size_t header_length =
      static_cast<unsigned char>(bytes[8]) | (static_cast<unsigned char>(bytes[9]) << 8);
  const std::string header = bytes.substr(10, header_length);
  EXPECT_NE(header.find("'descr': '<f4'"), std::string::npos) << header;
  EXPECT_NE(header.find("'fortran_order': False"), std::string::npos) << header;
  Npy npy;
  const std::size_t shape = header.find("'shape': (");
  EXPECT_NE(shape, std::string::npos);
  std::sscanf(header.c_str() + shape, "'shape': (%d, %d)", &npy.rows, &npy.cols);
  npy.values.resize(static_cast<std::size_t>(npy.rows) * npy.cols);
  EXPECT_EQ(bytes.size(), 10 + header_length + npy.values.size() * sizeof(float));
  std::memcpy(npy.values.data(), bytes.data() + 10 + header_length,
              npy.values.size() * sizeof(float));
  return npy;
}

// Centres of the voxels a leaf covers (a pruned leaf covers several).
inline std::vector<Eigen::Vector3d> voxelCentres(const octomap::OcTree::leaf_iterator& leaf,
                                                 double resolution) {
  const double size = leaf.getSize();
  const int per_axis = static_cast<int>(std::lround(size / resolution));
  const octomap::point3d centre = leaf.getCoordinate();
  const Eigen::Vector3d corner =
      Eigen::Vector3d(centre.x(), centre.y(), centre.z()) - Eigen::Vector3d::Constant(size / 2.0);
  std::vector<Eigen::Vector3d> centres;
  for (int i = 0; i < per_axis; ++i)
    for (int j = 0; j < per_axis; ++j)
      for (int k = 0; k < per_axis; ++k)
        centres.push_back(corner +
                          (Eigen::Vector3d(i, j, k) + Eigen::Vector3d::Constant(0.5)) * resolution);
  return centres;
}

}  // namespace test_support
}  // namespace occupancy_fusion
