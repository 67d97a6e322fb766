// Test node of stereo_matcher_pairs.test: the RTAB-Map pairs through the StereoMatcher nodelet
// (and on into the DisparityMapper). The reference is the core: the same images converted to grey
// as OpenCV does, rectified by CachedRectification and matched by StereoMatcher with the
// nodelet's own parameters.
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <stereo_msgs/DisparityImage.h>
#include <tf2_msgs/TFMessage.h>
#include <opencv2/imgproc.hpp>

#include "../common/rtabmap_pair.h"
#include "occupancy_fusion/SaveMap.h"
#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/params/stereo_matcher_config_reader.h"
#include "occupancy_fusion/ros/ros_parameter_source.h"
#include "occupancy_fusion/sensors/stereo_matcher.h"
#include "occupancy_fusion/sensors/stereo_rectification.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

const char* kFrame = "stereo_left_optical_frame";

sensor_msgs::Image imageMessage(const cv::Mat& image, const ros::Time& stamp) {
  sensor_msgs::Image message;
  message.header.frame_id = kFrame;
  message.header.stamp = stamp;
  message.width = static_cast<std::uint32_t>(image.cols);
  message.height = static_cast<std::uint32_t>(image.rows);
  message.encoding = image.channels() == 3 ? sensor_msgs::image_encodings::BGR8
                                           : sensor_msgs::image_encodings::MONO8;
  message.step = static_cast<std::uint32_t>(image.cols * image.elemSize());
  message.data.resize(static_cast<std::size_t>(message.step) * image.rows);
  for (int v = 0; v < image.rows; ++v) {
    std::memcpy(&message.data[static_cast<std::size_t>(v) * message.step], image.ptr(v),
                message.step);
  }
  return message;
}

sensor_msgs::CameraInfo infoMessage(const CameraCalibration& calibration, const ros::Time& stamp) {
  sensor_msgs::CameraInfo info;
  info.header.frame_id = kFrame;
  info.header.stamp = stamp;
  info.width = static_cast<std::uint32_t>(calibration.width);
  info.height = static_cast<std::uint32_t>(calibration.height);
  info.distortion_model = calibration.distortion_model;
  info.D = calibration.D;
  std::copy(calibration.K.begin(), calibration.K.end(), info.K.begin());
  std::copy(calibration.R.begin(), calibration.R.end(), info.R.begin());
  std::copy(calibration.P.begin(), calibration.P.end(), info.P.begin());
  return info;
}

// What the test publishes and what comes back.
class StereoRig {
 public:
  explicit StereoRig(ros::NodeHandle& node_handle) {
    left_image_ = node_handle.advertise<sensor_msgs::Image>("stereo/left/image_raw", 4);
    right_image_ = node_handle.advertise<sensor_msgs::Image>("stereo/right/image_raw", 4);
    left_info_ = node_handle.advertise<sensor_msgs::CameraInfo>("stereo/left/camera_info", 4);
    right_info_ = node_handle.advertise<sensor_msgs::CameraInfo>("stereo/right/camera_info", 4);
    disparity_sub_ = node_handle.subscribe("stereo/disparity", 10, &StereoRig::onDisparity, this);
    diagnostics_sub_ = node_handle.subscribe("/diagnostics", 10, &StereoRig::onDiagnostics, this);
    log_sub_ = node_handle.subscribe("/rosout", 100, &StereoRig::onLog, this);
  }

  bool connected() const {
    return left_image_.getNumSubscribers() > 0 && right_image_.getNumSubscribers() > 0 &&
           left_info_.getNumSubscribers() > 0 && right_info_.getNumSubscribers() > 0 &&
           disparity_sub_.getNumPublishers() > 0;
  }

  // Publishes the inputs of one stereo set at `stamp`; a null image or info is left out.
  void publish(const cv::Mat* left, const CameraCalibration* left_calibration, const cv::Mat* right,
               const CameraCalibration* right_calibration, const ros::Time& stamp) {
    if (left) left_image_.publish(imageMessage(*left, stamp));
    if (left_calibration) left_info_.publish(infoMessage(*left_calibration, stamp));
    if (right) right_image_.publish(imageMessage(*right, stamp));
    if (right_calibration) right_info_.publish(infoMessage(*right_calibration, stamp));
  }

  void publishRightImage(const sensor_msgs::Image& image) { right_image_.publish(image); }

  stereo_msgs::DisparityImage::ConstPtr disparityAt(const ros::Time& stamp) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = disparities_.find(stamp);
    return it == disparities_.end() ? nullptr : it->second;
  }
  std::size_t disparitiesReceived() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return disparities_.size();
  }
  std::size_t mapperCount(const std::string& key) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = mapper_counts_.find(key);
    return it == mapper_counts_.end() ? 0 : it->second;
  }
  // The first warning of the matcher that contains `text`; "" when none came.
  std::string matcherWarning(const std::string& text) const {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const std::string& message : warnings_) {
      if (message.find(text) != std::string::npos) return message;
    }
    return "";
  }

 private:
  void onDisparity(const stereo_msgs::DisparityImage::ConstPtr& disparity) {
    std::lock_guard<std::mutex> lock(mutex_);
    disparities_[disparity->header.stamp] = disparity;
  }
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& array) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& status : array->status) {
      // Not diagnostic_updater's "Node starting up" placeholder, which has no values.
      if (!isTask(status, "disparity mapping") || status.values.empty()) continue;
      for (const char* key : {"images integrated", "images dropped (invalid)"}) {
        mapper_counts_[key] = diagnosticCount(status, key);
      }
    }
  }
  void onLog(const rosgraph_msgs::Log::ConstPtr& log) {
    if (log->level < rosgraph_msgs::Log::WARN) return;
    std::lock_guard<std::mutex> lock(mutex_);
    warnings_.push_back(log->msg);
  }

  ros::Publisher left_image_, right_image_, left_info_, right_info_;
  ros::Subscriber disparity_sub_, diagnostics_sub_, log_sub_;
  mutable std::mutex mutex_;
  std::map<ros::Time, stereo_msgs::DisparityImage::ConstPtr> disparities_;
  std::map<std::string, std::size_t> mapper_counts_;
  std::vector<std::string> warnings_;
};

StereoRig* g_rig = nullptr;
std::string g_data_dir;
std::string g_matcher_namespace;

// Publishes the set until its disparity comes back (a first set can be lost while the
// subscriptions connect); the disparity, or null after the timeout.
stereo_msgs::DisparityImage::ConstPtr matchOnce(const cv::Mat& left, const CameraCalibration& lc,
                                                const cv::Mat& right, const CameraCalibration& rc,
                                                const ros::Time& stamp) {
  stereo_msgs::DisparityImage::ConstPtr disparity;
  waitUntil(
      [&] {
        if (!g_rig->disparityAt(stamp)) g_rig->publish(&left, &lc, &right, &rc, stamp);
        for (int i = 0; i < 20 && !(disparity = g_rig->disparityAt(stamp)); ++i) {
          ros::WallDuration(0.05).sleep();
        }
        return disparity != nullptr;
      },
      20.0);
  return disparity;
}

// Each test has a folder of its own (the map files of the online/offline comparison).
class StereoMatcherPairs : public TestFolder {};

TEST_F(StereoMatcherPairs, PublishedDisparityEqualsTheCoreMatchersOnTheRtabmapPairs) {
  ASSERT_TRUE(waitUntil([] { return g_rig->connected(); }, 20.0))
      << "the StereoMatcher did not subscribe to the test's inputs";
  const CameraCalibration left_calibration = test::rtabmapCalibration(g_data_dir, "left");
  const CameraCalibration right_calibration = test::rtabmapCalibration(g_data_dir, "right");
  // The reference, from the matcher's own parameters.
  const StereoMatcherConfig config =
      readStereoMatcherConfig(RosParameterSource(ros::NodeHandle(g_matcher_namespace)));
  StereoMatcher matcher(config);
  CachedRectification left_rectification, right_rectification;
  const StereoGeometry geometry = stereoGeometryOf(left_calibration, right_calibration);

  const ros::Time first(1000.0);
  int frame_index = 0;
  for (const std::string frame : {"50", "60"}) {
    const ros::Time stamp = first + ros::Duration(0.1 * frame_index++);
    const cv::Mat left = test::rtabmapImage(g_data_dir, "left", frame);
    const cv::Mat right = test::rtabmapImage(g_data_dir, "right", frame);
    ASSERT_EQ(left.type(), CV_8UC3);   // published as bgr8
    ASSERT_EQ(right.type(), CV_8UC1);  // published as mono8
    const stereo_msgs::DisparityImage::ConstPtr published =
        matchOnce(left, left_calibration, right, right_calibration, stamp);
    ASSERT_TRUE(published) << "no disparity for frame " << frame;

    cv::Mat left_grey, left_rectified, right_rectified, expected;
    cv::cvtColor(left, left_grey, cv::COLOR_BGR2GRAY);
    left_rectification.rectify(left_calibration, left_grey, &left_rectified);
    right_rectification.rectify(right_calibration, right, &right_rectified);
    matcher.match(left_rectified, right_rectified, geometry.principal_point_offset, &expected);

    EXPECT_EQ(published->header.frame_id, kFrame);
    EXPECT_EQ(published->image.header.stamp, stamp);
    ASSERT_EQ(published->image.encoding, "32FC1");
    ASSERT_EQ(published->image.width, 640u);
    ASSERT_EQ(published->image.height, 480u);
    ASSERT_EQ(published->image.step, 640u * 4);
    std::size_t different = 0, valid = 0;
    for (int v = 0; v < 480; ++v) {
      for (int u = 0; u < 640; ++u) {
        float value;
        std::memcpy(&value, &published->image.data[(static_cast<std::size_t>(v) * 640 + u) * 4], 4);
        different += value == expected.at<float>(v, u) ? 0 : 1;
        valid += value >= published->min_disparity ? 1 : 0;
      }
    }
    EXPECT_EQ(different, 0u) << "frame " << frame;
    ROS_INFO("frame %s: %zu of 307200 pixels matched", frame.c_str(), valid);
    EXPECT_GT(valid, 250000u) << "frame " << frame;

    // stereo_image_proc's fields: f and T of the right camera's P (fx 487.6087, Tx -58.3627),
    // the searched range 0..63, 1/16 px, and the valid window of a 5 px window and 64
    // disparities: x from 64 + 2 - 1 = 65 to 639 - 2, y from 2 to 477.
    EXPECT_FLOAT_EQ(published->f, 487.60873413085938f);
    EXPECT_NEAR(published->T, 58.3627 / 487.6087, 1e-6);
    EXPECT_FLOAT_EQ(published->min_disparity, 0.0f);
    EXPECT_FLOAT_EQ(published->max_disparity, 63.0f);
    EXPECT_FLOAT_EQ(published->delta_d, 0.0625f);
    EXPECT_EQ(published->valid_window.x_offset, 65u);
    EXPECT_EQ(published->valid_window.y_offset, 2u);
    EXPECT_EQ(published->valid_window.width, 572u);
    EXPECT_EQ(published->valid_window.height, 475u);
  }

  // The DisparityMapper behind the matcher integrated both.
  EXPECT_TRUE(waitUntil([] { return g_rig->mapperCount("images integrated") >= 2; }, 10.0))
      << "the DisparityMapper integrated " << g_rig->mapperCount("images integrated");
  EXPECT_EQ(g_rig->mapperCount("images dropped (invalid)"), 0u);
}

// Runs after the two pairs above were matched and mapped, before the sets below (gtest keeps the
// order of a suite's tests): the
// map the DisparityMapper built online from the matcher's disparity equals, voxel for voxel,
// what offline_mapper builds from the same disparity messages, camera_info and pose.
TEST_F(StereoMatcherPairs, OnlineMapEqualsOfflineMappersOnTheSameDisparity) {
  ASSERT_TRUE(waitUntil([] { return g_rig->mapperCount("images integrated") >= 2; }, 10.0));
  SaveMap save;
  save.request.prefix = path("online");
  ASSERT_TRUE(ros::service::call("/map_server/save_map", save));
  ASSERT_TRUE(save.response.success) << save.response.message;

  // The recording: the pose of stereo.test's static transform, the left camera_info the mapper
  // read and the two disparity images as the matcher published them.
  const CameraCalibration left_calibration = test::rtabmapCalibration(g_data_dir, "left");
  const std::string bag_path = path("matched.bag");
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
    geometry_msgs::TransformStamped pose;
    pose.header.frame_id = "map";
    pose.child_frame_id = kFrame;
    pose.transform.translation.z = 1.0;
    // static_transform_publisher's yaw -pi/2, pitch 0, roll -pi/2: optical z along map x.
    const Eigen::Quaterniond q = Eigen::AngleAxisd(-1.5707963, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(-1.5707963, Eigen::Vector3d::UnitX());
    pose.transform.rotation.x = q.x();
    pose.transform.rotation.y = q.y();
    pose.transform.rotation.z = q.z();
    pose.transform.rotation.w = q.w();
    tf2_msgs::TFMessage statics;
    statics.transforms = {pose};
    const ros::Time first(1000.0);
    bag.write("/tf_static", first - ros::Duration(0.1), statics);
    for (int frame = 0; frame < 2; ++frame) {
      const ros::Time stamp = first + ros::Duration(0.1 * frame);
      const stereo_msgs::DisparityImage::ConstPtr disparity = g_rig->disparityAt(stamp);
      ASSERT_TRUE(disparity) << "frame " << frame;
      bag.write("/stereo/left/camera_info", stamp, infoMessage(left_calibration, stamp));
      bag.write("/stereo/disparity", stamp, *disparity);
    }
  }
  std::string disparity_config, map_config;
  ASSERT_TRUE(ros::param::get("~disparity_mapper_config", disparity_config));
  ASSERT_TRUE(ros::param::get("~map_server_config", map_config));
  int exit_code = -1;
  const std::string output =
      runCommand(std::string(OFFLINE_MAPPER_PATH) + " --config '" + disparity_config +
                     "' --config '" + map_config + "' --bag '" + bag_path + "' --output-dir '" +
                     folder_.string() + "' --name offline",
                 &exit_code);
  ASSERT_EQ(exit_code, 0) << output;
  EXPECT_NE(output.find("disparity: 2 integrated, 0 skipped"), std::string::npos) << output;

  double resolution = 0.0;
  ASSERT_TRUE(ros::param::get("/disparity_mapper/resolution", resolution));
  const VoxelDump online = knownVoxelsOf(path("online.ot"), resolution);
  const VoxelDump offline = knownVoxelsOf(path("offline.ot"), resolution);
  std::size_t occupied = 0, differing = 0;
  for (const auto& [index, log_odds] : online) {
    occupied += log_odds > 0.0f ? 1 : 0;
    const auto other = offline.find(index);
    differing += other == offline.end() || other->second != log_odds ? 1 : 0;
  }
  EXPECT_GT(online.size(), 1000u);
  EXPECT_GT(occupied, 100u);
  EXPECT_EQ(online.size(), offline.size());
  EXPECT_EQ(differing, 0u) << "of " << online.size() << " voxels";
  RecordProperty("voxels", static_cast<int>(online.size()));
  RecordProperty("voxels_occupied", static_cast<int>(occupied));
}

TEST_F(StereoMatcherPairs, BadPairsAreDroppedAndTheMatcherRunsOn) {
  const CameraCalibration left_calibration = test::rtabmapCalibration(g_data_dir, "left");
  const CameraCalibration right_calibration = test::rtabmapCalibration(g_data_dir, "right");
  const cv::Mat left = test::rtabmapImage(g_data_dir, "left", "50");
  const cv::Mat right = test::rtabmapImage(g_data_dir, "right", "50");

  // Right image and camera_info of another size than the left ones.
  cv::Mat small_right;
  cv::resize(right, small_right, cv::Size(320, 240));
  CameraCalibration small_calibration = right_calibration;
  small_calibration.width = 320;
  small_calibration.height = 240;
  const ros::Time size_mismatch(2000.0);
  g_rig->publish(&left, &left_calibration, &small_right, &small_calibration, size_mismatch);
  // Left and right swapped: the baseline comes out negative.
  const ros::Time swapped(2000.1);
  g_rig->publish(&right, &right_calibration, &left, &left_calibration, swapped);
  // An encoding the matcher does not take (16-bit).
  cv::Mat deep;
  right.convertTo(deep, CV_16UC1, 256.0);
  const ros::Time wrong_encoding(2000.2);
  sensor_msgs::Image deep_message = imageMessage(right, wrong_encoding);
  deep_message.encoding = "mono16";
  deep_message.step = 640 * 2;
  deep_message.data.assign(reinterpret_cast<const std::uint8_t*>(deep.data),
                           reinterpret_cast<const std::uint8_t*>(deep.data) + 640 * 480 * 2);
  g_rig->publish(&left, &left_calibration, nullptr, &right_calibration, wrong_encoding);
  g_rig->publishRightImage(deep_message);

  // A good pair after them is matched.
  const ros::Time good(2001.0);
  EXPECT_TRUE(matchOnce(left, left_calibration, right, right_calibration, good));
  EXPECT_FALSE(g_rig->disparityAt(size_mismatch));
  EXPECT_FALSE(g_rig->disparityAt(swapped));
  EXPECT_FALSE(g_rig->disparityAt(wrong_encoding));
  // Each was reported with what is wrong.
  EXPECT_TRUE(waitUntil([] { return !g_rig->matcherWarning("stereo pair dropped").empty(); }, 5.0));
}

TEST_F(StereoMatcherPairs, AMissingInputIsNamed) {
  const CameraCalibration left_calibration = test::rtabmapCalibration(g_data_dir, "left");
  const cv::Mat left = test::rtabmapImage(g_data_dir, "left", "50");
  const cv::Mat right = test::rtabmapImage(g_data_dir, "right", "50");
  // Everything but the right camera_info, at 5 Hz, for over two of the matcher's 5 s report
  // periods.
  ros::Time stamp(3000.0);
  const bool named = waitUntil(
      [&] {
        g_rig->publish(&left, &left_calibration, &right, nullptr, stamp);
        stamp += ros::Duration(0.2);
        ros::WallDuration(0.15).sleep();
        return !g_rig->matcherWarning("nothing received on").empty();
      },
      15.0);
  ASSERT_TRUE(named) << "no warning about the missing input";
  const std::string warning = g_rig->matcherWarning("nothing received on");
  EXPECT_NE(warning.find("stereo/right/camera_info"), std::string::npos) << warning;
  EXPECT_EQ(warning.find("stereo/left/camera_info"), std::string::npos) << warning;
  EXPECT_EQ(warning.find("image_raw"), std::string::npos) << warning;
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "stereo_matcher_pairs");
  ros::NodeHandle node_handle;
  ros::NodeHandle private_node_handle("~");
  private_node_handle.getParam("data_dir", occupancy_fusion::g_data_dir);
  private_node_handle.getParam("matcher_namespace", occupancy_fusion::g_matcher_namespace);
  occupancy_fusion::StereoRig rig(node_handle);
  occupancy_fusion::g_rig = &rig;
  return occupancy_fusion::runTestsWhileSpinning();
}
