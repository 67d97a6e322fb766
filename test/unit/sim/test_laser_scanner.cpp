// Laser scans against analytic ranges (REP-117 semantics).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "occupancy_fusion/sim/laser_scanner.h"

namespace occupancy_fusion {
namespace sim {
namespace {

// Inner walls at x = +-2 and y = +-2, floor-to-ceiling for any sensor height in [0, 2].
Scene squareRoom() {
  Scene scene;
  scene.add(Box::axisAligned({2, -3, 0}, {3, 3, 2}))
      .add(Box::axisAligned({-3, -3, 0}, {-2, 3, 2}))
      .add(Box::axisAligned({-3, 2, 0}, {3, 3, 2}))
      .add(Box::axisAligned({-3, -3, 0}, {3, -2, 2}));
  return scene;
}

Eigen::Isometry3d sensorAt(double x, double y, double z, double yaw = 0.0) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, y, z);
  pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return pose;
}

// Distance from the centre of the square room to its wall along `angle`.
double squareRoomRange(double angle) {
  return 2.0 / std::max(std::abs(std::cos(angle)), std::abs(std::sin(angle)));
}

TEST(LaserScannerTest, CentreOfBoxRoomGivesAnalyticRanges) {
  LaserScanner scanner;  // 361 beams over [-90, 90] deg
  const LaserScan scan = renderScan(squareRoom(), scanner, sensorAt(0, 0, 1));
  ASSERT_EQ(scan.ranges.size(), 361u);
  EXPECT_NEAR(scan.angle_max, M_PI / 2, 1e-12);
  EXPECT_EQ(scan.range_max, 30.0);
  EXPECT_FLOAT_EQ(scan.ranges[180], 2.0f);  // straight ahead
  for (int beam = 0; beam < 361; ++beam) {
    const double angle = scan.angle(beam);
    if (std::abs(angle) <= M_PI / 4) {
      EXPECT_NEAR(scan.ranges[beam], 2.0 / std::cos(angle), 1e-5) << beam;
    }
    EXPECT_NEAR(scan.ranges[beam], squareRoomRange(angle), 1e-5) << beam;
  }
}

TEST(LaserScannerTest, BeamsFollowTheSensorPose) {
  LaserScanner scanner;
  scanner.angle_min = -M_PI;
  scanner.angle_max = M_PI - M_PI / 180;
  scanner.angle_increment = M_PI / 180;
  // Sensor off-centre at (1, 0.5), turned 90 deg: its +x looks along world +y.
  const LaserScan scan = renderScan(squareRoom(), scanner, sensorAt(1, 0.5, 1, M_PI / 2));
  ASSERT_EQ(scan.ranges.size(), 360u);
  EXPECT_NEAR(scan.ranges[180], 1.5, 1e-6);  // angle 0 -> world +y: wall at y = 2
  EXPECT_NEAR(scan.ranges[90], 1.0, 1e-6);   // angle -90 deg -> world +x: wall at x = 2
  EXPECT_NEAR(scan.ranges[0], 2.5, 1e-6);    // angle -180 deg -> world -y: wall at y = -2
  EXPECT_NEAR(scan.ranges[270], 3.0, 1e-6);  // angle +90 deg -> world -x: wall at x = -2
}

TEST(LaserScannerTest, OpenDirectionsAreInfinite) {
  Scene scene;
  scene.add(Box::axisAligned({2, -1, 0}, {3, 1, 2}));  // one wall segment ahead only
  LaserScanner scanner;
  const LaserScan scan = renderScan(scene, scanner, sensorAt(0, 0, 1));
  for (int beam = 0; beam < 361; ++beam) {
    const double angle = scan.angle(beam);
    if (std::abs(std::tan(angle)) * 2 < 1 - 1e-6 && std::cos(angle) > 0) {
      EXPECT_NEAR(scan.ranges[beam], 2.0 / std::cos(angle), 1e-5);
    } else if (std::abs(std::tan(angle)) * 2 > 1 + 1e-6 || std::cos(angle) <= 0) {
      EXPECT_EQ(scan.ranges[beam], std::numeric_limits<float>::infinity()) << beam;
    }
  }
  // Beyond range_max is also +inf; closer than range_min is -inf.
  scanner.range_max = 1.9;
  EXPECT_EQ(renderScan(scene, scanner, sensorAt(0, 0, 1)).ranges[180],
            std::numeric_limits<float>::infinity());
  scanner = LaserScanner();
  scanner.range_min = 0.5;
  EXPECT_EQ(renderScan(scene, scanner, sensorAt(1.7, 0, 1)).ranges[180],
            -std::numeric_limits<float>::infinity());
  EXPECT_NEAR(renderScan(scene, scanner, sensorAt(1.4, 0, 1)).ranges[180], 0.6, 1e-6);
}

TEST(LaserScannerTest, NoiseIsGaussianReproducibleAndClamped) {
  Scene scene;
  scene.add(Sphere{{0, 0, 0}, 5.0});  // from the centre every beam reads 5 m
  LaserScanner scanner;
  scanner.angle_min = -M_PI;
  scanner.angle_max = M_PI;
  scanner.angle_increment = 2 * M_PI / 3600;
  scanner.noise_sigma = 0.05;
  scanner.seed = 11;
  double sum = 0;
  double sum_sq = 0;
  std::size_t n = 0;
  for (int frame = 0; frame < 5; ++frame) {
    const LaserScan scan = renderScan(scene, scanner, sensorAt(0, 0, 0), frame);
    for (float r : scan.ranges) {
      sum += r - 5.0;
      sum_sq += (r - 5.0) * (r - 5.0);
      ++n;
    }
  }
  EXPECT_NEAR(sum / n, 0.0, 0.003);
  EXPECT_NEAR(std::sqrt(sum_sq / n), 0.05, 0.002);
  const LaserScan a = renderScan(scene, scanner, sensorAt(0, 0, 0), 2);
  EXPECT_EQ(renderScan(scene, scanner, sensorAt(0, 0, 0), 2).ranges, a.ranges);
  EXPECT_NE(renderScan(scene, scanner, sensorAt(0, 0, 0), 3).ranges, a.ranges);
  // A surface just inside range_max: noisy readings never exceed range_max.
  scanner.range_max = 5.01;
  for (float r : renderScan(scene, scanner, sensorAt(0, 0, 0), 0).ranges) {
    EXPECT_LE(r, 5.01f);
    EXPECT_GE(r, 4.7f);
  }
}

TEST(LaserScannerTest, ValidateNamesTheBadField) {
  LaserScanner scanner;
  scanner.range_max = 0.01;
  try {
    scanner.validate();
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("range_max"), std::string::npos);
  }
  scanner = LaserScanner();
  scanner.angle_increment = 0;
  EXPECT_THROW(renderScan(Scene(), scanner, Eigen::Isometry3d::Identity()), std::invalid_argument);
}

}  // namespace
}  // namespace sim
}  // namespace occupancy_fusion
