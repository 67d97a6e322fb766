// The MapServer's octomap_binary (occupancy_fusion/Octomap) reaches octomap_msgs users
// (octomap_msgs_interop.test):
//  1. occupancy_fusion/Octomap and octomap_msgs/Octomap, as generated from the octomap_msgs
//     package of test/octomap_msgs_consumer, both have octomap_msgs/Octomap's published MD5 sum.
//  2. With the map frozen, a consumer built against that octomap_msgs (a separate process, which
//     knows nothing of occupancy_fusion) receives octomap_binary, decodes the tree with liboctomap
//     and writes it; that tree is the one ~save_map wrote to the .bt file: same resolution, same
//     leaves, and every leaf's key, depth and label equal.
// If the sums differed, roscpp would refuse the consumer's connection: the consumer then gives up
// after its timeout and says why, and this test fails with its message.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <tuple>

#include <sys/wait.h>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <octomap/OcTree.h>
#include <ros/ros.h>

#include "occupancy_fusion/Octomap.h"
#include "occupancy_fusion/SaveMap.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

// The MD5 sum of octomap_msgs/Octomap (ROS 1), as published in the message's generated code, e.g.
// rosserial's octomap_msgs/Octomap.h for ROS Kinetic, whose getMD5() returns it:
// https://github.com/vfdev-5/ros-kinetic-mbed/blob/5b7789dd7fafba958a283f71754e8c5e608b834e/octomap_msgs/Octomap.h
constexpr char kOctomapMsgsMd5[] = "9a45536b45c5e409cd49f04bb2d9999f";

constexpr int kMinClouds = 5;  // enough for a few thousand leaves at 0.05 m

// The "key: value" lines a command printed.
std::map<std::string, std::string> keyValues(const std::string& output) {
  std::map<std::string, std::string> values;
  std::istringstream lines(output);
  std::string line;
  while (std::getline(lines, line)) {
    const std::size_t colon = line.find(": ");
    if (colon != std::string::npos) values[line.substr(0, colon)] = line.substr(colon + 2);
  }
  return values;
}

// The value of `key` in such lines; "" when there is none.
std::string valueOf(const std::map<std::string, std::string>& values, const std::string& key) {
  const auto found = values.find(key);
  return found == values.end() ? "" : found->second;
}

// Runs the octomap_msgs consumer with `arguments` (coreutils' timeout stops it should it hang past
// its own deadline). Returns its output and a line saying how it ended; *status gets its exit
// status, -1 when it did not exit.
std::string runConsumer(const std::string& arguments, int* status) {
  int wait_status = -1;
  std::string output = runCommand(
      "timeout --kill-after=5 60 " + std::string(OCTOMAP_CONSUMER_PATH) + " " + arguments,
      &wait_status);
  *status = WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : -1;
  output +=
      WIFEXITED(wait_status)
          ? "(exit status " + std::to_string(*status) +
                (*status == 124 ? ": stopped by timeout after 60 s" : "") + ")\n"
          : "(ended without an exit status, wait status " + std::to_string(wait_status) + ")\n";
  return output;
}

// Every leaf of a tree, by key and depth (a pruned leaf stands above the deepest level), and
// whether liboctomap calls it occupied.
using LeafLabels =
    std::map<std::tuple<std::uint16_t, std::uint16_t, std::uint16_t, unsigned>, bool>;
LeafLabels leafLabels(const octomap::OcTree& tree) {
  LeafLabels leaves;
  for (auto leaf = tree.begin_leafs(); leaf != tree.end_leafs(); ++leaf) {
    const octomap::OcTreeKey key = leaf.getKey();
    leaves[{key[0], key[1], key[2], leaf.getDepth()}] = tree.isNodeOccupied(*leaf);
  }
  return leaves;
}

// How many leaves of one tree the other lacks or labels otherwise (0: the same tree).
std::size_t leafDifferences(const LeafLabels& a, const LeafLabels& b) {
  std::size_t differences = 0;
  for (const auto& [key, occupied] : a) {
    const auto other = b.find(key);
    if (other == b.end() || other->second != occupied) ++differences;
  }
  for (const auto& entry : b) differences += a.count(entry.first) == 0 ? 1 : 0;
  return differences;
}

TEST(OctomapMsgsInterop, Md5SumsAreOctomapMsgs) {
  const std::string ours = ros::message_traits::MD5Sum<Octomap>::value();
  EXPECT_EQ(ours, kOctomapMsgsMd5) << "occupancy_fusion/Octomap (msg/Octomap.msg)";
  int status = -1;
  const std::string output = runConsumer("--md5", &status);
  ASSERT_EQ(status, 0) << output;
  const auto consumer = keyValues(output);
  EXPECT_EQ(valueOf(consumer, "datatype"), "octomap_msgs/Octomap") << output;
  EXPECT_EQ(valueOf(consumer, "md5sum"), kOctomapMsgsMd5)
      << "octomap_msgs/Octomap as generated from test/octomap_msgs_consumer/octomap_msgs";
  EXPECT_EQ(valueOf(consumer, "md5sum"), ours);
}

TEST(OctomapMsgsInterop, ConsumerDecodesTheSavedTree) {
  const TemporaryFolder temporary;
  const fs::path& folder = temporary.path();
  ros::NodeHandle node_handle;
  const MapObserver observer(node_handle);
  const auto integrated = [&] {
    return observer.diagnosticCount("point cloud mapping", "clouds integrated");
  };

  // A few clouds mapped, then nothing changes the map any more.
  ASSERT_TRUE(waitUntil([&] { return integrated() >= kMinClouds; }, 40.0))
      << "the point-cloud mapper integrated " << integrated() << " clouds";
  ASSERT_TRUE(ros::service::waitForService("/simulator/pause", ros::Duration(10.0)));
  ASSERT_TRUE(setSimulatorPaused(true));
  std::size_t settled = 0;
  ASSERT_TRUE(waitUntilSteady(integrated, 2.5, 20.0, &settled));

  SaveMap save;
  save.request.prefix = (folder / "saved").string();
  ASSERT_TRUE(ros::service::call("/map_server/save_map", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  const std::string saved_path = save.request.prefix + ".bt";

  // The consumer's subscription is the first to octomap_binary, so the MapServer sends the frozen
  // map to it (and nothing older was latched).
  const std::string received_path = (folder / "received.bt").string();
  int status = -1;
  const std::string output =
      runConsumer(received_path + " 20 octomap_binary:=/octomap_binary", &status);
  ASSERT_EQ(status, 0) << "the octomap_msgs consumer failed:\n" << output;
  const auto consumer = keyValues(output);
  // The message came from occupancy_fusion/Octomap's publisher, read as octomap_msgs/Octomap.
  EXPECT_EQ(valueOf(consumer, "publisher_type"), "occupancy_fusion/Octomap") << output;
  EXPECT_EQ(valueOf(consumer, "publisher_md5sum"), kOctomapMsgsMd5) << output;
  EXPECT_EQ(valueOf(consumer, "datatype"), "octomap_msgs/Octomap") << output;
  EXPECT_EQ(valueOf(consumer, "frame_id"), "map") << output;
  EXPECT_EQ(valueOf(consumer, "binary"), "true") << output;
  EXPECT_EQ(valueOf(consumer, "id"), "OcTree") << output;

  const octomap::OcTree saved(saved_path);
  const octomap::OcTree received(received_path);
  ASSERT_GT(saved.size(), 0u) << saved_path;
  EXPECT_EQ(received.getResolution(), saved.getResolution());
  EXPECT_EQ(received.getTreeDepth(), saved.getTreeDepth());
  EXPECT_EQ(received.getNumLeafNodes(), saved.getNumLeafNodes());
  const LeafLabels saved_leaves = leafLabels(saved);
  const LeafLabels received_leaves = leafLabels(received);
  EXPECT_EQ(saved_leaves.size(), saved.getNumLeafNodes());
  std::size_t occupied = 0;
  for (const auto& entry : saved_leaves) occupied += entry.second ? 1 : 0;
  RecordProperty("leaves", static_cast<int>(saved_leaves.size()));
  RecordProperty("occupied_leaves", static_cast<int>(occupied));
  RecordProperty("message_bytes", valueOf(consumer, "data_bytes"));
  EXPECT_GE(occupied, 1000u) << "too small a map to tell";
  EXPECT_GE(saved_leaves.size() - occupied, 1000u) << "too small a map to tell";
  EXPECT_EQ(leafDifferences(received_leaves, saved_leaves), 0u)
      << "of " << saved_leaves.size() << " leaves in " << saved_path;
  // Both files are liboctomap's writeBinary of the same tree: the same bytes.
  const std::string received_bytes = readBytes(received_path);
  const std::string saved_bytes = readBytes(saved_path);
  EXPECT_TRUE(received_bytes == saved_bytes)
      << received_bytes.size() << " bytes in " << received_path << ", " << saved_bytes.size()
      << " in " << saved_path;

  // The comparison sees a single voxel labelled otherwise.
  octomap::OcTree altered(received);
  for (auto leaf = altered.begin_leafs(); leaf != altered.end_leafs(); ++leaf) {
    if (leaf.getDepth() == altered.getTreeDepth() && altered.isNodeOccupied(*leaf)) {
      leaf->setLogOdds(altered.getClampingThresMinLog());
      break;
    }
  }
  EXPECT_EQ(leafDifferences(leafLabels(altered), received_leaves), 1u);

  ASSERT_TRUE(setSimulatorPaused(false));
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "octomap_msgs_interop_test");
  ros::NodeHandle node_handle;
  return occupancy_fusion::runTestsWhileSpinning();
}
