// The cartographer relay: its service type has the MD5 of cartographer_ros_msgs/TrajectoryQuery
// (computed here by ROS's rules from cartographer's field list, so a call reaches cartographer's
// server), and its answer becomes the path reanchoring:=path reads.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include <geometry_msgs/Point.h>
#include <geometry_msgs/PoseStamped.h>
#include <boost/uuid/detail/md5.hpp>

#include "occupancy_fusion/CartographerTrajectoryQuery.h"
#include "occupancy_fusion/ros/cartographer_trajectory.h"

namespace occupancy_fusion {
namespace {

std::string md5Hex(const std::string& text) {
  boost::uuids::detail::md5 hash;
  hash.process_bytes(text.data(), text.size());
  boost::uuids::detail::md5::digest_type digest;
  hash.get_digest(digest);
  // boost keeps each 32-bit word in host order; the digest's bytes are each word's, low first.
  std::string hex;
  for (unsigned int word : digest) {
    for (int byte = 0; byte < 4; ++byte) {
      char two[3];
      std::snprintf(two, sizeof(two), "%02x", (word >> (8 * (3 - byte))) & 0xffU);
      hex += two;
    }
  }
  return hex;
}

TEST(CartographerTrajectory, Md5FollowsRosRules) {
  // Built-in fields "type name"; a message field "<its md5> name" (genmsg's compute_md5_text).
  EXPECT_EQ(md5Hex("float64 x\nfloat64 y\nfloat64 z"),
            ros::message_traits::md5sum<geometry_msgs::Point>());
  const std::string header = ros::message_traits::md5sum<std_msgs::Header>();
  const std::string pose = ros::message_traits::md5sum<geometry_msgs::Pose>();
  EXPECT_EQ(md5Hex(header + " header\n" + pose + " pose"),
            ros::message_traits::md5sum<geometry_msgs::PoseStamped>());
}

TEST(CartographerTrajectory, ServiceHasTheMd5OfCartographersTrajectoryQuery) {
  // cartographer_ros_msgs/StatusResponse: uint8 code, string message.
  const std::string status = md5Hex("uint8 code\nstring message");
  EXPECT_EQ(status, ros::message_traits::md5sum<CartographerStatus>());
  // cartographer_ros_msgs/TrajectoryQuery: int32 trajectory_id, time start_time, time end_time
  // --- StatusResponse status, geometry_msgs/PoseStamped[] trajectory (request text, then
  // response).
  const std::string request = "int32 trajectory_id\ntime start_time\ntime end_time";
  const std::string response = status + " status\n" +
                               ros::message_traits::md5sum<geometry_msgs::PoseStamped>() +
                               " trajectory";
  EXPECT_EQ(md5Hex(request + response), ros::service_traits::md5sum<CartographerTrajectoryQuery>());
}

geometry_msgs::PoseStamped node(double stamp, double x, double yaw,
                                const std::string& frame = "map") {
  geometry_msgs::PoseStamped pose;
  pose.header.frame_id = frame;
  pose.header.stamp.fromSec(stamp);
  pose.pose.position.x = x;
  pose.pose.orientation.z = std::sin(yaw / 2);
  pose.pose.orientation.w = std::cos(yaw / 2);
  return pose;
}

TEST(CartographerTrajectory, PathHoldsTheUsableNodesInTimeOrder) {
  geometry_msgs::PoseStamped not_rigid = node(4.0, 4.0, 0.0);
  not_rigid.pose.orientation.w = 0.0;
  geometry_msgs::PoseStamped not_finite = node(5.0, std::nan(""), 0.0);
  const std::size_t nodes_given = 7;
  std::size_t left_out = 0;
  const nav_msgs::Path path =
      trajectoryPath({node(2.0, 2.0, 0.2), node(1.0, 1.0, 0.1), node(3.0, 3.0, 0.0, "odom"),
                      not_rigid, not_finite, node(0.0, 9.0, 0.0), node(6.0, 6.0, 0.3)},
                     &left_out);
  EXPECT_EQ(left_out, nodes_given - 3);
  ASSERT_EQ(path.poses.size(), 3u);
  EXPECT_EQ(path.header.frame_id, "map");
  EXPECT_DOUBLE_EQ(path.poses[0].pose.position.x, 1.0);
  EXPECT_DOUBLE_EQ(path.poses[1].pose.position.x, 2.0);
  EXPECT_DOUBLE_EQ(path.poses[2].pose.position.x, 6.0);
  EXPECT_DOUBLE_EQ(path.header.stamp.toSec(), 6.0);
  EXPECT_TRUE(trajectoryPath({}).poses.empty());
}

TEST(CartographerTrajectory, RepublishedOnlyWhenTheGraphMovedANode) {
  const nav_msgs::Path path = trajectoryPath({node(1.0, 1.0, 0.1), node(2.0, 2.0, 0.2)});
  EXPECT_FALSE(pathMoved(path, path, 0.001, 0.001));
  nav_msgs::Path nudged = trajectoryPath({node(1.0, 1.0005, 0.1), node(2.0, 2.0, 0.2005)});
  EXPECT_FALSE(pathMoved(path, nudged, 0.001, 0.001));
  EXPECT_TRUE(
      pathMoved(path, trajectoryPath({node(1.0, 1.0, 0.1), node(2.0, 2.002, 0.2)}), 0.001, 0.001));
  EXPECT_TRUE(
      pathMoved(path, trajectoryPath({node(1.0, 1.0, 0.1), node(2.0, 2.0, 0.202)}), 0.001, 0.001));
  EXPECT_TRUE(pathMoved(path, trajectoryPath({node(1.0, 1.0, 0.1)}), 0.001, 0.001));
  EXPECT_TRUE(
      pathMoved(path, trajectoryPath({node(1.0, 1.0, 0.1), node(2.5, 2.0, 0.2)}), 0.001, 0.001));
}

}  // namespace
}  // namespace occupancy_fusion
