// Drifting odometry: exact without errors, deterministic per seed, each error of the size its
// parameter says, growing with the distance travelled.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "occupancy_fusion/sim/odometry_drift.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {
namespace sim {
namespace {

OdometryDriftConfig noDrift() { return OdometryDriftConfig().scaled(0.0); }

double headingError(const Eigen::Isometry3d& odometry, const Eigen::Isometry3d& truth) {
  return std::remainder(yawOf(odometry) - yawOf(truth), 2 * M_PI);
}

double positionError(const Eigen::Isometry3d& odometry, const Eigen::Isometry3d& truth) {
  return (odometry.translation() - truth.translation()).norm();
}

TEST(OdometryDriftTest, WithoutErrorsOdometryIsTheTruth) {
  const std::vector<Eigen::Isometry3d> truth = buildingLoopPath(0.2, 1.25);
  const std::vector<Eigen::Isometry3d> odometry = driftedOdometry(truth, noDrift());
  ASSERT_EQ(odometry.size(), truth.size());
  for (std::size_t k = 0; k < truth.size(); ++k) {
    EXPECT_TRUE(odometry[k].isApprox(truth[k], 1e-9)) << k;
    EXPECT_LT(positionError(odometry[k], truth[k]), 1e-9) << k;
  }
  EXPECT_TRUE(driftedOdometry({}, OdometryDriftConfig()).empty());
}

TEST(OdometryDriftTest, StartsAtTheTruthAndIsDeterministicPerSeed) {
  const std::vector<Eigen::Isometry3d> truth = buildingLoopPath(0.2, 1.0);
  OdometryDriftConfig config;
  config.seed = 7;
  const std::vector<Eigen::Isometry3d> a = driftedOdometry(truth, config);
  const std::vector<Eigen::Isometry3d> b = driftedOdometry(truth, config);
  EXPECT_TRUE(a[0].isApprox(truth[0], 0.0));
  for (std::size_t k = 0; k < a.size(); ++k) ASSERT_TRUE(a[k].isApprox(b[k], 0.0)) << k;
  config.seed = 8;
  const std::vector<Eigen::Isometry3d> c = driftedOdometry(truth, config);
  EXPECT_GT(positionError(a.back(), c.back()), 0.01);
}

// The systematic parts alone are exact: on a straight line the odometry reads (1 + scale_error)
// times the distance, and the heading turns by heading_drift per metre.
TEST(OdometryDriftTest, SystematicErrorsHaveTheirConfiguredSize) {
  const std::vector<Eigen::Isometry3d> line =
      straightLinePath(Eigen::Vector3d(1, 2, 0), Eigen::Vector3d(11, 2, 0), 51, 0.0, 0.0);
  OdometryDriftConfig config = noDrift();
  config.scale_error = 0.02;
  std::vector<Eigen::Isometry3d> odometry = driftedOdometry(line, config);
  EXPECT_NEAR(odometry.back().translation().x(), 1.0 + 10.0 * 1.02, 1e-9);
  EXPECT_NEAR(odometry.back().translation().y(), 2.0, 1e-9);
  config = noDrift();
  config.heading_drift = 0.003;
  const std::vector<Eigen::Isometry3d> loop = buildingLoopPath(0.2, 1.0);
  odometry = driftedOdometry(loop, config);
  double travelled = 0.0;
  for (std::size_t k = 1; k < loop.size(); ++k) {
    travelled += (loop[k].translation() - loop[k - 1].translation()).norm();
    ASSERT_NEAR(headingError(odometry[k], loop[k]), 0.003 * travelled, 1e-9) << k;
  }
  EXPECT_GT(positionError(odometry.back(), loop.back()), 0.5);  // the bias moved it sideways
}

TEST(OdometryDriftTest, RandomErrorsGrowWithDistance) {
  const std::vector<Eigen::Isometry3d> truth =
      straightLinePath(Eigen::Vector3d::Zero(), Eigen::Vector3d(80, 0, 0), 401, 0.0, 0.0);
  OdometryDriftConfig config = noDrift();
  config.translation_noise = 0.01;
  config.heading_noise = 0.001;
  // Mean squared errors over seeds after 10, 20, 40 and 80 m (frames 50, 100, 200, 400).
  const int frames[] = {50, 100, 200, 400};
  double heading[4] = {}, position[4] = {};
  constexpr int kSeeds = 200;
  for (unsigned seed = 1; seed <= kSeeds; ++seed) {
    config.seed = seed;
    const std::vector<Eigen::Isometry3d> odometry = driftedOdometry(truth, config);
    for (int i = 0; i < 4; ++i) {
      heading[i] += std::pow(headingError(odometry[frames[i]], truth[frames[i]]), 2) / kSeeds;
      position[i] += std::pow(positionError(odometry[frames[i]], truth[frames[i]]), 2) / kSeeds;
    }
  }
  for (int i = 0; i < 4; ++i) {
    const double metres = frames[i] * 0.2;
    // A random walk of the heading: variance heading_noise^2 per metre.
    EXPECT_NEAR(heading[i] / (1e-6 * metres), 1.0, 0.25) << metres;
    if (i > 0) {
      EXPECT_GT(position[i], 2.0 * position[i - 1]) << metres;
    }
  }
}

TEST(OdometryDriftTest, DefaultsDriftAFewTenthsOfAMetreAndAFewDegreesPerLoop) {
  const std::vector<Eigen::Isometry3d> truth = buildingLoopPath(0.2, 1.0);
  for (unsigned seed = 1; seed <= 5; ++seed) {
    OdometryDriftConfig config;
    config.seed = seed;
    const std::vector<Eigen::Isometry3d> odometry = driftedOdometry(truth, config);
    const double metres = positionError(odometry.back(), truth.back());
    const double degrees = std::abs(headingError(odometry.back(), truth.back())) * 180 / M_PI;
    EXPECT_GT(metres, 0.1) << seed;
    EXPECT_LT(metres, 1.5) << seed;
    EXPECT_GT(degrees, 1.0) << seed;
    EXPECT_LT(degrees, 8.0) << seed;
  }
}

TEST(OdometryDriftTest, HeightRollAndPitchStayExact) {
  std::vector<Eigen::Isometry3d> truth = buildingLoopPath(0.5, 0.5);
  for (std::size_t k = 0; k < truth.size(); ++k) {
    truth[k].translation().z() = 0.1 * std::sin(0.3 * k);
    truth[k].linear() = truth[k].linear() * Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()) *
                        Eigen::AngleAxisd(0.02 * std::cos(0.2 * k), Eigen::Vector3d::UnitY());
  }
  const std::vector<Eigen::Isometry3d> odometry = driftedOdometry(truth, OdometryDriftConfig());
  for (std::size_t k = 0; k < truth.size(); ++k) {
    EXPECT_EQ(odometry[k].translation().z(), truth[k].translation().z()) << k;
    // The body's axes have the same vertical components: only the yaw differs.
    EXPECT_TRUE(odometry[k].linear().row(2).isApprox(truth[k].linear().row(2), 1e-12)) << k;
  }
  EXPECT_GT(std::abs(headingError(odometry.back(), truth.back())), 0.01);
}

TEST(OdometryDriftTest, ScaledAndValidated) {
  const OdometryDriftConfig base;
  const OdometryDriftConfig doubled = base.scaled(2.0);
  EXPECT_DOUBLE_EQ(doubled.translation_noise, 2 * base.translation_noise);
  EXPECT_DOUBLE_EQ(doubled.scale_error, 2 * base.scale_error);
  EXPECT_DOUBLE_EQ(doubled.heading_drift, 2 * base.heading_drift);
  EXPECT_DOUBLE_EQ(doubled.heading_noise, 2 * base.heading_noise);
  EXPECT_EQ(doubled.seed, base.seed);
  EXPECT_THROW(base.scaled(-1.0), std::invalid_argument);
  OdometryDriftConfig bad;
  bad.translation_noise = -0.1;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = OdometryDriftConfig();
  bad.scale_error = -1.0;
  EXPECT_THROW(driftedOdometry(buildingLoopPath(1.0, 0.1), bad), std::invalid_argument);
}

}  // namespace
}  // namespace sim
}  // namespace occupancy_fusion
