// The bad-input matrix, online: all four mappers and the MapServer in one manager (mapping.launch)
// get each kind of bad input from this node, which plays the sensors and tf itself, with its own
// stamps. Per case: the mapper's diagnostics count the drop under its reason
// ("frames dropped (<reason>)"); the shared map is unchanged by the bad frames (its version and
// the laser layer's cell count); and the mapper is still alive, integrating a good frame
// afterwards. What is skipped inside a frame (bad pixels, beams, points) is checked exactly, map
// against map, by the unit tests test/unit/ros/test_bad_input.cpp.
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <stereo_msgs/DisparityImage.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

constexpr int kWidth = 64, kHeight = 48;
constexpr double kFocal = 50.0, kBaseline = 0.1, kWall = 2.0;  // px, m, m
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

geometry_msgs::TransformStamped transform(const std::string& parent, const std::string& child,
                                          const ros::Time& stamp, double x = 0.0) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = parent;
  t.header.stamp = stamp;
  t.child_frame_id = child;
  t.transform.translation.x = x;
  t.transform.rotation.w = 1.0;
  return t;
}

// Camera optical frames look along the base's +x (z forward, x right, y down).
geometry_msgs::TransformStamped opticalTransform(const std::string& child, const ros::Time& stamp) {
  geometry_msgs::TransformStamped t = transform("base_link", child, stamp);
  t.transform.translation.z = 0.5;
  t.transform.rotation.x = -0.5;
  t.transform.rotation.y = 0.5;
  t.transform.rotation.z = -0.5;
  t.transform.rotation.w = 0.5;
  return t;
}

sensor_msgs::CameraInfo cameraInfo(const std::string& frame, const ros::Time& stamp,
                                   int width = kWidth, int height = kHeight, double f = kFocal) {
  sensor_msgs::CameraInfo info;
  info.header.frame_id = frame;
  info.header.stamp = stamp;
  info.width = width;
  info.height = height;
  info.K = {f, 0.0, (width - 1) / 2.0, 0.0, f, (height - 1) / 2.0, 0.0, 0.0, 1.0};
  info.P = {f, 0.0, (width - 1) / 2.0, 0.0, 0.0, f, (height - 1) / 2.0, 0.0, 0.0, 0.0, 1.0, 0.0};
  return info;
}

// A kWidth x kHeight 32FC1 image of one value.
sensor_msgs::Image uniformImage(const std::string& frame, const ros::Time& stamp, float value) {
  return floatImage(std::vector<float>(kWidth * kHeight, value), kWidth, kHeight, frame, stamp);
}

class BadInputMatrix : public ::testing::Test {
 protected:
  static constexpr const char* kDepth = "depth mapping";
  static constexpr const char* kDisparity = "disparity mapping";
  static constexpr const char* kLaser = "laser mapping";
  static constexpr const char* kCloud = "point cloud mapping";
  static constexpr const char* kMapServer = "map publishing";

  static void SetUpTestSuite() {
    ros::NodeHandle nh;
    observer_ = new MapObserver(nh);
    depth_ = nh.advertise<sensor_msgs::Image>("/camera/depth/image", 10);
    depth_info_ = nh.advertise<sensor_msgs::CameraInfo>("/camera/depth/camera_info", 10);
    disparity_ = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 10);
    disparity_info_ = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 10);
    scan_ = nh.advertise<sensor_msgs::LaserScan>("/front_laser/scan", 10);
    cloud_ = nh.advertise<sensor_msgs::PointCloud2>("/cloud_in", 10);
    tf_ = new tf2_ros::TransformBroadcaster;
    static_tf_ = new tf2_ros::StaticTransformBroadcaster;
    const ros::Time zero;
    static_tf_->sendTransform(
        {opticalTransform("depth_optical", zero), opticalTransform("stereo_optical", zero),
         transform("base_link", "laser", zero), transform("base_link", "cloud_frame", zero),
         transform("base_link", "old_cloud_frame", zero)});
    // Every mapper subscribed and diagnosing (the laser mapper's status comes once it runs).
    ASSERT_TRUE(waitUntil(
        [] {
          return depth_.getNumSubscribers() > 0 && disparity_.getNumSubscribers() > 0 &&
                 scan_.getNumSubscribers() > 0 && cloud_.getNumSubscribers() > 0 &&
                 depth_info_.getNumSubscribers() > 0 && disparity_info_.getNumSubscribers() > 0;
        },
        20.0));
    start_ = ros::Time::now();
    last_stamp_ = start_;
  }

  // The next stamp, 0.1 s after the last; the robot (map -> base_link) at x there.
  static ros::Time nextStamp(double x = 0.0) {
    last_stamp_ += ros::Duration(0.1);
    tf_->sendTransform(transform("map", "base_link", last_stamp_, x));
    ros::WallDuration(0.05).sleep();  // the mappers' tf listeners have it before the frame
    return last_stamp_;
  }

  template <class Message>
  static void send(const ros::Publisher& publisher, const Message& message) {
    publisher.publish(message);
    ros::WallDuration(0.05).sleep();
  }

  // Publishes a camera_info and waits until `task`'s mapper has it (its "camera_info received"
  // count, of every camera_info this test sent it): an image sent next cannot overtake it on its
  // own connection and be paired with the previous camera_info.
  static void sendCameraInfo(const ros::Publisher& publisher, const std::string& task,
                             const sensor_msgs::CameraInfo& info) {
    publisher.publish(info);
    expectCount(task, "camera_info received", ++camera_infos_sent_[task]);
  }

  static stereo_msgs::DisparityImage disparity(const ros::Time& stamp, double baseline) {
    stereo_msgs::DisparityImage message;
    message.header.frame_id = "stereo_optical";
    message.header.stamp = stamp;
    message.image = uniformImage("stereo_optical", stamp, kFocal * kBaseline / kWall);
    message.f = kFocal;
    message.T = baseline;
    message.min_disparity = 0.0f;
    message.max_disparity = kWidth;
    message.delta_d = 1.0f / 16.0f;
    return message;
  }

  static sensor_msgs::LaserScan scan(const ros::Time& stamp) {
    sensor_msgs::LaserScan message;
    message.header.frame_id = "laser";
    message.header.stamp = stamp;
    message.angle_min = -M_PI / 2;
    message.angle_max = M_PI / 2;
    message.angle_increment = M_PI / 180;
    message.range_min = 0.1f;
    message.range_max = 10.0f;
    message.ranges.assign(181, 3.0f);
    return message;
  }

  static sensor_msgs::PointCloud2 cloud(const std::string& frame, const ros::Time& stamp) {
    sensor_msgs::PointCloud2 message;
    message.header.frame_id = frame;
    message.header.stamp = stamp;
    sensor_msgs::PointCloud2Modifier modifier(message);
    modifier.setPointCloud2FieldsByString(1, "xyz");
    modifier.resize(100);
    sensor_msgs::PointCloud2Iterator<float> x(message, "x"), y(message, "y"), z(message, "z");
    for (int i = 0; i < 100; ++i, ++x, ++y, ++z) {
      *x = kWall, *y = 0.02f * i - 1.0f, *z = 0.3f;
    }
    return message;
  }

  // The shared map's state: the voxel map's version (a DisparityMapper key; every write bumps
  // it) and the laser layer's known cells (a MapServer key), read from statuses sent after now.
  static std::pair<std::size_t, std::size_t> mapState() {
    const ros::WallTime now = ros::WallTime::now();
    return {countIn(observer_->diagnosticsAfter(kDisparity, now), "map version"),
            countIn(observer_->diagnosticsAfter(kMapServer, now), "layer cells")};
  }

  static std::string dropped(const std::string& reason) {
    return "frames dropped (" + reason + ")";
  }

  // Expects `key` of `task` to reach `value`.
  static void expectCount(const std::string& task, const std::string& key, std::size_t value) {
    EXPECT_EQ(observer_->waitForCount(task, key, value), value) << task << ": " << key;
  }

  static MapObserver* observer_;
  static ros::Publisher depth_, depth_info_, disparity_, disparity_info_, scan_, cloud_;
  static tf2_ros::TransformBroadcaster* tf_;
  static tf2_ros::StaticTransformBroadcaster* static_tf_;
  static ros::Time start_, last_stamp_;
  static std::map<std::string, std::size_t> camera_infos_sent_;  // by task
};

MapObserver* BadInputMatrix::observer_ = nullptr;
ros::Publisher BadInputMatrix::depth_, BadInputMatrix::depth_info_, BadInputMatrix::disparity_,
    BadInputMatrix::disparity_info_, BadInputMatrix::scan_, BadInputMatrix::cloud_;
tf2_ros::TransformBroadcaster* BadInputMatrix::tf_ = nullptr;
tf2_ros::StaticTransformBroadcaster* BadInputMatrix::static_tf_ = nullptr;
ros::Time BadInputMatrix::start_, BadInputMatrix::last_stamp_;
std::map<std::string, std::size_t> BadInputMatrix::camera_infos_sent_;

// Frames before any camera_info: dropped, counted, nothing written.
TEST_F(BadInputMatrix, CameraInfoMissing) {
  const auto before = mapState();
  ros::Time stamp = nextStamp();
  send(depth_, uniformImage("depth_optical", stamp, kWall));
  send(disparity_, disparity(stamp, kBaseline));
  expectCount(kDepth, dropped("no camera_info"), 1);
  expectCount(kDisparity, dropped("no camera_info"), 1);
  EXPECT_EQ(mapState(), before);
  // Alive: with camera_info, the next frames are integrated and change the map.
  sendCameraInfo(disparity_info_, kDisparity, cameraInfo("stereo_optical", stamp));
  stamp = nextStamp();
  sendCameraInfo(depth_info_, kDepth, cameraInfo("depth_optical", stamp));
  send(depth_, uniformImage("depth_optical", stamp, kWall));
  send(disparity_, disparity(stamp, kBaseline));
  expectCount(kDepth, "frames integrated", 1);
  expectCount(kDisparity, "frames integrated", 1);
  EXPECT_NE(mapState().first, before.first);
}

TEST_F(BadInputMatrix, DepthImages) {
  const auto before = mapState();
  // Unsupported encoding.
  ros::Time stamp = nextStamp();
  sensor_msgs::Image rgb = uniformImage("depth_optical", stamp, kWall);
  rgb.encoding = "rgb8";
  send(depth_, rgb);
  // camera_info of another size, stamped like its image.
  stamp = nextStamp();
  sendCameraInfo(depth_info_, kDepth, cameraInfo("depth_optical", stamp, 32, 24));
  send(depth_, uniformImage("depth_optical", stamp, kWall));
  // camera_info with zero focal length.
  stamp = nextStamp();
  sendCameraInfo(depth_info_, kDepth, cameraInfo("depth_optical", stamp, kWidth, kHeight, 0.0));
  send(depth_, uniformImage("depth_optical", stamp, kWall));
  expectCount(kDepth, dropped("encoding"), 1);
  expectCount(kDepth, dropped("camera_info"), 2);
  EXPECT_EQ(mapState(), before);
  EXPECT_EQ(countIn(observer_->diagnosticsAfter(kDepth, ros::WallTime::now()), "frames integrated"),
            1u);

  // A good frame, then the same stamp again: the duplicate is dropped.
  stamp = nextStamp(0.5);
  sendCameraInfo(depth_info_, kDepth, cameraInfo("depth_optical", stamp));
  send(depth_, uniformImage("depth_optical", stamp, kWall));
  expectCount(kDepth, "frames integrated", 2);
  const auto after_good = mapState();
  EXPECT_NE(after_good.first, before.first);
  send(depth_, uniformImage("depth_optical", stamp, kWall));
  expectCount(kDepth, dropped("duplicate stamp"), 1);
  EXPECT_EQ(mapState(), after_good);
}

TEST_F(BadInputMatrix, DisparityImages) {
  const auto before = mapState();
  const std::vector<double> bad_baselines = {0.0, -kBaseline};
  for (const double baseline : bad_baselines) send(disparity_, disparity(nextStamp(), baseline));
  stereo_msgs::DisparityImage mono16 = disparity(nextStamp(), kBaseline);
  mono16.image.encoding = "16UC1";
  send(disparity_, mono16);
  // camera_info of another size (the latest camera_info counts).
  sendCameraInfo(disparity_info_, kDisparity, cameraInfo("stereo_optical", last_stamp_, 32, 24));
  send(disparity_, disparity(nextStamp(), kBaseline));
  expectCount(kDisparity, dropped("invalid"), 4);
  EXPECT_EQ(mapState(), before);
  sendCameraInfo(disparity_info_, kDisparity, cameraInfo("stereo_optical", last_stamp_));
  send(disparity_, disparity(nextStamp(1.0), kBaseline));
  expectCount(kDisparity, "frames integrated", 2);
  EXPECT_NE(mapState().first, before.first);
  // Two cameras of different sizes on one camera_info topic: a disparity image takes the
  // camera_info of its own stamp, though another camera's arrived after it.
  const ros::Time own = nextStamp(1.2);
  sendCameraInfo(disparity_info_, kDisparity, cameraInfo("stereo_optical", own));
  sendCameraInfo(disparity_info_, kDisparity, cameraInfo("stereo_optical", nextStamp(1.2), 32, 24));
  send(disparity_, disparity(own, kBaseline));
  expectCount(kDisparity, "frames integrated", 3);
  expectCount(kDisparity, dropped("invalid"), 4);
}

TEST_F(BadInputMatrix, LaserScans) {
  ros::Time stamp = nextStamp();
  send(scan_, scan(stamp));
  expectCount(kLaser, "frames integrated", 1);
  const auto before = mapState();
  EXPECT_GT(before.second, 0u);
  sensor_msgs::LaserScan zero_increment = scan(nextStamp());
  zero_increment.angle_increment = 0.0f;
  send(scan_, zero_increment);
  sensor_msgs::LaserScan count_mismatch = scan(nextStamp());
  count_mismatch.ranges.resize(150);
  send(scan_, count_mismatch);
  sensor_msgs::LaserScan min_above_max = scan(nextStamp());
  min_above_max.range_min = 20.0f;
  send(scan_, min_above_max);
  expectCount(kLaser, dropped("rejected: bad scan or pose, tilted scanner"), 3);
  EXPECT_EQ(mapState(), before);
  send(scan_, scan(nextStamp(2.0)));  // a new place: more of the layer known
  expectCount(kLaser, "frames integrated", 2);
  EXPECT_GT(mapState().second, before.second);
}

TEST_F(BadInputMatrix, PointCloudsAndTf) {
  const auto before = mapState();
  sensor_msgs::PointCloud2 no_z = cloud("cloud_frame", nextStamp());
  no_z.fields.pop_back();
  send(cloud_, no_z);
  expectCount(kCloud, dropped("invalid cloud"), 1);
  // Extrapolation into the past: 30 s before the newest tf (its buffer keeps 10 s). A frame_id
  // of its own, since 30 s back in the stamps of one sensor is a jump back in time.
  send(cloud_, cloud("old_cloud_frame", last_stamp_ - ros::Duration(30.0)));
  expectCount(kCloud, dropped("tf: older than the tf buffer"), 1);
  // No transform at all (a frame nobody publishes, or one whose only transform had NaN, which
  // tf2 refuses): held back, then pushed out of the queue (~queue_size 5) by newer ones.
  geometry_msgs::TransformStamped nan_pose = transform("base_link", "nan_frame", last_stamp_);
  nan_pose.transform.translation.y = std::numeric_limits<double>::quiet_NaN();
  tf_->sendTransform(nan_pose);
  for (int i = 0; i < 6; ++i)
    send(cloud_, cloud(i % 2 == 0 ? "nowhere" : "nan_frame", nextStamp()));
  expectCount(kCloud, dropped("tf: no transform while queued"), 1);
  EXPECT_EQ(mapState(), before);
  send(cloud_, cloud("cloud_frame", nextStamp(1.5)));
  expectCount(kCloud, "frames integrated", 1);
  EXPECT_NE(mapState().first, before.first);
}

// A bag played again from its start (no /clock): the laser's stamps jump back by 30 s, more
// than the tf buffer keeps. The mapper clears its tf buffer, so the replayed transforms are
// accepted and the scan integrated.
TEST_F(BadInputMatrix, TimeJumpsBack) {
  expectCount(kLaser, "time jumps back (tf buffer cleared)", 0);
  const std::size_t integrated =
      countIn(observer_->diagnosticsAfter(kLaser, ros::WallTime::now()), "frames integrated");
  const ros::Time replayed = last_stamp_ - ros::Duration(30.0);
  send(scan_, scan(replayed));
  expectCount(kLaser, "time jumps back (tf buffer cleared)", 1);
  // The replayed transforms, sent again until taken: one that reached the tf listener before the
  // scan reached the mapper was refused as too old.
  for (int attempt = 0; attempt < 10; ++attempt) {
    tf_->sendTransform(transform("map", "base_link", replayed - ros::Duration(0.05), 3.0));
    tf_->sendTransform(transform("map", "base_link", replayed + ros::Duration(0.05), 3.0));
    if (observer_->waitForCount(kLaser, "frames integrated", integrated + 1, 0.5) ==
        integrated + 1) {
      break;
    }
  }
  expectCount(kLaser, "frames integrated", integrated + 1);
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "bad_input_matrix");
  ros::NodeHandle nh;
  return occupancy_fusion::runTestsWhileSpinning();
}
