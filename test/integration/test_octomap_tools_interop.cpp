// The .bt files this package writes, read by OctoMap's own command-line tools (Debian's
// octomap-tools): bt2vrml must find exactly our occupied voxels at their centres, and
// convert_octree must read the file and write it again as .ot. Skipped (with the reason) only
// where the tools are not installed.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <tuple>

#include <unistd.h>

#include <gtest/gtest.h>

#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

bool toolInstalled(const std::string& tool) {
  return std::system(("command -v " + tool + " > /dev/null 2>&1").c_str()) == 0;
}

// Runs a command in `directory`; its exit status and what it printed.
std::pair<int, std::string> run(const fs::path& directory, const std::string& command) {
  const std::string line = "cd '" + directory.string() + "' && " + command + " 2>&1";
  std::string output;
  FILE* pipe = popen(line.c_str(), "r");
  if (!pipe) return {-1, ""};
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe)) output += buffer;
  const int status = pclose(pipe);
  return {status, output};
}

// Voxel centres rounded to 0.1 mm, comparable as a set.
using Key = std::tuple<long, long, long>;
Key keyOf(double x, double y, double z) {
  return {std::lround(x * 1e4), std::lround(y * 1e4), std::lround(z * 1e4)};
}

class OctomapToolsInterop : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ =
        fs::temp_directory_path() / ("octomap_tools_interop_" + std::to_string(::getpid()));
    fs::create_directories(directory_);
  }
  void TearDown() override { fs::remove_all(directory_); }

  // A one-voxel-thick wall (occupied; no eight occupied siblings, so OctoMap cannot prune them
  // into larger leaves) in front of a free box, at 0.05 m, across negative and positive
  // coordinates.
  std::set<Key> writeMap(const std::string& name) {
    VoxelMapConfig config;
    config.resolution = 0.05;
    VoxelMap map(config);
    std::set<Key> occupied;
    for (int y = -12; y < 15; ++y) {
      for (int z = -3; z < 20; ++z) {
        const VoxelIndex wall(7, y, z);
        map.updateVoxel(wall, 2.0f);
        const Eigen::Vector3d centre = map.centerOf(wall);
        occupied.insert(keyOf(centre.x(), centre.y(), centre.z()));
        for (int x = -8; x < 7; ++x) map.updateVoxel(VoxelIndex(x, y, z), -2.0f);
      }
    }
    writeBt(map, (directory_ / name).string());
    return occupied;
  }

  fs::path directory_;
};

TEST_F(OctomapToolsInterop, Bt2VrmlFindsExactlyOurOccupiedVoxels) {
  if (!toolInstalled("bt2vrml")) GTEST_SKIP() << "bt2vrml (Debian package octomap-tools) absent";
  const std::set<Key> occupied = writeMap("map.bt");
  const auto [status, output] = run(directory_, "bt2vrml map.bt");
  ASSERT_EQ(status, 0) << output;
  // bt2vrml: "Finished writing <n> voxels to map.bt.wrl", then one box per occupied leaf.
  std::smatch finished;
  ASSERT_TRUE(std::regex_search(output, finished, std::regex("writing (\\d+) voxels"))) << output;
  EXPECT_EQ(std::stoul(finished[1]), occupied.size());
  std::ifstream vrml(directory_ / "map.bt.wrl");
  ASSERT_TRUE(vrml.good());
  std::set<Key> read;
  std::string line;
  const std::regex translation("translation\\s+(\\S+)\\s+(\\S+)\\s+(\\S+)");
  std::smatch match;
  while (std::getline(vrml, line)) {
    if (std::regex_search(line, match, translation)) {
      read.insert(keyOf(std::stod(match[1]), std::stod(match[2]), std::stod(match[3])));
    }
  }
  EXPECT_EQ(read.size(), occupied.size());
  EXPECT_TRUE(read == occupied) << "bt2vrml's voxel centres differ from the map's";
}

TEST_F(OctomapToolsInterop, ConvertOctreeReadsAndRewritesTheFile) {
  if (!toolInstalled("convert_octree")) {
    GTEST_SKIP() << "convert_octree (Debian package octomap-tools) absent";
  }
  writeMap("map.bt");
  const auto [status, output] = run(directory_, "convert_octree map.bt map.ot");
  ASSERT_EQ(status, 0) << output;
  EXPECT_EQ(output.find("ERROR"), std::string::npos) << output;
  ASSERT_TRUE(fs::exists(directory_ / "map.ot")) << output;
  // The .ot written by OctoMap from our .bt carries an OcTree of our resolution.
  std::ifstream ot(directory_ / "map.ot");
  std::stringstream text;
  text << ot.rdbuf();
  EXPECT_NE(text.str().find("id OcTree"), std::string::npos);
  EXPECT_NE(text.str().find("res 0.05"), std::string::npos);
}

}  // namespace
}  // namespace occupancy_fusion
