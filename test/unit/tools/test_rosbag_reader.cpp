#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nav_msgs/Path.h>
#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include "occupancy_fusion/ros/conversions.h"
#include "occupancy_fusion/sim/trajectory.h"
#include "occupancy_fusion/tools/ros_conversions.h"
#include "occupancy_fusion/tools/rosbag_reader.h"
#include "occupancy_fusion/tools/simulated_recording.h"

#include "../../common/test_folder.h"
#include "tool_test_support.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

// The nodelets' cloud conversion, which the bag reader shares, keeps non-finite points (the
// integrators skip them); the reader drops them from its frames.
TEST(RosConversions, CloudRoundTripKeepsNonFinitePoints) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<Eigen::Vector3f> points = {
      {1.0f, 2.0f, 3.0f}, {nan, 0.0f, 1.0f}, {-4.5f, 0.25f, 1e3f}};
  const sensor_msgs::PointCloud2 cloud = cloudFromPoints(points, "camera", ros::Time(12.5));
  EXPECT_EQ(cloud.header.frame_id, "camera");
  EXPECT_DOUBLE_EQ(cloud.header.stamp.toSec(), 12.5);
  EXPECT_EQ(cloud.width * cloud.height, 3u);
  EXPECT_FALSE(cloud.is_dense);
  const std::vector<Eigen::Vector3f> back = transformedPoints(cloud, Eigen::Isometry3d::Identity());
  ASSERT_EQ(back.size(), 3u);
  EXPECT_EQ(back[0], points[0]);
  EXPECT_FALSE(back[1].allFinite());
  EXPECT_EQ(back[2], points[2]);
}

TEST(RosConversions, ReadsDoublePrecisionCloudsAndRejectsOthers) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header.frame_id = "lidar";
  sensor_msgs::PointCloud2Modifier modifier(cloud);
  modifier.setPointCloud2Fields(3, "x", 1, sensor_msgs::PointField::FLOAT64, "y", 1,
                                sensor_msgs::PointField::FLOAT64, "z", 1,
                                sensor_msgs::PointField::FLOAT64);
  modifier.resize(1);
  sensor_msgs::PointCloud2Iterator<double> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  *x = 0.5, *y = -1.5, *z = 2.25;
  const std::vector<Eigen::Vector3f> points =
      transformedPoints(cloud, Eigen::Isometry3d::Identity());
  ASSERT_EQ(points.size(), 1u);
  EXPECT_EQ(points[0], Eigen::Vector3f(0.5f, -1.5f, 2.25f));

  sensor_msgs::PointCloud2 no_z;
  no_z.header.frame_id = "lidar";
  sensor_msgs::PointCloud2Modifier(no_z).setPointCloud2Fields(
      2, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1, sensor_msgs::PointField::FLOAT32);
  try {
    transformedPoints(no_z, Eigen::Isometry3d::Identity());
    FAIL() << "a cloud without z was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("'lidar'"), std::string::npos);
  }
}

class SimulatedBagTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ros::Time::init();
    std::string pattern = (fs::temp_directory_path() / "rosbag_reader_test_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    config_.scene = "room";
    config_.frames = 4;
    config_.rate_hz = 2.0;
    std::vector<std::unique_ptr<SimulatedSensor>> sensors;
    sensors.push_back(std::make_unique<PointCloudCameraSensor>(camera_));
    writeSimulatedRecording(config_, sensors, (dir_ / "room.bag").string());
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static fs::path dir_;
  static SimulatedRecordingConfig config_;
  static PointCloudCameraConfig camera_;
};

fs::path SimulatedBagTest::dir_;
SimulatedRecordingConfig SimulatedBagTest::config_;
PointCloudCameraConfig SimulatedBagTest::camera_;

struct CollectingConsumer : FrameConsumer {
  void onPointCloud(const PointCloudFrame& frame) override { clouds.push_back(frame); }
  void onDepthImage(const DepthImageFrame& frame) override { depth.push_back(frame); }
  void onDisparityImage(const DisparityFrame& frame) override { disparity.push_back(frame); }
  void onLaserScan(const LaserScanFrame& frame) override { scans.push_back(frame); }
  void onUnreadable(const FrameHeader&, const std::string& why) override { errors.push_back(why); }
  void onTrajectory(const std::vector<StampedPose>& keyframes, double stamp) override {
    trajectories.push_back({stamp, keyframes, clouds.size()});
  }
  struct Trajectory {
    double stamp;
    std::vector<StampedPose> keyframes;
    std::size_t clouds_before;  // frames delivered before it
  };
  std::vector<Trajectory> trajectories;
  std::vector<PointCloudFrame> clouds;
  std::vector<DepthImageFrame> depth;
  std::vector<DisparityFrame> disparity;
  std::vector<LaserScanFrame> scans;
  std::vector<std::string> errors;
};

TEST_F(SimulatedBagTest, ReaderDeliversEveryCloudInTimeOrder) {
  RosbagReader reader((dir_ / "room.bag").string(), {});
  EXPECT_EQ(reader.cloudTopics(), std::vector<std::string>{"/cloud_in"});
  EXPECT_EQ(reader.frameCount(), 4u);
  CollectingConsumer consumer;
  std::vector<std::size_t> progress;
  reader.read(&consumer, [&](std::size_t done) { progress.push_back(done); });
  EXPECT_EQ(progress, (std::vector<std::size_t>{1, 2, 3, 4}));
  ASSERT_EQ(consumer.clouds.size(), 4u);
  EXPECT_TRUE(consumer.errors.empty());
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(consumer.clouds[k].header.frame_id, "camera_optical_frame");
    EXPECT_EQ(consumer.clouds[k].header.source, "/cloud_in");
    EXPECT_NEAR(consumer.clouds[k].header.stamp, config_.start_time + k / config_.rate_hz, 1e-6);
    EXPECT_GT(consumer.clouds[k].points.size(), 1000u);  // the camera always sees walls
  }
}

TEST_F(SimulatedBagTest, TfChainGivesTheSimulatedCameraPose) {
  RosbagReader reader((dir_ / "room.bag").string(), {"/cloud_in"});
  const SimulatedWorld world = makeSimulatedWorld("room", config_.frames);
  for (int k = 0; k < config_.frames; ++k) {
    const Eigen::Isometry3d expected =
        world.T_map_base[k] * camera_.T_base_link * sim::opticalFrameInBody();
    std::string why;
    const std::optional<Eigen::Isometry3d> pose = reader.poses().lookup(
        "map", "camera_optical_frame", config_.start_time + k / config_.rate_hz, &why);
    ASSERT_TRUE(pose) << why;
    EXPECT_TRUE(pose->matrix().isApprox(expected.matrix(), 1e-9)) << "frame " << k;
  }
  std::string why;
  EXPECT_FALSE(reader.poses().lookup("map", "nowhere", config_.start_time, &why));
  EXPECT_NE(why.find("nowhere"), std::string::npos) << why;
  // After the last pose: tf2 does not extrapolate.
  EXPECT_FALSE(
      reader.poses().lookup("map", "camera_optical_frame", config_.start_time + 100, &why));
}

TEST_F(SimulatedBagTest, PointsTransformedWithTheTfPoseLieOnTheScene) {
  RosbagReader reader((dir_ / "room.bag").string(), {});
  CollectingConsumer consumer;
  reader.read(&consumer, nullptr);
  const sim::Scene scene = makeSimulatedWorld("room", 1).scene;
  const PointCloudFrame& frame = consumer.clouds.at(2);
  std::string why;
  const std::optional<Eigen::Isometry3d> pose =
      reader.poses().lookup("map", frame.header.frame_id, frame.header.stamp, &why);
  ASSERT_TRUE(pose) << why;
  for (const Eigen::Vector3f& point : frame.points) {
    ASSERT_LT(scene.distanceToSurface(*pose * point.cast<double>()), 1e-4);
  }
}

// A SLAM system's path (--path-topic) comes to the consumer in time order with the frames, each
// keyframe with its own stamp and pose; it is never read unless asked for, and does not count as
// a frame.
TEST_F(SimulatedBagTest, PathMessagesReachTheConsumerBetweenTheFrames) {
  const fs::path bag_path = dir_ / "with_path.bag";
  fs::copy_file(dir_ / "room.bag", bag_path, fs::copy_options::overwrite_existing);
  const double between = config_.start_time + 1.25 / config_.rate_hz;  // after frames 0 and 1
  {
    rosbag::Bag bag(bag_path.string(), rosbag::bagmode::Append);
    nav_msgs::Path path;
    path.header.frame_id = "map";
    path.header.stamp = ros::Time(between);
    for (int k = 0; k < 2; ++k) {
      geometry_msgs::PoseStamped pose;
      pose.header.frame_id = "map";
      pose.header.stamp = ros::Time(config_.start_time + k / config_.rate_hz);
      pose.pose.position.x = 1.5 * k;
      pose.pose.orientation.z = std::sin(0.25);  // 0.5 rad about z
      pose.pose.orientation.w = std::cos(0.25);
      path.poses.push_back(pose);
    }
    bag.write("/slam/path", ros::Time(between), path);
  }
  RosbagTopics topics;
  topics.clouds = {"/cloud_in"};
  topics.paths = {"/slam/path"};
  RosbagReader reader({bag_path.string()}, topics);
  EXPECT_EQ(reader.frameCount(), 4u);
  CollectingConsumer consumer;
  std::size_t progress = 0;
  reader.read(&consumer, [&](std::size_t done) { progress = done; });
  EXPECT_EQ(progress, 4u);
  ASSERT_EQ(consumer.trajectories.size(), 1u);
  const CollectingConsumer::Trajectory& path = consumer.trajectories[0];
  EXPECT_DOUBLE_EQ(path.stamp, between);
  EXPECT_EQ(path.clouds_before, 2u);
  ASSERT_EQ(path.keyframes.size(), 2u);
  EXPECT_NEAR(path.keyframes[1].stamp, config_.start_time + 1.0 / config_.rate_hz, 1e-6);
  EXPECT_NEAR(path.keyframes[1].pose.translation().x(), 1.5, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(path.keyframes[1].pose.linear()).angle(), 0.5, 1e-9);

  // Without asking for it: no path.
  RosbagReader clouds_only({bag_path.string()}, RosbagTopics{{"/cloud_in"}, {}, {}, {}, {}});
  CollectingConsumer other;
  clouds_only.read(&other, {});
  EXPECT_TRUE(other.trajectories.empty());
  // A path topic the bags do not hold is an error naming it.
  RosbagTopics missing = topics;
  missing.paths = {"/mapPath"};
  EXPECT_THROW(RosbagReader({bag_path.string()}, missing), std::invalid_argument);
}

TEST_F(SimulatedBagTest, ReaderRejectsMissingTopicsAndFiles) {
  EXPECT_THROW(RosbagReader((dir_ / "room.bag").string(), {"/tf"}), std::invalid_argument);
  EXPECT_THROW(RosbagReader((dir_ / "absent.bag").string(), {}), std::invalid_argument);
}

TEST(SimulatedWorld, KnowsItsScenesAndRejectsOthers) {
  for (const std::string& name : simulatedSceneNames()) {
    EXPECT_EQ(makeSimulatedWorld(name, 5).T_map_base.size(), 5u) << name;
  }
  EXPECT_THROW(makeSimulatedWorld("attic", 5), std::invalid_argument);
  EXPECT_THROW(makeSimulatedWorld("room", 0), std::invalid_argument);
}

// Sensors at rates below the recording's (--every) and camera images of another size
// (--image-size): per topic the messages of every n-th frame, stamped n frames apart, and the
// cameras' intrinsics scaled to the same field of view.
TEST(SimulatedRecording, WritesEachSensorAtItsOwnRateAndSize) {
  const TemporaryFolder temporary;
  const std::string path = (temporary.path() / "rates.bag").string();
  SimulatedSensorOptions options;
  options.image_width = 64;
  options.image_height = 48;
  options.every = {{"depth", 4}, {"disparity", 8}, {"scan", 3}};
  SimulatedRecordingConfig config;
  config.frames = 24;
  config.rate_hz = 120.0;
  writeSimulatedRecording(config, makeSimulatedSensors({"depth", "disparity", "scan"}, options),
                          path);
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::map<std::string, std::vector<double>> stamps;
  for (const rosbag::MessageInstance& message : rosbag::View(bag)) {
    stamps[message.getTopic()].push_back(message.getTime().toSec());
    if (const auto image = message.instantiate<sensor_msgs::Image>()) {
      EXPECT_EQ(image->width, 64u);
      EXPECT_EQ(image->height, 48u);
    }
    if (const auto info = message.instantiate<sensor_msgs::CameraInfo>()) {
      EXPECT_NEAR(info->K[0], 138.6 * 64 / 160, 1e-9);  // fx of 160 px, scaled
      EXPECT_NEAR(info->K[2], 31.5, 1e-9);              // cx at the centre
    }
  }
  const std::map<std::string, std::pair<std::size_t, int>> expected = {
      {"/camera/depth/image", {6, 4}},
      {"/stereo/disparity", {3, 8}},
      {"/scan_front", {8, 3}},
      {"/scan_rear", {8, 3}},
      {"/tf", {24, 1}}};
  for (const auto& [topic, count_and_every] : expected) {
    const auto& [count, every] = count_and_every;
    ASSERT_EQ(stamps[topic].size(), count) << topic;
    for (std::size_t i = 1; i < count; ++i) {
      EXPECT_NEAR(stamps[topic][i] - stamps[topic][i - 1], every / 120.0, 1e-6) << topic;
    }
  }
  // The mounts on /tf_static are latched on playback, as rosbag record keeps a
  // static_transform_publisher's: a mapper started after the bag began still gets them.
  for (const auto& [topic, latching] : test_support::latchingByTopic(path)) {
    EXPECT_EQ(latching, topic == "/tf_static" ? "1" : "") << topic;
  }
  options.every = {{"cloud", 2}};  // not recorded
  EXPECT_THROW(makeSimulatedSensors({"depth"}, options), std::invalid_argument);
  options.every = {{"depth", 0}};
  EXPECT_THROW(makeSimulatedSensors({"depth"}, options), std::invalid_argument);
}

}  // namespace
}  // namespace occupancy_fusion
