// Nothing lost, end to end in a nodelet manager (map_persistence.test): the test node loads and
// unloads MapServers through the manager's services, as `nodelet load` / `nodelet unload` do.
//  1. MapServer A maps with the running PointCloudMapper and LaserMapper; ~save_map reports
//     failures clearly and keeps the previous files; unloading A saves the map (save_on_shutdown)
//     while the mappers still write.
//  2. With every user gone (map freed), MapServer B starts with load_map: the published cloud is
//     exactly the saved file's occupied voxels right after start, the published projected_map is
//     exactly the fused view of the saved voxels and laser layer (computed here from the files),
//     and B saves a byte-identical .ot and laser layer.
//  3. A bad load_map path stops the MapServer from loading.
//  4. Mapping resumes on B's map: new frames update the loaded voxels, which stay.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <nav_msgs/OccupancyGrid.h>
#include <nodelet/NodeletLoad.h>
#include <nodelet/NodeletUnload.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/SetBool.h>

#include "occupancy_fusion/SaveMap.h"
#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/layer_files.h"
#include "occupancy_fusion/map/map_files.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

constexpr double kResolution = 0.05;  // config/point_cloud_mapper.yaml

void setMapServerParameters(const std::string& name, const std::string& load_map,
                            const std::string& save_on_shutdown, const std::string& save_prefix) {
  ros::param::set(name + "/map_name", std::string("map"));
  ros::param::set(name + "/resolution", kResolution);
  ros::param::set(name + "/publish_rate", 5.0);
  ros::param::set(name + "/load_map", load_map);
  ros::param::set(name + "/save_on_shutdown", save_on_shutdown);
  ros::param::set(name + "/save_prefix", save_prefix);
}

SaveMap save(const std::string& service, const std::string& prefix) {
  SaveMap request;
  request.request.prefix = prefix;
  EXPECT_TRUE(ros::service::call(service, request)) << service;
  return request;
}

// An .ot file as liboctomap reads it (OcTree's file constructor reads .bt only).
std::unique_ptr<octomap::OcTree> readOt(const std::string& path) {
  std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(path));
  auto* octree = dynamic_cast<octomap::OcTree*>(tree.get());
  if (octree == nullptr) return nullptr;
  tree.release();
  return std::unique_ptr<octomap::OcTree>(octree);
}

// Occupied voxels of an OctoMap file (pruned leaves counted for every voxel they cover).
double occupiedVoxels(const octomap::OcTree& tree) {
  double count = 0.0;
  for (auto leaf = tree.begin_leafs(); leaf != tree.end_leafs(); ++leaf) {
    if (tree.isNodeOccupied(*leaf)) count += std::pow(leaf.getSize() / tree.getResolution(), 3);
  }
  return count;
}

TEST(MapPersistence, SaveOnShutdownRestartWithLoadMapAndResume) {
  const TemporaryFolder temporary;
  const fs::path& folder = temporary.path();
  const std::string a = (folder / "a").string();
  constexpr const char* kCentres = "/octomap_point_cloud_centers";
  constexpr const char* kProjected = "/projected_map";
  ros::NodeHandle node_handle;
  MapObserver observer(node_handle);
  auto centres = [&] { return observer.latest<sensor_msgs::PointCloud2>(kCentres); };
  auto projected = [&] { return observer.latest<nav_msgs::OccupancyGrid>(kProjected); };

  ASSERT_TRUE(ros::service::waitForService("/manager/load_nodelet", ros::Duration(20.0)));
  // 1. MapServer A on the map the PointCloudMapper fills.
  setMapServerParameters("/map_server_a", "", a, (folder / "unused").string());
  ASSERT_TRUE(loadNodelet("/map_server_a", "occupancy_fusion/MapServer"));
  observer.watch<sensor_msgs::PointCloud2>(kCentres);
  ASSERT_TRUE(waitUntil(
      [&] {
        const auto cloud = centres();
        return cloud && cloud->width * cloud->height >= 2000;
      },
      40.0))
      << "the mapper did not fill the map";

  // A failed save names the file and keeps what was there: <prefix>.ot is taken by a folder, so
  // the first file fails and the older .bt beside it is not touched.
  const std::string taken = (folder / "taken").string();
  fs::create_directories(taken + ".ot/inside");
  { std::ofstream(taken + ".bt") << "previous"; }
  const SaveMap failed = save("/map_server_a/save_map", taken);
  EXPECT_FALSE(failed.response.success);
  EXPECT_NE(failed.response.message.find(taken + ".ot"), std::string::npos)
      << failed.response.message;
  EXPECT_TRUE(failed.response.files.empty());
  EXPECT_EQ(readBytes(taken + ".bt"), "previous");
  EXPECT_TRUE(fs::is_directory(taken + ".ot/inside"));
  const std::string missing = (folder / "no_such_folder" / "map").string();
  const SaveMap unwritable = save("/map_server_a/save_map", missing);
  EXPECT_FALSE(unwritable.response.success);
  EXPECT_NE(unwritable.response.message.find(missing + ".ot"), std::string::npos)
      << unwritable.response.message;

  // Unloading A saves the map while the mapper keeps writing to it.
  ASSERT_TRUE(unloadNodelet("/map_server_a"));
  for (const char* extension : {".ot", ".bt", ".pgm", ".yaml", ".laser.npy", ".laser.yaml"}) {
    EXPECT_TRUE(fs::exists(a + extension)) << a + extension;
  }
  for (const auto& entry : fs::directory_iterator(folder)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  }
  const std::unique_ptr<octomap::OcTree> saved_tree = readOt(a + ".ot");
  ASSERT_NE(saved_tree, nullptr);
  const octomap::OcTree& saved = *saved_tree;
  ASSERT_NEAR(saved.getResolution(), kResolution, 1e-12);
  const double saved_occupied = occupiedVoxels(saved);
  EXPECT_GE(saved_occupied, 2000.0);

  const LogOddsRaster saved_layer = readLayerFiles(a + ".laser.yaml");
  const auto known_cells = std::count_if(saved_layer.data.begin(), saved_layer.data.end(),
                                         [](float value) { return !std::isnan(value); });
  EXPECT_GE(known_cells, 5000) << "the laser layer was not saved";

  // 2. Everyone leaves: the map is freed. B starts on an empty manager with load_map.
  ASSERT_TRUE(unloadNodelet("/point_cloud_mapper"));
  ASSERT_TRUE(unloadNodelet("/laser_mapper"));
  ASSERT_TRUE(unloadNodelet("/simulator"));
  const std::string b = (folder / "b").string();
  setMapServerParameters("/map_server_b", a + ".ot", "", b);
  // The outputs are latched: messages stamped before now are A's, handed over while its links
  // are not torn down yet.
  const ros::Time b_start = ros::Time::now();
  observer.unwatch(kCentres);
  observer.watch<sensor_msgs::PointCloud2>(kCentres, 1, {}, b_start);
  observer.watch<nav_msgs::OccupancyGrid>(kProjected, 1, {}, b_start);
  ASSERT_TRUE(loadNodelet("/map_server_b", "occupancy_fusion/MapServer"));
  ASSERT_TRUE(waitUntil([&] { return centres() && projected(); }, 10.0));
  // The fused view of what was saved, computed here from the two files, is what B publishes;
  // without the laser layer it would not be (the layer's cells differ from the voxels' columns).
  {
    VoxelMapConfig voxel_config;
    voxel_config.resolution = kResolution;
    const std::unique_ptr<VoxelMap> voxels = readOctomapFile(a + ".ot", voxel_config);
    GridLayer2DConfig layer_config;
    layer_config.resolution = kResolution;
    GridLayer2D layer(layer_config);
    layer.importRaster(saved_layer);
    const OccupancyRaster expected = projectToRaster(*voxels, &layer, FusedGridConfig());
    const OccupancyRaster voxels_only = projectToRaster(*voxels, nullptr, FusedGridConfig());
    const nav_msgs::OccupancyGrid& published = *projected();
    ASSERT_EQ(static_cast<int>(published.info.width), expected.width);
    ASSERT_EQ(static_cast<int>(published.info.height), expected.height);
    EXPECT_NEAR(published.info.origin.position.x, expected.origin_x, 1e-6);
    EXPECT_NEAR(published.info.origin.position.y, expected.origin_y, 1e-6);
    EXPECT_TRUE(published.data == expected.data) << "projected_map is not the saved map's view";
    EXPECT_TRUE(voxels_only.width != expected.width || voxels_only.data != expected.data);
  }
  // Right after start, the published cloud is exactly the file's occupied voxels.
  const std::vector<Eigen::Vector3d> points = cloudPoints(*centres());
  EXPECT_EQ(static_cast<double>(points.size()), saved_occupied);
  std::size_t not_occupied_in_file = 0;
  for (const Eigen::Vector3d& p : points) {
    const octomap::OcTreeNode* node = saved.search(p.x(), p.y(), p.z());
    if (node == nullptr || !saved.isNodeOccupied(node)) ++not_occupied_in_file;
  }
  EXPECT_EQ(not_occupied_in_file, 0u);
  // Every log-odds came back exactly: saving again gives the same file, byte for byte.
  const SaveMap resaved = save("/map_server_b/save_map", "");
  ASSERT_TRUE(resaved.response.success) << resaved.response.message;
  EXPECT_EQ(resaved.response.files.size(), 6u);
  EXPECT_EQ(readBytes(b + ".ot"), readBytes(a + ".ot"));
  EXPECT_EQ(readBytes(b + ".laser.npy"), readBytes(a + ".laser.npy"));
  const LogOddsRaster resaved_layer = readLayerFiles(b + ".laser.yaml");
  EXPECT_EQ(resaved_layer.origin_cell, saved_layer.origin_cell);
  EXPECT_EQ(resaved_layer.width, saved_layer.width);

  // 3. A file that is not there: the MapServer refuses to start.
  setMapServerParameters("/map_server_c", (folder / "absent.ot").string(), "", b);
  ros::param::set("/map_server_c/map_name", std::string("other"));
  EXPECT_FALSE(loadNodelet("/map_server_c", "occupancy_fusion/MapServer"));
  // A file cut in the middle (an interrupted copy) is refused too, not resumed in part.
  const std::string whole = readBytes(a + ".ot");
  const std::string cut = (folder / "cut.ot").string();
  { std::ofstream(cut, std::ios::binary) << whole.substr(0, whole.size() / 2); }
  ros::param::set("/map_server_c/load_map", cut);
  EXPECT_FALSE(loadNodelet("/map_server_c", "occupancy_fusion/MapServer"));

  // 4. Mapping resumes on the loaded map: restart the simulator and the mapper.
  const std::size_t loaded_points = points.size();
  ASSERT_TRUE(loadNodelet("/simulator", "occupancy_fusion/Simulator"));
  ASSERT_TRUE(loadNodelet("/point_cloud_mapper", "occupancy_fusion/PointCloudMapper",
                          {{"/cloud_in", "/camera/depth/points"}}));
  ASSERT_TRUE(waitUntil(
      [&] {
        const auto cloud = centres();
        return cloud && cloud->width * cloud->height >= loaded_points + 200;
      },
      40.0))
      << "mapping did not resume";
  const std::string c = (folder / "c").string();
  const SaveMap resumed = save("/map_server_b/save_map", c);
  ASSERT_TRUE(resumed.response.success) << resumed.response.message;
  const std::unique_ptr<octomap::OcTree> after_tree = readOt(c + ".ot");
  ASSERT_NE(after_tree, nullptr);
  const octomap::OcTree& after = *after_tree;
  // The loaded voxels are still there (the robot sees the same room again), and new frames
  // changed the log-odds of many of them.
  std::size_t kept_occupied = 0, changed = 0, loaded = 0;
  for (auto leaf = saved.begin_leafs(); leaf != saved.end_leafs(); ++leaf) {
    if (!saved.isNodeOccupied(*leaf) || leaf.getDepth() != saved.getTreeDepth()) continue;
    ++loaded;
    const octomap::OcTreeNode* node = after.search(leaf.getKey());
    if (node == nullptr) continue;
    if (after.isNodeOccupied(node)) ++kept_occupied;
    if (node->getLogOdds() != leaf->getLogOdds()) ++changed;
  }
  ASSERT_GT(loaded, 1000u);
  EXPECT_GE(static_cast<double>(kept_occupied) / loaded, 0.9);
  EXPECT_GE(changed, loaded / 10);
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "map_persistence_test");
  ros::NodeHandle node_handle;
  return occupancy_fusion::runTestsWhileSpinning();
}
