// The mapping session's tf lookups at a frame's stamp, which reaches them as double seconds.
#include <gtest/gtest.h>

#include <geometry_msgs/TransformStamped.h>
#include <tf2/buffer_core.h>

#include "occupancy_fusion/ros/tf_buffer_pose_source.h"

namespace occupancy_fusion {
namespace {

geometry_msgs::TransformStamped odomToBase(const ros::Time& stamp, double x) {
  geometry_msgs::TransformStamped transform;
  transform.header.frame_id = "odom";
  transform.header.stamp = stamp;
  transform.child_frame_id = "base_link";
  transform.transform.translation.x = x;
  transform.transform.rotation.w = 1.0;
  return transform;
}

// The newest transform sent at exactly the frame's stamp: found although the stamp, through a
// double, comes back a few tens of nanoseconds later (as a simulator or a driver that sends the
// pose with the data gives it).
TEST(TfBufferPoseSource, FindsTheNewestTransformAtTheFramesOwnStamp) {
  // A stamp of today whose double rounds up.
  ros::Time stamp(1796496223, 120487000);
  while (!(ros::Time(stamp.toSec()) > stamp)) stamp.nsec += 1;
  tf2::BufferCore buffer;
  buffer.setTransform(odomToBase(stamp - ros::Duration(0.1), 1.0), "test");
  buffer.setTransform(odomToBase(stamp, 2.0), "test");
  const TfBufferPoseSource poses(buffer);
  std::string why;
  const std::optional<Eigen::Isometry3d> pose =
      poses.lookup("odom", "base_link", stamp.toSec(), &why);
  ASSERT_TRUE(pose.has_value()) << why;
  EXPECT_NEAR(pose->translation().x(), 2.0, 1e-4);
  // Later than the newest transform by more than the double's rounding: still refused.
  EXPECT_FALSE(poses.lookup("odom", "base_link", stamp.toSec() + 0.01, &why).has_value());
  EXPECT_NE(why.find("extrapolation"), std::string::npos) << why;
}

}  // namespace
}  // namespace occupancy_fusion
