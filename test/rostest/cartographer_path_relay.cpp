// Checks the cartographer relay through mapping.launch: this node serves trajectory_query as
// cartographer_node does (poses of the tracking frame in the map frame, stamped with the nodes'
// times) and reads slam/path. A failed answer publishes nothing; the first answer is published
// in time order; an unchanged graph is not published again; a loop closure that moves a node is.
#include <cmath>
#include <mutex>
#include <vector>

#include <gtest/gtest.h>

#include <nav_msgs/Path.h>
#include <ros/ros.h>

#include "occupancy_fusion/CartographerTrajectoryQuery.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

constexpr int kTrajectory = 2;  // the launch's cartographer_trajectory_id

// What the stand-in answers, and what it was asked and what came out.
struct Cartographer {
  std::mutex mutex;
  bool ready = false;
  std::vector<geometry_msgs::PoseStamped> nodes;
  int calls = 0;
  int other_trajectory_calls = 0;
  std::vector<nav_msgs::Path> paths;
};
Cartographer g_cartographer;

geometry_msgs::PoseStamped node(double stamp, double x, double y) {
  geometry_msgs::PoseStamped pose;
  pose.header.frame_id = "map";
  pose.header.stamp.fromSec(stamp);
  pose.pose.position.x = x;
  pose.pose.position.y = y;
  pose.pose.orientation.w = 1.0;
  return pose;
}

bool answer(CartographerTrajectoryQuery::Request& request,
            CartographerTrajectoryQuery::Response& response) {
  std::lock_guard<std::mutex> lock(g_cartographer.mutex);
  ++g_cartographer.calls;
  if (request.trajectory_id != kTrajectory) ++g_cartographer.other_trajectory_calls;
  if (!g_cartographer.ready) {
    response.status.code = 14;  // cartographer's StatusCode UNAVAILABLE
    response.status.message = "no trajectory yet";
    return true;
  }
  response.status.code = 0;
  response.trajectory = g_cartographer.nodes;
  return true;
}

std::size_t pathsReceived() {
  std::lock_guard<std::mutex> lock(g_cartographer.mutex);
  return g_cartographer.paths.size();
}

int callsAnswered() {
  std::lock_guard<std::mutex> lock(g_cartographer.mutex);
  return g_cartographer.calls;
}

TEST(CartographerPathRelay, RelaysTheOptimisedTrajectoryWhenItMoves) {
  // Answers that are not OK publish nothing.
  ASSERT_TRUE(waitUntil([] { return callsAnswered() >= 2; }, 20.0)) << "the relay never called";
  EXPECT_EQ(pathsReceived(), 0u);
  {
    std::lock_guard<std::mutex> lock(g_cartographer.mutex);
    g_cartographer.nodes = {node(12.0, 2.0, 0.0), node(10.0, 0.0, 0.0), node(11.0, 1.0, 0.1)};
    g_cartographer.ready = true;
  }
  ASSERT_TRUE(waitUntil([] { return pathsReceived() >= 1; }, 10.0));
  {
    std::lock_guard<std::mutex> lock(g_cartographer.mutex);
    const nav_msgs::Path& path = g_cartographer.paths.front();
    EXPECT_EQ(path.header.frame_id, "map");
    ASSERT_EQ(path.poses.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i) {
      EXPECT_DOUBLE_EQ(path.poses[i].header.stamp.toSec(), 10.0 + static_cast<double>(i));
      EXPECT_DOUBLE_EQ(path.poses[i].pose.position.x, static_cast<double>(i));
    }
    EXPECT_EQ(g_cartographer.other_trajectory_calls, 0);
  }
  // The same graph, asked again (a call a second): nothing new.
  const int calls = callsAnswered();
  ASSERT_TRUE(waitUntil([&] { return callsAnswered() >= calls + 2; }, 10.0));
  EXPECT_EQ(pathsReceived(), 1u);
  // A loop closure moves the first node by 0.3 m: published again.
  {
    std::lock_guard<std::mutex> lock(g_cartographer.mutex);
    g_cartographer.nodes[1].pose.position.y = 0.3;
  }
  ASSERT_TRUE(waitUntil([] { return pathsReceived() >= 2; }, 10.0));
  std::lock_guard<std::mutex> lock(g_cartographer.mutex);
  EXPECT_DOUBLE_EQ(g_cartographer.paths.back().poses.front().pose.position.y, 0.3);
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "cartographer_path_relay_test");
  ros::NodeHandle node_handle;
  const ros::ServiceServer server =
      node_handle.advertiseService("/cartographer/trajectory_query", occupancy_fusion::answer);
  const boost::function<void(const nav_msgs::Path::ConstPtr&)> keep =
      [](const nav_msgs::Path::ConstPtr& path) {
        std::lock_guard<std::mutex> lock(occupancy_fusion::g_cartographer.mutex);
        occupancy_fusion::g_cartographer.paths.push_back(*path);
      };
  const ros::Subscriber subscriber = node_handle.subscribe<nav_msgs::Path>("slam/path", 10, keep);
  return occupancy_fusion::runTestsWhileSpinning();
}
