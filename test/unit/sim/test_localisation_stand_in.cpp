// The graph-SLAM stand-in on the building loop: it drifts with the odometry, closes the loop when
// the robot returns to the start, and then publishes the true past and a right map -> odom.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "occupancy_fusion/sim/localisation_stand_in.h"
#include "occupancy_fusion/sim/odometry_drift.h"
#include "occupancy_fusion/sim/scenes.h"

namespace occupancy_fusion {
namespace sim {
namespace {

bool samePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tolerance = 1e-9) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff() <= tolerance;
}

double distance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

class LocalisationStandInTest : public ::testing::Test {
 protected:
  void SetUp() override {
    truth_ = buildingLoopPath(0.2, 1.25);
    odometry_ = driftedOdometry(truth_, OdometryDriftConfig());
    track_ = runLocalisation(truth_, odometry_);
  }
  Eigen::Isometry3d estimate(int k) const { return track_.T_map_odom[k] * odometry_[k]; }

  std::vector<Eigen::Isometry3d> truth_, odometry_;
  LocalisationTrack track_;
};

TEST_F(LocalisationStandInTest, ClosesTheLoopOnReturningToTheStart) {
  ASSERT_EQ(track_.frames(), 552);
  ASSERT_FALSE(track_.corrections.empty());
  // The first frame of the second half of the lap that is within 1.5 m of the start: there the
  // robot meets keyframe 0.
  int expected = -1;
  for (int k = 300; k < 552 && expected < 0; ++k) {
    if (distance(truth_[k], truth_[0]) <= 1.5) expected = k;
  }
  EXPECT_EQ(expected, 434);  // 1.5 m before the lap's end at frame 441
  EXPECT_EQ(track_.corrections.front(), expected);
  // Then, over corridor already mapped, again as soon as allowed: every 50 frames.
  EXPECT_EQ(track_.corrections, (std::vector<int>{434, 484, 534}));
  EXPECT_EQ(track_.lastCorrectionAt(433), -1);
  EXPECT_EQ(track_.lastCorrectionAt(500), 484);
}

TEST_F(LocalisationStandInTest, BeforeTheClosureTheEstimateDrifts) {
  const int closure = track_.corrections.front();
  for (int k = 0; k < closure; ++k) {
    ASSERT_TRUE(samePose(track_.T_map_odom[k], Eigen::Isometry3d::Identity(), 1e-12)) << k;
  }
  // The estimate is the odometry, wrong by the drift accumulated over the lap.
  EXPECT_GT(distance(estimate(closure - 1), truth_[closure - 1]), 0.2);
  const std::vector<Eigen::Isometry3d> path = track_.pathAt(closure - 1);
  ASSERT_EQ(static_cast<int>(path.size()), track_.keyframeCountAt(closure - 1));
  for (std::size_t i = 0; i < path.size(); ++i) {
    EXPECT_TRUE(samePose(path[i], odometry_[track_.keyframe_frames[i]])) << i;
  }
  EXPECT_GT(distance(path.back(), truth_[track_.keyframe_frames[path.size() - 1]]), 0.2);
}

TEST_F(LocalisationStandInTest, ACorrectionSetsThePastAndMapToOdomToTheTruth) {
  for (int correction : track_.corrections) {
    EXPECT_TRUE(samePose(estimate(correction), truth_[correction])) << correction;
    const std::vector<Eigen::Isometry3d> path = track_.pathAt(correction);
    ASSERT_EQ(static_cast<int>(path.size()), track_.keyframeCountAt(correction));
    EXPECT_EQ(track_.keyframe_frames[path.size() - 1], correction);  // a keyframe is added
    for (std::size_t i = 0; i < path.size(); ++i) {
      ASSERT_TRUE(samePose(path[i], truth_[track_.keyframe_frames[i]])) << correction << " " << i;
    }
  }
  // map -> odom moved the robot's estimate by the drift the closure removed.
  const int closure = track_.corrections.front();
  EXPECT_GT(distance(estimate(closure), track_.T_map_odom[closure - 1] * odometry_[closure]), 0.2);
}

TEST_F(LocalisationStandInTest, BetweenCorrectionsTheEstimateDriftsAgain) {
  const int first = track_.corrections[0], second = track_.corrections[1];
  for (int k = first; k < second; ++k) {
    ASSERT_TRUE(samePose(track_.T_map_odom[k], track_.T_map_odom[first], 0.0)) << k;
    // The truth at the correction, moved by what the odometry measured since.
    const Eigen::Isometry3d expected = truth_[first] * odometry_[first].inverse() * odometry_[k];
    ASSERT_TRUE(samePose(estimate(k), expected)) << k;
  }
  // 10 m of drift since: the error is small but not zero.
  const double error = distance(estimate(second - 1), truth_[second - 1]);
  EXPECT_GT(error, 1e-3);
  EXPECT_LT(error, 0.2);
  // Keyframes added after the correction are published as estimated, the older ones as corrected.
  const std::vector<Eigen::Isometry3d> path = track_.pathAt(second - 1);
  const int before = track_.keyframeCountAt(first);
  EXPECT_TRUE(samePose(path[before - 1], truth_[first]));
  EXPECT_TRUE(samePose(path.back(), estimate(track_.keyframe_frames[path.size() - 1])));
  EXPECT_FALSE(samePose(path.back(), truth_[track_.keyframe_frames[path.size() - 1]], 1e-3));
}

TEST_F(LocalisationStandInTest, KeyframesEveryMetreOfOdometry) {
  // On the first straight: 0.2 m steps read 1.005 m (the default scale error) every 5 frames.
  ASSERT_GE(track_.keyframe_frames.size(), 4u);
  EXPECT_EQ(std::vector<int>(track_.keyframe_frames.begin(), track_.keyframe_frames.begin() + 4),
            (std::vector<int>{0, 5, 10, 15}));
  EXPECT_NEAR(static_cast<double>(track_.keyframe_frames.size()), 110.0, 10.0);
  for (int k = 0; k < track_.frames(); ++k) {
    const bool keyframe =
        std::binary_search(track_.keyframe_frames.begin(), track_.keyframe_frames.end(), k);
    const bool correction =
        std::binary_search(track_.corrections.begin(), track_.corrections.end(), k);
    EXPECT_EQ(track_.pathChangedAt(k), keyframe || correction) << k;
    EXPECT_EQ(static_cast<int>(track_.pathAt(k).size()), track_.keyframeCountAt(k)) << k;
  }
}

TEST(LocalisationStandInOptions, FixedScheduleAndExactOdometry) {
  const std::vector<Eigen::Isometry3d> truth = buildingLoopPath(0.2, 1.25);
  LocalisationConfig config;
  config.detect_loop_closures = false;
  config.correct_every_frames = 100;
  // With exact odometry the estimate is the truth at every frame, corrections or not.
  const LocalisationTrack track = runLocalisation(truth, truth, config);
  EXPECT_EQ(track.corrections, (std::vector<int>{100, 200, 300, 400, 500}));
  for (int k = 0; k < track.frames(); ++k) {
    ASSERT_TRUE(samePose(track.T_map_odom[k] * truth[k], truth[k])) << k;
  }
  config.correct_every_frames = 0;
  EXPECT_TRUE(runLocalisation(truth, truth, config).corrections.empty());
}

TEST(LocalisationStandInOptions, ResidualNoiseLeavesASmallSeededError) {
  const std::vector<Eigen::Isometry3d> truth = buildingLoopPath(0.2, 1.25);
  const std::vector<Eigen::Isometry3d> odometry = driftedOdometry(truth, OdometryDriftConfig());
  LocalisationConfig config;
  config.residual_translation_noise = 0.05;
  config.residual_heading_noise = 0.01;
  const LocalisationTrack track = runLocalisation(truth, odometry, config);
  const LocalisationTrack again = runLocalisation(truth, odometry, config);
  ASSERT_EQ(track.corrections.front(), 434);
  const std::vector<Eigen::Isometry3d> path = track.pathAt(434);
  const std::vector<Eigen::Isometry3d> same = again.pathAt(434);
  double largest = 0.0;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const double error = distance(path[i], truth[track.keyframe_frames[i]]);
    EXPECT_GT(error, 1e-6) << i;
    largest = std::max(largest, error);
    EXPECT_TRUE(samePose(path[i], same[i], 0.0)) << i;
  }
  EXPECT_LT(largest, 0.3);
  // map -> odom places the robot where its corrected keyframe is.
  EXPECT_TRUE(samePose(track.T_map_odom[434] * odometry[434], path.back()));
}

TEST(LocalisationStandInOptions, RejectsBadInput) {
  const std::vector<Eigen::Isometry3d> truth = buildingLoopPath(1.0, 0.2);
  EXPECT_THROW(runLocalisation(truth, {truth.begin(), truth.end() - 1}), std::invalid_argument);
  LocalisationConfig config;
  config.keyframe_distance = 0.0;
  EXPECT_THROW(runLocalisation(truth, truth, config), std::invalid_argument);
  config = LocalisationConfig();
  config.min_frames_between_closures = 0;
  EXPECT_THROW(config.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace sim
}  // namespace occupancy_fusion
