// The rules of the mapping session that the nodelets and offline_mapper share: the duplicate-stamp
// key, the laser sources' sensor frame and tilt, upside-down scanners, poses that are not finite.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "occupancy_fusion/mapping/mapping_session.h"

namespace occupancy_fusion {
namespace {

// Poses by sensor frame, the same at every stamp.
class FixedPoses : public PoseSource {
 public:
  std::map<std::string, Eigen::Isometry3d> poses;
  std::optional<Eigen::Isometry3d> lookup(const std::string&, const std::string& sensor_frame,
                                          double, std::string* why) const override {
    const auto pose = poses.find(sensor_frame);
    if (pose != poses.end()) return pose->second;
    *why = "unknown frame '" + sensor_frame + "'";
    return std::nullopt;
  }
};

MappingSessionConfig sessionConfig() {
  MappingSessionConfig config;
  config.map.resolution = 0.1;
  return config;
}

PointCloudFrame cloud(const std::string& source, const std::string& frame_id, double stamp) {
  PointCloudFrame frame;
  frame.header.kind = "point_cloud";
  frame.header.source = source;
  frame.header.frame_id = frame_id;
  frame.header.stamp = stamp;
  frame.header.T_map_sensor = Eigen::Isometry3d::Identity();
  frame.points = {{2.0f, 0.0f, 0.0f}, {2.0f, 0.5f, 0.0f}};
  return frame;
}

// A scan of 61 beams over +-0.6 rad: a wall 3 m ahead, and 9 beams (0.4 to 0.56 rad) 1 m short.
LaserScanFrame scan(const std::string& source, const std::string& frame_id, double stamp) {
  LaserScanFrame frame;
  frame.header.kind = "laser";
  frame.header.source = source;
  frame.header.frame_id = frame_id;
  frame.header.stamp = stamp;
  frame.scan.angle_min = -0.6;
  frame.scan.angle_increment = 0.02;
  frame.scan.range_min = 0.1;
  frame.scan.range_max = 10.0;
  frame.scan.ranges.assign(61, 3.0f);
  for (int beam = 50; beam <= 58; ++beam) frame.scan.ranges[beam] = 2.0f;
  return frame;
}

std::map<std::pair<int, int>, float> cells(const GridLayer2D& layer) {
  std::map<std::pair<int, int>, float> known;
  layer.forEachKnownCell([&](const CellIndex& index, float log_odds) {
    known[{index.x(), index.y()}] = log_odds;
  });
  return known;
}

TEST(MappingSessionDuplicates, KeyIsTheSensorKindAndFrameNotTheTopic) {
  MappingSession session(sessionConfig(), nullptr, nullptr);
  EXPECT_TRUE(session.integrate(cloud("/a", "cam", 5.0)).integrated);
  // The same sensor's frame on another topic, same stamp: the same evidence again.
  const FrameOutcome again = session.integrate(cloud("/b", "cam", 5.0));
  EXPECT_FALSE(again.integrated);
  EXPECT_STREQ(again.drop, MappingSession::kDropDuplicateStamp);
  // Another sensor at that stamp, and the first one later, are new.
  EXPECT_TRUE(session.integrate(cloud("/a", "other_cam", 5.0)).integrated);
  EXPECT_TRUE(session.integrate(cloud("/a", "cam", 5.1)).integrated);
  // Unstamped frames (files without times) are never duplicates.
  EXPECT_TRUE(session.integrate(cloud("/a", "cam", 0.0)).integrated);
  EXPECT_TRUE(session.integrate(cloud("/a", "cam", 0.0)).integrated);
  EXPECT_EQ(session.statistics().frames_by_kind.at("point_cloud"), 5u);
  EXPECT_EQ(session.statistics().skipped_by_reason.at("duplicate stamp on /b"), 1u);
  // A looped recording starts over: its frames are no duplicates.
  session.forgetStamps();
  EXPECT_TRUE(session.integrate(cloud("/a", "cam", 5.1)).integrated);
}

TEST(MappingSessionDuplicates, AFrameNotIntegratedLeavesNoStamp) {
  FixedPoses poses;  // knows no frame
  MappingSession session(sessionConfig(), &poses, nullptr);
  PointCloudFrame unplaced = cloud("/a", "cam", 5.0);
  unplaced.header.T_map_sensor.reset();
  const FrameOutcome no_pose = session.integrate(unplaced);
  EXPECT_STREQ(no_pose.drop, MappingSession::kDropNoPose);
  EXPECT_NE(no_pose.detail.find("unknown frame 'cam'"), std::string::npos) << no_pose.detail;
  EXPECT_TRUE(session.integrate(cloud("/a", "cam", 5.0)).integrated);
}

TEST(MappingSessionPoses, APoseThatIsNotFiniteIsDropped) {
  MappingSession session(sessionConfig(), nullptr, nullptr);
  PointCloudFrame frame = cloud("/a", "cam", 5.0);
  frame.header.T_map_sensor->translation().x() = std::nan("");
  EXPECT_STREQ(session.integrate(frame).drop, MappingSession::kDropPoseNotFinite);
  EXPECT_EQ(session.map().knownVoxelCount(), 0u);
}

// Cells known in only one of the layers, or whose log-odds differ by more than 0.01.
std::size_t differingCells(const std::map<std::pair<int, int>, float>& a,
                           const std::map<std::pair<int, int>, float>& b) {
  std::size_t differing = 0;
  for (const auto& [cell, log_odds] : a) {
    const auto other = b.find(cell);
    differing += other == b.end() || std::abs(other->second - log_odds) > 0.01f ? 1 : 0;
  }
  for (const auto& entry : b) differing += a.count(entry.first) == 0 ? 1 : 0;
  return differing;
}

// A scanner mounted upside down (rolled by pi) at the same place sweeps clockwise: mirrored, its
// scan of the same world lands where the upright scanner's does. The short beams (world angles
// 0.4 to 0.56 rad, 2 m from (1, 2)) make cell (28, 29) occupied.
TEST(MappingSessionLaser, UpsideDownScannerIsMirroredOntoTheSameCells) {
  FixedPoses poses;
  poses.poses["upright"] = Eigen::Isometry3d(Eigen::Translation3d(1.0, 2.0, 0.3));
  poses.poses["upside_down"] = Eigen::Isometry3d(Eigen::Translation3d(1.0, 2.0, 0.3) *
                                                 Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  MappingSession upright(sessionConfig(), &poses, nullptr);
  ASSERT_TRUE(upright.integrate(scan("/front", "upright", 1.0)).integrated);
  const auto expected = cells(upright.laserLayer());
  ASSERT_GT(expected.size(), 100u);
  ASSERT_GT(expected.at({28, 29}), 0.0f);
  // Upside down, the beam at sensor angle a looks along world angle -a: the ranges reversed.
  LaserScanFrame flipped = scan("/rear", "upside_down", 1.0);
  std::reverse(flipped.scan.ranges.begin(), flipped.scan.ranges.end());
  MappingSession upside_down(sessionConfig(), &poses, nullptr);
  ASSERT_TRUE(upside_down.integrate(flipped).integrated);
  const auto mirrored = cells(upside_down.laserLayer());
  EXPECT_GT(mirrored.at({28, 29}), 0.0f);
  EXPECT_LT(differingCells(mirrored, expected), expected.size() / 100);
  // The same ranges taken as an upright scanner's (no mirroring) put the short beams at -0.48 rad:
  // the test can fail.
  LaserScanFrame unmirrored = flipped;
  unmirrored.header.frame_id = "upright";
  MappingSession wrong(sessionConfig(), &poses, nullptr);
  ASSERT_TRUE(wrong.integrate(unmirrored).integrated);
  EXPECT_LT(cells(wrong.laserLayer()).at({28, 29}), 0.0f);
  EXPECT_GT(differingCells(cells(wrong.laserLayer()), expected), 10u);
}

TEST(MappingSessionLaser, SourcesChooseSensorFrameAndTilt) {
  FixedPoses poses;
  poses.poses["mount"] = Eigen::Isometry3d(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()));
  MappingSessionConfig config = sessionConfig();
  LaserSourceConfig front;
  front.name = "front";
  front.topic = "front/scan";  // as configured: no leading slash
  front.sensor_frame = "mount";
  front.max_tilt = 0.3;
  config.laser_sources = {front};
  config.laser_max_tilt = 0.1;
  MappingSession session(config, &poses, nullptr);
  const LaserScanFrame from_front = scan("/front/scan", "frame_in_message", 1.0);
  EXPECT_EQ(session.sensorFrameOf(from_front.header), "mount");
  EXPECT_DOUBLE_EQ(session.maxTiltOf(from_front.header), 0.3);
  EXPECT_TRUE(session.integrate(from_front).integrated);  // tilted 0.2 rad: within 0.3
  // Another topic: the message's frame and the default tilt (0.1 rad: 0.2 is too much).
  LaserScanFrame other = scan("/other/scan", "mount", 1.0);
  EXPECT_EQ(session.sensorFrameOf(other.header), "mount");
  const FrameOutcome tilted = session.integrate(other);
  EXPECT_STREQ(tilted.drop, MappingSession::kDropTiltedScanPlane);
}

}  // namespace
}  // namespace occupancy_fusion
