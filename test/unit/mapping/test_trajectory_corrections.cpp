// Submap placements from a SLAM system's corrected keyframes (trajectory_corrections.h), against
// poses built by hand: a drifted odometry and the true trajectory it came from.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "occupancy_fusion/mapping/trajectory_corrections.h"

namespace occupancy_fusion {
namespace {

Eigen::Isometry3d planar(double x, double y, double yaw) {
  return Eigen::Isometry3d(Eigen::Translation3d(x, y, 0.0) *
                           Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
}

SubmapInfo submap(int id, double start, double end) {
  SubmapInfo info;
  info.id = id;
  info.start_stamp = start;
  info.end_stamp = end;
  info.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-2, -2, 0), Eigen::Vector3d(2, 2, 2));
  return info;
}

TEST(TrajectoryCorrections, InterpolatesTranslationLinearlyAndRotationBySlerp) {
  const Eigen::Isometry3d mid = interpolatePose(planar(0, 0, 0), planar(2, 4, 1.0), 0.25);
  EXPECT_TRUE(mid.translation().isApprox(Eigen::Vector3d(0.5, 1.0, 0.0)));
  EXPECT_NEAR(Eigen::AngleAxisd(mid.linear()).angle(), 0.25, 1e-12);
}

TEST(TrajectoryCorrections, TheMeanOfNearbyPosesIsTheirMiddle) {
  const Eigen::Isometry3d mean = meanPose({planar(1, 0, 0.1), planar(3, 2, 0.3)});
  EXPECT_TRUE(mean.translation().isApprox(Eigen::Vector3d(2, 1, 0)));
  EXPECT_NEAR(Eigen::AngleAxisd(mean.linear()).angle(), 0.2, 1e-9);
}

TEST(TrajectoryCorrections, OdometryIsInterpolatedWithinItsSpanAndNotAcrossGaps) {
  OdometryTrack odometry;
  odometry.add(1.0, planar(0, 0, 0));
  odometry.add(2.0, planar(1, 0, 0));
  odometry.add(5.0, planar(2, 0, 0));
  odometry.add(4.0, planar(9, 9, 9));  // earlier than the last: ignored
  ASSERT_TRUE(odometry.at(1.5, 1.0).has_value());
  EXPECT_NEAR(odometry.at(1.5, 1.0)->translation().x(), 0.5, 1e-12);
  EXPECT_FALSE(odometry.at(3.0, 1.0).has_value());  // a 3 s gap
  EXPECT_TRUE(odometry.at(3.0, 5.0).has_value());
  EXPECT_FALSE(odometry.at(0.5, 1.0).has_value());
  EXPECT_FALSE(odometry.at(5.5, 1.0).has_value());
  EXPECT_EQ(odometry.size(), 3u);
}

// A robot driving along x at 1 m/s whose odometry overestimates its heading by 0.02 rad per
// metre: T_odom_base(t) differs from the truth more and more; a SLAM keyframe every 2 s carries
// the truth. The corrections then place each submap so that T_map_odom * T_odom_base = truth.
TEST(TrajectoryCorrections, KeyframesOfTheTruthPlaceEachSubmapWhereItsOdometryWasWrong) {
  OdometryTrack odometry;
  std::vector<StampedPose> truth;
  Eigen::Isometry3d odom = planar(0, 0, 0);
  for (int k = 0; k <= 200; ++k) {
    const double t = 100.0 + 0.1 * k;
    const Eigen::Isometry3d true_pose = planar(0.1 * k, 0.0, 0.0);
    odometry.add(t, odom);
    if (k % 20 == 0) truth.push_back({t, true_pose});
    odom = odom * planar(0.1, 0.0, 0.002);  // each step's motion as the odometry measured it
  }
  const std::vector<StampedPose> corrections =
      correctionsAlongPath(truth, odometry, TrajectoryCorrectionConfig());
  ASSERT_EQ(corrections.size(), truth.size());
  for (std::size_t i = 0; i < corrections.size(); ++i) {
    const Eigen::Isometry3d placed = corrections[i].pose * *odometry.at(truth[i].stamp, 1.0);
    EXPECT_TRUE(placed.isApprox(truth[i].pose, 1e-9));
  }
  // Submaps of 5 s: the mean of their keyframes' corrections. A submap between keyframes (no
  // keyframe inside 103.1-103.9 s) takes the interpolation at its middle.
  const std::vector<std::pair<int, Eigen::Isometry3d>> placements = placementsFromCorrections(
      corrections, {submap(0, 100.0, 105.0), submap(1, 103.1, 103.9), submap(2, 110.0, 120.0)});
  ASSERT_EQ(placements.size(), 3u);
  EXPECT_TRUE(placements[0].second.isApprox(
      meanPose({corrections[0].pose, corrections[1].pose, corrections[2].pose})));
  EXPECT_TRUE(placements[1].second.isApprox(
      interpolatePose(corrections[1].pose, corrections[2].pose, 0.75), 1e-9));
  // At the submap's middle its placement undoes most of the odometry's error: a rigid placement
  // of 10 m of odometry that turned 0.2 rad more than the robot is off by about 0.11 m there
  // (computed independently), against 2.2 m uncorrected.
  const double middle = 115.0;
  const Eigen::Isometry3d placed = placements[2].second * *odometry.at(middle, 1.0);
  EXPECT_NEAR(placed.translation().x(), 0.1 * (middle - 100.0) / 0.1, 0.05);
  EXPECT_NEAR(placed.translation().y(), 0.111, 0.01);
  // The uncorrected odometry is far off there.
  EXPECT_GT(std::abs(odometry.at(middle, 1.0)->translation().y()), 1.0);
}

TEST(TrajectoryCorrections, SubmapsBeyondThePathTakeItsNearestCorrectionAndEmptyOnesNone) {
  const std::vector<StampedPose> corrections = {{10.0, planar(1, 0, 0)}, {20.0, planar(2, 0, 0)}};
  SubmapInfo unwritten;
  unwritten.id = 3;
  SubmapInfo fixed = submap(0, 1.0, 2.0);
  fixed.fixed = true;
  const auto placements =
      placementsFromCorrections(corrections, {fixed, submap(1, 30.0, 40.0), unwritten});
  ASSERT_EQ(placements.size(), 1u);
  EXPECT_EQ(placements[0].first, 1);
  EXPECT_TRUE(placements[0].second.isApprox(planar(2, 0, 0)));
  EXPECT_TRUE(placementsFromCorrections({}, {submap(1, 30.0, 40.0)}).empty());
}

}  // namespace
}  // namespace occupancy_fusion
