// make_demo_recording end to end: the demo's bag from the bundled data (data/demo) holds every
// scan of the log with its pose on tf, StereoSGBM disparity in the ROS convention with its
// camera_info, the simulated depth images, and the static transforms that place them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <stereo_msgs/DisparityImage.h>
#include <tf2_msgs/TFMessage.h>

#include "occupancy_fusion/sensors/carmen_log.h"
#include "tool_test_support.h"

namespace occupancy_fusion {
namespace {

using namespace test_support;

fs::path demoData() { return fs::path(OCCUPANCY_FUSION_SOURCE_DIR) / "data" / "demo"; }

const geometry_msgs::TransformStamped* findTransform(
    const std::vector<geometry_msgs::TransformStamped>& transforms, const std::string& parent,
    const std::string& child) {
  for (const auto& transform : transforms) {
    if (transform.header.frame_id == parent && transform.child_frame_id == child) return &transform;
  }
  return nullptr;
}

class MakeDemoRecording : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ros::Time::init();
    dir_ = makeTempDir();
    log_ = demoData() / "intel" / "intel_flaser_every2nd.log.gz";
    const RunResult run = runTool(MAKE_DEMO_RECORDING_PATH,
                                  "--carmen '" + log_.string() + "' --stereo '" +
                                      (demoData() / "middlebury" / "ArtL").string() +
                                      "' --stereo-frames 2 --depth-frames 3 --rate 20 --output '" +
                                      (dir_ / "demo.bag").string() + "'",
                                  dir_);
    exit_code_ = run.exit_code;
    error_ = run.err;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  template <typename Message>
  std::vector<Message> messages(const std::string& topic) const {
    rosbag::Bag bag((dir_ / "demo.bag").string(), rosbag::bagmode::Read);
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    std::vector<Message> result;
    for (const rosbag::MessageInstance& instance : view) {
      result.push_back(*instance.instantiate<Message>());
    }
    return result;
  }

  static fs::path dir_;
  static fs::path log_;
  static int exit_code_;
  static std::string error_;
};

fs::path MakeDemoRecording::dir_;
fs::path MakeDemoRecording::log_;
int MakeDemoRecording::exit_code_ = -1;
std::string MakeDemoRecording::error_;

TEST_F(MakeDemoRecording, EveryScanWithItsCorrectedPoseOnTf) {
  ASSERT_EQ(exit_code_, 0) << error_;
  const std::vector<CarmenLaserScan> log = readCarmenLog(log_.string());
  ASSERT_EQ(log.size(), 455u);
  const auto scans = messages<sensor_msgs::LaserScan>("/scan");
  ASSERT_EQ(scans.size(), log.size());
  EXPECT_EQ(scans[0].header.frame_id, "laser");
  EXPECT_EQ(scans[0].ranges.size(), 180u);
  EXPECT_NEAR(scans[0].angle_min, -M_PI / 2, 1e-6);
  EXPECT_NEAR(scans[0].angle_increment, M_PI / 180, 1e-6);
  EXPECT_NEAR(scans[0].angle_max, -M_PI / 2 + 179 * M_PI / 180, 1e-5);
  EXPECT_EQ(scans[100].ranges, log[100].scan.ranges);
  // Restamped at 20 Hz, half a period after the start.
  EXPECT_NEAR((scans[10].header.stamp - scans[0].header.stamp).toSec(), 0.5, 1e-6);
  // One /tf per scan (map -> odom -> base_link) plus one per depth frame.
  const auto tf = messages<tf2_msgs::TFMessage>("/tf");
  EXPECT_EQ(tf.size(), log.size() + 3);
  std::size_t checked = 0;
  for (const auto& message : tf) {
    const auto* pose = findTransform(message.transforms, "odom", "base_link");
    if (pose == nullptr || pose->header.stamp != scans[200].header.stamp) continue;
    EXPECT_NEAR(pose->transform.translation.x, log[200].x, 1e-9);
    EXPECT_NEAR(pose->transform.translation.y, log[200].y, 1e-9);
    const auto& q = pose->transform.rotation;
    EXPECT_NEAR(2 * std::atan2(q.z, q.w), std::remainder(log[200].theta, 2 * M_PI), 1e-9);
    EXPECT_NE(findTransform(message.transforms, "map", "odom"), nullptr);
    ++checked;
  }
  EXPECT_EQ(checked, 1u);
}

TEST_F(MakeDemoRecording, StaticTransformsInOneMessage) {
  ASSERT_EQ(exit_code_, 0) << error_;
  const auto statics = messages<tf2_msgs::TFMessage>("/tf_static");
  ASSERT_EQ(statics.size(), 1u);
  const auto& transforms = statics[0].transforms;
  EXPECT_NE(findTransform(transforms, "base_link", "laser"), nullptr);
  EXPECT_NE(findTransform(transforms, "sim_base_link", "depth_camera_link"), nullptr);
  EXPECT_NE(findTransform(transforms, "depth_camera_link", "depth_camera_optical_frame"), nullptr);
  const auto* stereo = findTransform(transforms, "map", "stereo_0_optical_frame");
  ASSERT_NE(stereo, nullptr);
  EXPECT_NEAR(stereo->transform.translation.z, 1.2, 1e-9);  // camera height
  // Latched on playback, as a recorded static_transform_publisher: a mapper started after the
  // bag began still gets the mounts. /tf is not.
  const std::map<std::string, std::string> latching = latchingByTopic(dir_ / "demo.bag");
  EXPECT_EQ(latching.at("/tf_static"), "1");
  EXPECT_EQ(latching.at("/tf"), "");
}

TEST_F(MakeDemoRecording, SgbmDisparityInTheRosConvention) {
  ASSERT_EQ(exit_code_, 0) << error_;
  const auto disparities = messages<stereo_msgs::DisparityImage>("/stereo/disparity");
  const auto infos = messages<sensor_msgs::CameraInfo>("/stereo/left/camera_info");
  ASSERT_EQ(disparities.size(), 2u);
  ASSERT_EQ(infos.size(), 2u);
  const stereo_msgs::DisparityImage& d = disparities[0];
  EXPECT_EQ(d.header.frame_id, "stereo_0_optical_frame");
  EXPECT_EQ(infos[0].header.stamp, d.header.stamp);
  EXPECT_EQ(d.image.encoding, "32FC1");
  EXPECT_EQ(d.image.width, 347u);
  EXPECT_EQ(d.image.height, 277u);
  EXPECT_DOUBLE_EQ(d.f, 935.0);                     // ArtL's calib.txt
  EXPECT_NEAR(d.T, 0.16, 1e-6);                     // 160 mm
  EXPECT_FLOAT_EQ(d.min_disparity, 50.0f);          // doffs
  EXPECT_FLOAT_EQ(d.max_disparity, 50.0f + 64.0f);  // doffs + ndisp
  EXPECT_DOUBLE_EQ(infos[0].K[2], 148.0);           // cx of cam0
  ASSERT_EQ(d.image.data.size(), 347u * 277u * 4u);
  const float* values = reinterpret_cast<const float*>(d.image.data.data());
  std::vector<float> matched;
  for (std::size_t i = 0; i < 347u * 277u; ++i) {
    if (values[i] >= d.min_disparity && values[i] <= d.max_disparity) matched.push_back(values[i]);
  }
  // SGBM matches most of the textured scene; its disparities + doffs fall in the scene's range
  // (calib.txt: vmin 16, vmax 58 before doffs), not the raw 16..58 of an offset left out.
  EXPECT_GT(matched.size(), 347u * 277u / 2);
  std::nth_element(matched.begin(), matched.begin() + matched.size() / 2, matched.end());
  const float median = matched[matched.size() / 2];
  EXPECT_GT(median, 50.0f + 16.0f);
  EXPECT_LT(median, 50.0f + 58.0f);
  // Real matcher noise: not a smooth ground truth, some pixels are left unmatched.
  EXPECT_LT(matched.size(), 347u * 277u);
}

TEST_F(MakeDemoRecording, SimulatedDepthImages) {
  ASSERT_EQ(exit_code_, 0) << error_;
  const auto images = messages<sensor_msgs::Image>("/camera/depth/image");
  const auto infos = messages<sensor_msgs::CameraInfo>("/camera/depth/camera_info");
  ASSERT_EQ(images.size(), 3u);
  EXPECT_EQ(infos.size(), 3u);
  EXPECT_EQ(images[0].encoding, "16UC1");
  EXPECT_EQ(images[0].width, 160u);
  EXPECT_EQ(images[0].header.frame_id, "depth_camera_optical_frame");
}

TEST_F(MakeDemoRecording, RejectsBadArguments) {
  const std::string stereo = (demoData() / "middlebury" / "ArtL").string();
  for (const std::string& arguments :
       {"--stereo '" + stereo + "' --output x.bag",         // no --carmen
        "--carmen '" + log_.string() + "' --output x.bag",  // no --stereo
        "--carmen nowhere.log --stereo '" + stereo + "' --output x.bag",
        "--carmen '" + log_.string() + "' --stereo '" + dir_.string() + "' --output x.bag",
        "--carmen '" + log_.string() + "' --stereo '" + stereo + "' --rate 0 --output x.bag"}) {
    const RunResult bad = runTool(MAKE_DEMO_RECORDING_PATH, arguments, dir_);
    EXPECT_EQ(bad.exit_code, 2) << arguments;
    EXPECT_NE(bad.err.find("error:"), std::string::npos) << arguments;
  }
}

}  // namespace
}  // namespace occupancy_fusion
