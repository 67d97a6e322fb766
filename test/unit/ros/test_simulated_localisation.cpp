// The Simulator nodelet's loop motion: its parameters read into the core's configs, the loop
// sampled once per tf tick, and with drift the stand-in's map -> odom that is true right after
// each correction.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <variant>

#include "occupancy_fusion/params/parameter_source.h"
#include "occupancy_fusion/sim/scenes.h"

#include "../../../src/nodelets/simulator/simulated_localisation.h"

#include "../../common/map_parameter_source.h"

namespace occupancy_fusion {
namespace {

using MapSource = MapParameterSource;

std::string errorOf(const MapSource& source) {
  try {
    readLoopMotionConfig(source);
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "";
}

TEST(SimulatedLocalisation, ReadsItsParameters) {
  const LoopMotionConfig defaults = readLoopMotionConfig(MapSource({}));
  EXPECT_FALSE(defaults.drift);
  EXPECT_EQ(defaults.speed, 1.0);
  EXPECT_EQ(defaults.laps, 1.25);
  const LoopMotionConfig config = readLoopMotionConfig(MapSource({
      {"trajectory/speed", 0.5},
      {"trajectory/laps", 2.0},
      {"drift/enabled", true},
      {"drift/seed", 9},
      {"drift/scale", 2.0},
      {"drift/heading_drift", 0.001},
      {"localisation/min_frames_between_closures", 150},
      {"localisation/closure_radius", 2.0},
      {"localisation/detect_loop_closures", false},
  }));
  EXPECT_TRUE(config.drift);
  EXPECT_EQ(config.speed, 0.5);
  EXPECT_EQ(config.laps, 2.0);
  EXPECT_EQ(config.odometry_drift.seed, 9u);
  EXPECT_DOUBLE_EQ(config.odometry_drift.heading_drift, 0.002);  // scaled
  EXPECT_DOUBLE_EQ(config.odometry_drift.translation_noise,
                   2 * sim::OdometryDriftConfig().translation_noise);
  EXPECT_EQ(config.localisation.min_frames_between_closures, 150);
  EXPECT_EQ(config.localisation.closure_radius, 2.0);
  EXPECT_FALSE(config.localisation.detect_loop_closures);
  // Bad values name their parameter.
  EXPECT_NE(errorOf(MapSource({{"trajectory/speed", 0.0}})).find("trajectory/speed"),
            std::string::npos);
  EXPECT_NE(errorOf(MapSource({{"drift/scale", -1.0}})).find("drift/scale"), std::string::npos);
  EXPECT_NE(errorOf(MapSource({{"drift/translation_noise", -1.0}})).find("translation_noise"),
            std::string::npos);
  EXPECT_NE(errorOf(MapSource({{"localisation/keyframe_distance", 0.0}})).find("keyframe_distance"),
            std::string::npos);
  EXPECT_NE(errorOf(MapSource({{"localisation/seed", 1.5}})).find("localisation/seed"),
            std::string::npos);
}

TEST(SimulatedLocalisation, OneFramePerTickAlongTheLoop) {
  const LoopMotion motion(LoopMotionConfig(), 30.0);
  const int frames = static_cast<int>(std::floor(1.25 * sim::buildingLoopLength() * 30.0)) + 1;
  ASSERT_EQ(motion.frames(), frames);
  EXPECT_EQ(motion.frameAt(-1.0), 0);
  EXPECT_EQ(motion.frameAt(0.0), 0);
  EXPECT_EQ(motion.frameAt(1.0), 30);
  EXPECT_EQ(motion.frameAt(31.0 / 30.0), 31);
  EXPECT_EQ(motion.frameAt(1e6), frames - 1);  // then it stands at the end
  // 1 m/s: a second later the robot is 1 m along the south corridor.
  EXPECT_TRUE(motion.truth(30).translation().isApprox(Eigen::Vector3d(1.0, -7.5, 0.0), 1e-9));
  // Without drift odometry is the truth and there is no stand-in.
  EXPECT_TRUE(motion.odometry(500).isApprox(motion.truth(500), 0.0));
  EXPECT_FALSE(motion.track());
  EXPECT_TRUE(motion.mapToOdom(500).isApprox(Eigen::Isometry3d::Identity(), 0.0));
}

TEST(SimulatedLocalisation, WithDriftMapToOdomIsTrueAtEachCorrection) {
  LoopMotionConfig config;
  config.drift = true;
  config.localisation.min_frames_between_closures = 150;
  const LoopMotion motion(config, 30.0);
  ASSERT_TRUE(motion.track());
  const std::vector<int>& corrections = motion.track()->corrections;
  ASSERT_FALSE(corrections.empty());
  // The first at the return to the start (the robot 1.5 m before it), then every 5 s.
  EXPECT_NEAR(corrections.front() / 30.0, sim::buildingLoopLength() - 1.5, 0.05);
  for (std::size_t i = 1; i < corrections.size(); ++i) {
    EXPECT_EQ(corrections[i] - corrections[i - 1], 150);
  }
  for (int frame : corrections) {
    const Eigen::Isometry3d estimate = motion.mapToOdom(frame) * motion.odometry(frame);
    EXPECT_LT((estimate.matrix() - motion.truth(frame).matrix()).cwiseAbs().maxCoeff(), 1e-9);
  }
  const int before = corrections.front() - 1;
  EXPECT_GT((motion.odometry(before).translation() - motion.truth(before).translation()).norm(),
            0.2);
}

}  // namespace
}  // namespace occupancy_fusion
