// simulate_recording --drift end to end: the building loop with drifting odometry and the SLAM
// stand-in. The bag's map -> odom changes only at the stand-in's corrections, right after one it
// composes with odom -> base_link to the true pose, and /slam/path carries the keyframes, true
// after a correction and drifted before it.
#include <gtest/gtest.h>

#include <cmath>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include <nav_msgs/Path.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>
#include <Eigen/Geometry>

#include "occupancy_fusion/sim/localisation_stand_in.h"
#include "occupancy_fusion/sim/odometry_drift.h"
#include "occupancy_fusion/sim/scenes.h"
#include "tool_test_support.h"

namespace occupancy_fusion {
namespace {

using namespace test_support;

constexpr int kFrames = 552;  // 1.25 laps of 88.28 m in 0.2 m steps

template <typename Message>
std::vector<Message> messages(const fs::path& bag_path, const std::string& topic) {
  rosbag::Bag bag(bag_path.string(), rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  std::vector<Message> result;
  for (const rosbag::MessageInstance& instance : view) {
    result.push_back(*instance.instantiate<Message>());
  }
  return result;
}

Eigen::Isometry3d poseOf(const geometry_msgs::Pose& pose) {
  Eigen::Isometry3d result;
  tf2::fromMsg(pose, result);
  return result;
}

double gap(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

// Per frame (in stamp order), the transform parent -> child from the bag's /tf.
std::vector<Eigen::Isometry3d> transforms(const fs::path& bag_path, const std::string& parent,
                                          const std::string& child) {
  std::vector<Eigen::Isometry3d> result;
  for (const tf2_msgs::TFMessage& message : messages<tf2_msgs::TFMessage>(bag_path, "/tf")) {
    for (const geometry_msgs::TransformStamped& transform : message.transforms) {
      if (transform.header.frame_id == parent && transform.child_frame_id == child) {
        result.push_back(tf2::transformToEigen(transform));
      }
    }
  }
  return result;
}

class SimulateRecordingDrift : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ros::Time::init();
    dir_ = makeTempDir();
    const RunResult run = runTool(
        SIMULATE_RECORDING_PATH,
        "--scene building --drift 3 --sensors scan --output '" + bag().string() + "'", dir_);
    exit_code_ = run.exit_code;
    error_ = run.err;
    if (exit_code_ != 0) return;
    map_odom_ = transforms(bag(), "map", "odom");
    odom_base_ = transforms(bag(), "odom", "base_link");
    for (const nav_msgs::Path& path : messages<nav_msgs::Path>(bag(), "/ground_truth/path")) {
      for (const geometry_msgs::PoseStamped& pose : path.poses) {
        truth_by_stamp_[pose.header.stamp] = poseOf(pose.pose);
      }
    }
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path bag() { return dir_ / "building.bag"; }
  // Frame k's stamp: 1000 s + k / 5 Hz.
  static ros::Time stampOf(int frame) { return ros::Time(1000.0 + frame / 5.0); }
  // Frames at which map -> odom changed.
  static std::vector<int> changes() {
    std::vector<int> result;
    for (std::size_t k = 1; k < map_odom_.size(); ++k) {
      if (gap(map_odom_[k], map_odom_[k - 1]) > 0.0) result.push_back(static_cast<int>(k));
    }
    return result;
  }

  static fs::path dir_;
  static int exit_code_;
  static std::string error_;
  static std::vector<Eigen::Isometry3d> map_odom_, odom_base_;
  static std::map<ros::Time, Eigen::Isometry3d> truth_by_stamp_;
};

fs::path SimulateRecordingDrift::dir_;
int SimulateRecordingDrift::exit_code_ = -1;
std::string SimulateRecordingDrift::error_;
std::vector<Eigen::Isometry3d> SimulateRecordingDrift::map_odom_,
    SimulateRecordingDrift::odom_base_;
std::map<ros::Time, Eigen::Isometry3d> SimulateRecordingDrift::truth_by_stamp_;

TEST_F(SimulateRecordingDrift, TheTrueLoopOnceAtTheEnd) {
  ASSERT_EQ(exit_code_, 0) << error_;
  const auto truth = messages<nav_msgs::Path>(bag(), "/ground_truth/path");
  ASSERT_EQ(truth.size(), 1u);
  EXPECT_EQ(truth[0].header.frame_id, "map");
  EXPECT_EQ(truth[0].header.stamp, stampOf(kFrames - 1));
  ASSERT_EQ(truth[0].poses.size(), static_cast<std::size_t>(kFrames));
  const std::vector<Eigen::Isometry3d> loop = sim::buildingLoopPath(0.2, 1.25);
  for (int k = 0; k < kFrames; k += 50) {
    EXPECT_EQ(truth[0].poses[k].header.stamp, stampOf(k));
    EXPECT_LT(gap(poseOf(truth[0].poses[k].pose), loop[k]), 1e-9) << k;
  }
  EXPECT_EQ(latchingByTopic(bag())["/slam/path"], "1");
  EXPECT_EQ(latchingByTopic(bag())["/ground_truth/path"], "1");
}

TEST_F(SimulateRecordingDrift, MapToOdomChangesAtTheCorrectionsOnly) {
  ASSERT_EQ(exit_code_, 0) << error_;
  ASSERT_EQ(map_odom_.size(), static_cast<std::size_t>(kFrames));
  ASSERT_EQ(odom_base_.size(), static_cast<std::size_t>(kFrames));
  // Frame 0: odom starts at the robot's pose, so map -> odom is the identity until the loop
  // closes, 1.5 m before the start (frame 434), and then every 50 frames over mapped corridor.
  EXPECT_LT(gap(map_odom_[0], Eigen::Isometry3d::Identity()), 1e-12);
  EXPECT_EQ(changes(), (std::vector<int>{434, 484, 534}));
  // The same as the stand-in gives for this seed.
  const std::vector<Eigen::Isometry3d> loop = sim::buildingLoopPath(0.2, 1.25);
  sim::OdometryDriftConfig drift;
  drift.seed = 3;
  EXPECT_EQ(changes(), sim::runLocalisation(loop, sim::driftedOdometry(loop, drift)).corrections);
}

TEST_F(SimulateRecordingDrift, RightAfterACorrectionTheTfChainGivesTheTruth) {
  ASSERT_EQ(exit_code_, 0) << error_;
  ASSERT_EQ(truth_by_stamp_.size(), static_cast<std::size_t>(kFrames));
  for (int frame : changes()) {
    const Eigen::Isometry3d truth = truth_by_stamp_.at(stampOf(frame));
    EXPECT_LT(gap(map_odom_[frame] * odom_base_[frame], truth), 1e-9) << frame;
    // The frame before, the estimate was off by the drift since the last correction.
    EXPECT_GT(gap(map_odom_[frame - 1] * odom_base_[frame], truth), 1e-3) << frame;
  }
  const int closure = changes().front();
  const Eigen::Isometry3d before = map_odom_[closure - 1] * odom_base_[closure - 1];
  EXPECT_GT((before.translation() - truth_by_stamp_.at(stampOf(closure - 1)).translation()).norm(),
            0.2);
}

TEST_F(SimulateRecordingDrift, SlamPathTrueAfterACorrectionDriftedBefore) {
  ASSERT_EQ(exit_code_, 0) << error_;
  const auto paths = messages<nav_msgs::Path>(bag(), "/slam/path");
  ASSERT_GT(paths.size(), 55u);  // every 10 frames as it grows, and at each correction
  std::map<ros::Time, const nav_msgs::Path*> by_stamp;
  std::size_t previous_size = 0;
  for (const nav_msgs::Path& path : paths) {
    EXPECT_EQ(path.header.frame_id, "map");
    EXPECT_GE(path.poses.size(), previous_size);
    previous_size = path.poses.size();
    by_stamp[path.header.stamp] = &path;
    for (const geometry_msgs::PoseStamped& pose : path.poses) {
      ASSERT_EQ(truth_by_stamp_.count(pose.header.stamp), 1u);  // stamped with a frame's stamp
      ASSERT_LE(pose.header.stamp, path.header.stamp);
    }
  }
  EXPECT_EQ(paths.front().header.stamp, stampOf(0));
  ASSERT_EQ(paths.front().poses.size(), 1u);
  const int closure = changes().front();
  // At each correction a path goes out with every keyframe at its true pose.
  for (int frame : changes()) {
    ASSERT_EQ(by_stamp.count(stampOf(frame)), 1u) << frame;
    const nav_msgs::Path& path = *by_stamp.at(stampOf(frame));
    EXPECT_EQ(path.poses.back().header.stamp, stampOf(frame));  // a keyframe at the correction
    for (const geometry_msgs::PoseStamped& pose : path.poses) {
      ASSERT_LT(gap(poseOf(pose.pose), truth_by_stamp_.at(pose.header.stamp)), 1e-9) << frame;
    }
  }
  // The last path before the closure: keyframes where the odometry put them, far off by then.
  const nav_msgs::Path& before = *std::prev(by_stamp.lower_bound(stampOf(closure)))->second;
  EXPECT_EQ(before.header.stamp, stampOf(430));
  const geometry_msgs::PoseStamped& last = before.poses.back();
  EXPECT_GT((poseOf(last.pose).translation() - truth_by_stamp_.at(last.header.stamp).translation())
                .norm(),
            0.2);
}

TEST(SimulateRecordingDriftOptions, OptionsAndTheirChecks) {
  const fs::path dir = makeTempDir();
  // Without --drift the building bag has the fixed map -> odom and no paths.
  const fs::path plain = dir / "plain.bag";
  ASSERT_EQ(runTool(SIMULATE_RECORDING_PATH,
                    "--scene building --laps 0.1 --step 0.5 --sensors scan --output '" +
                        plain.string() + "'",
                    dir)
                .exit_code,
            0);
  const std::vector<Eigen::Isometry3d> map_odom = transforms(plain, "map", "odom");
  ASSERT_EQ(map_odom.size(), 18u);  // floor(0.1 * 88.28 / 0.5) + 1
  EXPECT_LT(gap(map_odom.front(), map_odom.back()), 1e-12);
  EXPECT_NEAR(map_odom.front().translation().x(), 0.3, 1e-12);
  EXPECT_TRUE(messages<nav_msgs::Path>(plain, "/slam/path").empty());
  // --drift-scale 0: exact odometry, so map -> odom stays the identity. Keyframes every metre
  // (0.3 m steps: frames 0, 4, 8); with --path-every 3 a path goes out at frames 0, 6 and 9 (the
  // last), not at 3 (no new keyframe since 0).
  const fs::path exact = dir / "exact.bag";
  ASSERT_EQ(runTool(SIMULATE_RECORDING_PATH,
                    "--scene building --step 0.3 --frames 10 --drift 1 --drift-scale 0 "
                    "--path-every 3 --sensors scan --output '" +
                        exact.string() + "'",
                    dir)
                .exit_code,
            0);
  for (const Eigen::Isometry3d& T : transforms(exact, "map", "odom")) {
    EXPECT_LT(gap(T, Eigen::Isometry3d::Identity()), 1e-12);
  }
  const auto paths = messages<nav_msgs::Path>(exact, "/slam/path");
  ASSERT_EQ(paths.size(), 3u);
  const int written[] = {0, 6, 9};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(paths[i].header.stamp, ros::Time(1000.0 + written[i] / 5.0)) << i;
    EXPECT_EQ(paths[i].poses.size(), i + 1) << i;
  }
  EXPECT_EQ(paths[2].poses[2].header.stamp, ros::Time(1000.0 + 8 / 5.0));
  for (const std::string& arguments :
       {std::string("--scene room --laps 2 --output x.bag"),
        std::string("--scene building --step 0 --output x.bag"),
        std::string("--scene building --frames 100000 --output x.bag"),
        std::string("--drift-scale 2 --output x.bag"), std::string("--drift -1 --output x.bag"),
        std::string("--drift 1 --drift-scale -1 --output x.bag"),
        std::string("--drift 1 --path-every 0 --output x.bag")}) {
    const RunResult bad = runTool(SIMULATE_RECORDING_PATH, arguments, dir);
    EXPECT_EQ(bad.exit_code, 2) << arguments << ": " << bad.err;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace occupancy_fusion
