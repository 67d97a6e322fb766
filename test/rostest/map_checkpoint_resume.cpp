// A mapping process killed with SIGKILL resumes its last checkpoint (map_checkpoint_resume.test):
//  1. In `manager`, a MapServer creates the map with a spill store, memory bounds for the voxels
//     and the laser layer far below what the map needs, and checkpoint_period 0.5 s; the
//     PointCloudMapper and LaserMapper map the simulator into it until blocks and laser tiles are
//     in the store and checkpoints were written.
//  2. The simulator pauses; once the mappers are idle and two more checkpoints went by, the map
//     is saved (what the store's last checkpoint holds), and `manager` is killed with SIGKILL.
//  3. A MapServer on the same store in `manager_b` resumes it: its saved .ot, .bt and laser layer
//     are the bytes saved before the kill, and its submaps (the map follows map -> odom) are those
//     saved before it.
#include <signal.h>
#include <sys/types.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <nodelet/NodeletLoad.h>
#include <ros/master.h>
#include <ros/network.h>
#include <ros/ros.h>
#include <xmlrpcpp/XmlRpcClient.h>

#include "occupancy_fusion/SaveMap.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

// The map's parameters, as every nodelet of a shared map reads them.
void setMapParameters(const std::string& name, const std::string& store) {
  ros::param::set(name + "/map_name", std::string("map"));
  ros::param::set(name + "/resolution", 0.05);
  ros::param::set(name + "/spill_folder", store);
  ros::param::set(name + "/checkpoint_period", 0.5);
  ros::param::set(name + "/max_memory_mb", 0.5);         // ~250 dense blocks
  ros::param::set(name + "/layer_max_memory_mb", 0.05);  // ~12 tiles
  // Following map -> odom: the submaps go into the checkpoints and come back with them.
  ros::param::set(name + "/reanchoring/source", std::string("tf"));
}

// The process id of a node, from its own XML-RPC server (what `rosnode info` asks).
int pidOf(const std::string& node) {
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  request[1] = node;
  if (!ros::master::execute("lookupNode", request, response, payload, true)) return -1;
  std::string host;
  std::uint32_t port = 0;
  if (!ros::network::splitURI(static_cast<std::string>(payload), host, port)) return -1;
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpc::XmlRpcValue caller(ros::this_node::getName()), result;
  if (!client.execute("getPid", caller, result) ||
      result.getType() != XmlRpc::XmlRpcValue::TypeArray || result.size() != 3) {
    return -1;
  }
  return static_cast<int>(result[2]);
}

SaveMap save(const std::string& service, const std::string& prefix) {
  SaveMap request;
  request.request.prefix = prefix;
  EXPECT_TRUE(ros::service::call(service, request)) << service;
  EXPECT_TRUE(request.response.success) << request.response.message;
  return request;
}

TEST(MapCheckpointResume, ManagerKilledWithSigkillResumesItsLastCheckpoint) {
  const TemporaryFolder temporary;
  const fs::path& folder = temporary.path();
  const std::string store = (folder / "store").string();
  ros::NodeHandle node_handle;
  MapObserver observer(node_handle);
  ASSERT_TRUE(ros::service::waitForService("/manager/load_nodelet", ros::Duration(20.0)));
  ASSERT_TRUE(ros::service::waitForService("/manager_b/load_nodelet", ros::Duration(20.0)));

  // 1. The map, created by the MapServer with the store, filled by the two mappers.
  for (const char* name : {"/map_server_a", "/point_cloud_mapper", "/laser_mapper"}) {
    setMapParameters(name, store);
  }
  ros::param::set("/map_server_a/publish_rate", 5.0);
  ASSERT_TRUE(loadNodelet("/map_server_a", "occupancy_fusion/MapServer"));
  ASSERT_TRUE(loadNodelet("/point_cloud_mapper", "occupancy_fusion/PointCloudMapper",
                          {{"/cloud_in", "/camera/depth/points"}}));
  ASSERT_TRUE(loadNodelet("/laser_mapper", "occupancy_fusion/LaserMapper"));
  constexpr const char* kServerA = "map_server_a: map publishing";
  ASSERT_TRUE(waitUntil(
      [&] {
        const DiagnosticValues values = observer.diagnostics(kServerA);
        return countIn(values, "checkpoints written") >= 3 &&
               countIn(values, "spilled blocks") > 0 &&
               countIn(values, "layer tiles in the spill store") > 0;
      },
      60.0))
      << "no checkpoints with blocks and laser tiles in the store";
  const DiagnosticValues mapped = observer.diagnostics(kServerA);
  EXPECT_EQ(countIn(mapped, "spill store failures"), 0u);
  EXPECT_EQ(countIn(mapped, "layer spill failures"), 0u);

  // 2. Idle mappers, two more checkpoints: the last one holds the map as it is now.
  ASSERT_TRUE(setSimulatorPaused(true));
  ros::WallDuration(2.0).sleep();
  const std::size_t before = observer.diagnosticCount(kServerA, "checkpoints written");
  ASSERT_TRUE(waitUntil(
      [&] { return observer.diagnosticCount(kServerA, "checkpoints written") >= before + 2; },
      10.0));
  const std::string saved = (folder / "before").string();
  ASSERT_TRUE(save("/map_server_a/save_map", saved).response.success);
  const int pid = pidOf("/manager");
  ASSERT_GT(pid, 0);
  ASSERT_EQ(kill(pid, SIGKILL), 0);
  ASSERT_TRUE(
      waitUntil([] { return !ros::service::exists("/map_server_a/save_map", false); }, 10.0));

  // 3. A MapServer on the same store, in another process.
  setMapParameters("/map_server_b", store);
  ASSERT_TRUE(loadNodelet("/map_server_b", "occupancy_fusion/MapServer", {}, "/manager_b"));
  const std::string resumed = (folder / "after").string();
  ASSERT_TRUE(save("/map_server_b/save_map", resumed).response.success);
  for (const char* extension : {".ot", ".bt", ".laser.npy"}) {
    const std::string expected = readBytes(saved + extension);
    EXPECT_GT(expected.size(), 1000u) << extension;
    EXPECT_TRUE(readBytes(resumed + extension) == expected) << extension << " differs";
  }
  // The submaps came back with the checkpoint: the same submaps, changes and odometry (their
  // blocks in another order), not the resumed map as one fixed submap.
  const std::string submaps = readBytes(saved + ".submaps");
  EXPECT_GT(submaps.size(), 1000u);
  EXPECT_EQ(readBytes(resumed + ".submaps").size(), submaps.size());
  const DiagnosticValues values =
      observer.diagnosticsAfter("map_server_b: map publishing", ros::WallTime::now(), 5.0);
  EXPECT_GT(countIn(values, "blocks resumed from the store"), 0u);
  EXPECT_GT(countIn(values, "spilled blocks"), 0u);  // the resumed map keeps its bound
  EXPECT_FALSE(values.count("resumed checkpoint") == 0 || values.at("resumed checkpoint").empty());
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "map_checkpoint_resume_test");
  ros::NodeHandle node_handle;
  return occupancy_fusion::runTestsWhileSpinning();
}
