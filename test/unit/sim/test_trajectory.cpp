// Trajectory generators: the paper's rotation sweep, orbits, straight paths, lookAt.
#include <gtest/gtest.h>

#include <cmath>

#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {
namespace sim {
namespace {

double angleBetween(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

TEST(TrajectoryTest, OpticalFrameLooksAlongBodyX) {
  const Eigen::Isometry3d T = opticalFrameInBody();
  EXPECT_TRUE((T.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_TRUE((T.linear() * Eigen::Vector3d::UnitX()).isApprox(-Eigen::Vector3d::UnitY()));
  EXPECT_TRUE((T.linear() * Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-12);
}

TEST(TrajectoryTest, RotationSweepHas181ViewsAt4DegreeSteps) {
  const Eigen::Vector3d position(0, 0, 1.5);
  const auto poses = rotationSweep(position);
  ASSERT_EQ(poses.size(), 181u);
  const Eigen::Matrix3d R0 = opticalFrameInBody().linear();
  EXPECT_TRUE(poses[0].linear().isApprox(R0));
  for (const auto& pose : poses) EXPECT_TRUE(pose.translation().isApprox(position));
  const double step = 4.0 * M_PI / 180.0;
  for (int k = 1; k <= 90; ++k) {
    // About the camera's own x axis by k * 4 deg.
    const Eigen::Matrix3d expected = R0 * Eigen::AngleAxisd(k * step, Eigen::Vector3d::UnitX());
    EXPECT_TRUE(poses[k].linear().isApprox(expected, 1e-12)) << k;
    EXPECT_NEAR(angleBetween(poses[k - 1], poses[k]), step, 1e-9) << k;
  }
  EXPECT_TRUE(poses[90].linear().isApprox(R0, 1e-12));  // the full turn closes
  for (int k = 1; k <= 90; ++k) {
    const Eigen::Matrix3d expected = R0 * Eigen::AngleAxisd(k * step, Eigen::Vector3d::UnitY());
    EXPECT_TRUE(poses[90 + k].linear().isApprox(expected, 1e-12)) << k;
  }
  EXPECT_NEAR(angleBetween(poses[0], poses[91]), step, 1e-9);
  // Turning about optical x tilts the view up/down: optical z stays in the world x-z plane.
  EXPECT_NEAR((poses[10].linear() * Eigen::Vector3d::UnitZ()).y(), 0.0, 1e-12);
  // Turning about optical y pans left/right: optical z stays horizontal.
  EXPECT_NEAR((poses[100].linear() * Eigen::Vector3d::UnitZ()).z(), 0.0, 1e-12);
}

TEST(TrajectoryTest, RotationSweepSplitsOddCounts) {
  const auto poses = rotationSweep(Eigen::Vector3d::Zero(), 4, 10.0);  // 2 about x, 1 about y
  ASSERT_EQ(poses.size(), 4u);
  const Eigen::Matrix3d R0 = opticalFrameInBody().linear();
  EXPECT_TRUE(poses[2].linear().isApprox(
      R0 * Eigen::AngleAxisd(20 * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix()));
  EXPECT_TRUE(poses[3].linear().isApprox(
      R0 * Eigen::AngleAxisd(10 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix()));
}

TEST(TrajectoryTest, LookAtPointsOpticalAxisAtTarget) {
  const Eigen::Vector3d eye(1, 2, 3);
  const Eigen::Vector3d target(4, -2, 1);
  const Eigen::Isometry3d pose = lookAt(eye, target);
  const Eigen::Vector3d forward = (target - eye).normalized();
  EXPECT_TRUE((pose.linear() * Eigen::Vector3d::UnitZ()).isApprox(forward));
  EXPECT_NEAR((pose.linear() * Eigen::Vector3d::UnitX()).z(), 0.0, 1e-12);  // level horizon
  EXPECT_LT((pose.linear() * Eigen::Vector3d::UnitY()).z(), 0.0);           // image y is down
  EXPECT_NEAR(pose.linear().determinant(), 1.0, 1e-12);
  EXPECT_TRUE((pose.inverse() * target).head<2>().isZero(1e-12));  // projects to the centre
  EXPECT_THROW(lookAt(eye, eye), std::invalid_argument);
  EXPECT_THROW(lookAt(eye, eye + Eigen::Vector3d::UnitZ()), std::invalid_argument);
}

TEST(TrajectoryTest, OrbitCirclesTheCentreLookingAtTarget) {
  const Eigen::Vector3d center(1, -1, 0.5);
  const Eigen::Vector3d target(1, -1, 0);
  const auto poses = orbitTrajectory(center, 3.0, 1.0, 12, target);
  ASSERT_EQ(poses.size(), 12u);
  for (int k = 0; k < 12; ++k) {
    const Eigen::Vector3d offset = poses[k].translation() - center;
    EXPECT_NEAR(offset.head<2>().norm(), 3.0, 1e-12);
    EXPECT_NEAR(offset.z(), 1.0, 1e-12);
    EXPECT_NEAR(std::atan2(offset.y(), offset.x()), std::remainder(k * M_PI / 6, 2 * M_PI), 1e-12);
    EXPECT_TRUE((poses[k].inverse() * target).head<2>().isZero(1e-12));
  }
}

TEST(TrajectoryTest, StraightLinePathInterpolatesPositionAndYaw) {
  const auto poses = straightLinePath({0, 0, 0}, {4, 2, 0}, 5, 0.0, M_PI / 2);
  ASSERT_EQ(poses.size(), 5u);
  EXPECT_TRUE(poses[0].translation().isZero());
  EXPECT_TRUE(poses[4].translation().isApprox(Eigen::Vector3d(4, 2, 0)));
  EXPECT_TRUE(poses[2].translation().isApprox(Eigen::Vector3d(2, 1, 0)));
  for (int k = 0; k < 5; ++k) {
    const Eigen::Vector3d heading = poses[k].linear() * Eigen::Vector3d::UnitX();
    EXPECT_NEAR(std::atan2(heading.y(), heading.x()), k * M_PI / 8, 1e-12);
    EXPECT_NEAR(heading.z(), 0.0, 1e-12);
  }
  EXPECT_THROW(straightLinePath({0, 0, 0}, {1, 0, 0}, 1, 0, 0), std::invalid_argument);
}

}  // namespace
}  // namespace sim
}  // namespace occupancy_fusion
