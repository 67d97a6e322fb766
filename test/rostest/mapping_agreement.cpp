// offline_mapper maps a recording exactly as the nodelets map it live (mapping_agreement.test).
// The recording exercises every rule the two once applied differently: depth camera_info whose P
// differs from K, disparity with a valid window (and other values outside it) and an unset
// max_disparity, a left camera_info whose P differs from K, two laser scanners one of them upside
// down with a source of its own settings, and a depth image republished with the stamp of the one
// before it (different pixels: integrated, it would change the map). The depth camera looks left
// (+y), the stereo camera right (-y): their voxels never meet, so the order in which the two
// mappers' threads integrate cannot matter. The test plays the bag to the nodelets, saves the map
// with the MapServer's ~save_map, maps the bag with offline_mapper and compares both maps voxel
// for voxel and laser cell for cell.
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <stereo_msgs/DisparityImage.h>
#include <tf2_msgs/TFMessage.h>
#include <topic_tools/shape_shifter.h>
#include <Eigen/Geometry>

#include "occupancy_fusion/SaveMap.h"
#include "occupancy_fusion/map/layer_files.h"
#include "occupancy_fusion/map/map_files.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

constexpr int kFrames = 6;
constexpr double kStart = 1000.0, kPeriod = 0.2;  // s
constexpr double kResolution = 0.1;               // mapping_agreement.yaml
constexpr int kDuplicatedFrame = 3;               // its depth image comes twice

ros::Time stampOf(int frame) { return ros::Time(kStart + kPeriod * frame); }

// The robot drives along x.
Eigen::Isometry3d baseInMap(int frame) {
  return Eigen::Isometry3d(Eigen::Translation3d(0.1 * frame, 0.0, 0.0));
}

// Optical frames (z forward, x right, y down) looking along the base's +y and -y.
Eigen::Isometry3d opticalLooking(double side, const Eigen::Vector3d& at) {
  Eigen::Matrix3d rotation;
  rotation.col(2) = Eigen::Vector3d(0.0, side, 0.0);  // z: forward
  rotation.col(0) = Eigen::Vector3d(side, 0.0, 0.0);  // x: right of forward
  rotation.col(1) = Eigen::Vector3d(0.0, 0.0, -1.0);  // y: down
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation;
  pose.translation() = at;
  return pose;
}
const Eigen::Isometry3d kDepthInBase = opticalLooking(1.0, {0.0, 0.1, 0.5});
const Eigen::Isometry3d kStereoInBase = opticalLooking(-1.0, {0.0, -0.1, 0.5});
const Eigen::Isometry3d kFrontLaserInBase(Eigen::Translation3d(0.2, 0.0, 0.3));
// Upside down (rolled by pi), looking backwards.
const Eigen::Isometry3d kRearLaserInBase(Eigen::Translation3d(-0.2, 0.0, 0.3) *
                                         Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()) *
                                         Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));

geometry_msgs::TransformStamped transform(const Eigen::Isometry3d& pose, const std::string& parent,
                                          const std::string& child, const ros::Time& stamp) {
  geometry_msgs::TransformStamped message;
  message.header.frame_id = parent;
  message.header.stamp = stamp;
  message.child_frame_id = child;
  message.transform.translation.x = pose.translation().x();
  message.transform.translation.y = pose.translation().y();
  message.transform.translation.z = pose.translation().z();
  const Eigen::Quaterniond rotation(pose.rotation());
  message.transform.rotation.x = rotation.x();
  message.transform.rotation.y = rotation.y();
  message.transform.rotation.z = rotation.z();
  message.transform.rotation.w = rotation.w();
  return message;
}

// K and P of a rectified camera: P is what the images are in, K (unrectified) differs.
sensor_msgs::CameraInfo cameraInfo(const std::string& frame, const ros::Time& stamp, int width,
                                   int height, double f_k, double f_p) {
  sensor_msgs::CameraInfo info;
  info.header.frame_id = frame;
  info.header.stamp = stamp;
  info.width = width;
  info.height = height;
  info.distortion_model = "plumb_bob";
  info.D = {0.02, -0.01, 0.0, 0.0, 0.0};
  info.K = {f_k, 0.0, width / 2.0 - 2.0, 0.0, f_k, height / 2.0 - 1.0, 0.0, 0.0, 1.0};
  info.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.P = {f_p, 0.0, (width - 1) / 2.0, 0.0, 0.0, f_p, (height - 1) / 2.0, 0.0, 0.0, 0.0,
            1.0, 0.0};
  return info;
}

// A wall 2.4 m ahead with a box 1.5 m ahead; the duplicate's pixels are all 1 m.
sensor_msgs::Image depthImage(int frame, bool duplicate) {
  constexpr int kWidth = 40, kHeight = 30;
  std::vector<float> depth(kWidth * kHeight, 2.4f);
  for (int v = 5; v < 13; ++v) {
    for (int u = 10 + frame; u < 20 + frame; ++u) depth[v * kWidth + u] = 1.5f;
  }
  if (duplicate) depth.assign(depth.size(), 1.0f);
  return floatImage(depth, kWidth, kHeight, "depth_optical", stampOf(frame));
}

// d = f T / z: a wall 2.9 m ahead, a patch 2 m ahead; outside the valid window the matcher's
// border garbage (d = 40, 1 m), which both sides must ignore.
constexpr int kStereoWidth = 48, kStereoHeight = 36;
constexpr double kStereoFocal = 60.0, kStereoBaseline = 0.5;
stereo_msgs::DisparityImage disparityImage(int frame) {
  std::vector<float> disparity(kStereoWidth * kStereoHeight, 40.0f);
  for (int v = 4; v < 32; ++v) {
    for (int u = 6; u < 42; ++u) {
      const bool patch = v >= 10 && v < 18 && u >= 20 && u < 28;
      disparity[v * kStereoWidth + u] =
          static_cast<float>(kStereoFocal * kStereoBaseline / (patch ? 2.0 : 2.9));
    }
  }
  stereo_msgs::DisparityImage message;
  message.header.frame_id = "stereo_optical";
  message.header.stamp = stampOf(frame);
  message.image =
      floatImage(disparity, kStereoWidth, kStereoHeight, "stereo_optical", message.header.stamp);
  message.f = static_cast<float>(kStereoFocal);
  message.T = static_cast<float>(kStereoBaseline);
  message.valid_window.x_offset = 6;
  message.valid_window.y_offset = 4;
  message.valid_window.width = 36;
  message.valid_window.height = 28;
  message.min_disparity = 1.0f;
  message.max_disparity = 0.0f;  // not filled in: no upper bound
  message.delta_d = 1.0f / 16.0f;
  return message;
}

// 91 beams over 180 degrees in a room of walls at x = -4 and 5, y = -3 and 3, ray-cast from the
// scanner's pose in the map (so the upside-down scanner's beams go clockwise).
sensor_msgs::LaserScan laserScan(int frame, const Eigen::Isometry3d& laser_in_base,
                                 const std::string& frame_id) {
  const Eigen::Isometry3d laser = baseInMap(frame) * laser_in_base;
  sensor_msgs::LaserScan scan;
  scan.header.frame_id = frame_id;
  scan.header.stamp = stampOf(frame);
  scan.angle_min = static_cast<float>(-M_PI / 2);
  scan.angle_increment = static_cast<float>(M_PI / 90);
  scan.angle_max = static_cast<float>(scan.angle_min + 90 * scan.angle_increment);
  scan.range_min = 0.1f;
  scan.range_max = 8.0f;
  for (int beam = 0; beam <= 90; ++beam) {
    const double angle = scan.angle_min + beam * scan.angle_increment;
    const Eigen::Vector3d direction =
        laser.linear() * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
    const Eigen::Vector3d& origin = laser.translation();
    double range = std::numeric_limits<double>::infinity();
    const std::array<std::pair<int, double>, 4> walls = {
        {{0, -4.0}, {0, 5.0}, {1, -3.0}, {1, 3.0}}};
    for (const auto& [axis, at] : walls) {
      if (std::abs(direction[axis]) < 1e-9) continue;
      const double t = (at - origin[axis]) / direction[axis];
      if (t > 0.0) range = std::min(range, t);
    }
    scan.ranges.push_back(static_cast<float>(range));
  }
  return scan;
}

void writeRecording(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  tf2_msgs::TFMessage statics;
  statics.transforms = {transform(kDepthInBase, "base_link", "depth_optical", ros::Time(0)),
                        transform(kStereoInBase, "base_link", "stereo_optical", ros::Time(0)),
                        transform(kFrontLaserInBase, "base_link", "laser_front", ros::Time(0)),
                        transform(kRearLaserInBase, "base_link", "laser_rear", ros::Time(0))};
  bag.write("/tf_static", stampOf(0) - ros::Duration(0.1), statics);
  for (int frame = 0; frame < kFrames; ++frame) {
    const ros::Time stamp = stampOf(frame);
    tf2_msgs::TFMessage moving;
    moving.transforms = {transform(baseInMap(frame), "map", "base_link", stamp)};
    bag.write("/tf", stamp, moving);
    bag.write("/camera/depth/camera_info", stamp,
              cameraInfo("depth_optical", stamp, 40, 30, 40.0, 36.0));
    bag.write("/camera/depth/image", stamp, depthImage(frame, false));
    if (frame == kDuplicatedFrame) {
      bag.write("/camera/depth/image", stamp, depthImage(frame, true));
    }
    bag.write("/stereo/left/camera_info", stamp,
              cameraInfo("stereo_optical", stamp, kStereoWidth, kStereoHeight, 64.0, kStereoFocal));
    bag.write("/stereo/disparity", stamp, disparityImage(frame));
    bag.write("/scan_front", stamp, laserScan(frame, kFrontLaserInBase, "laser_front"));
    bag.write("/scan_rear", stamp, laserScan(frame, kRearLaserInBase, "laser_rear"));
  }
  bag.close();
}

// Publishes a bag's messages in its order, as rosbag play does, once every topic has a
// subscriber; a short pause after each lets the mappers keep up without any queue filling.
bool play(const std::string& path) {
  ros::NodeHandle node;
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag);
  std::map<std::string, ros::Publisher> publishers;
  for (const rosbag::ConnectionInfo* connection : view.getConnections()) {
    topic_tools::ShapeShifter shape;
    shape.morph(connection->md5sum, connection->datatype, connection->msg_def, "");
    publishers[connection->topic] =
        shape.advertise(node, connection->topic, 100, connection->topic == "/tf_static");
  }
  const bool connected = waitUntil(
      [&] {
        for (const auto& entry : publishers) {
          if (entry.second.getNumSubscribers() == 0) return false;
        }
        return true;
      },
      30.0);
  if (!connected) return false;
  for (const rosbag::MessageInstance& message : view) {
    publishers[message.getTopic()].publish(*message.instantiate<topic_tools::ShapeShifter>());
    ros::WallDuration(0.02).sleep();
  }
  bag.close();
  return true;
}

class MappingAgreement : public TestFolder {};

TEST_F(MappingAgreement, OfflineMapperMapsTheRecordingAsTheNodeletsDoLive) {
  const std::string bag = path("recording.bag");
  writeRecording(bag);

  ros::NodeHandle node_handle;
  const MapObserver diagnostics(node_handle);
  ASSERT_TRUE(play(bag)) << "the mappers did not subscribe";
  const auto integrated = [&](const char* task) {
    return diagnostics.diagnosticCount(task, "frames integrated");
  };
  ASSERT_TRUE(waitUntil(
      [&] {
        return integrated("depth mapping") == kFrames &&
               integrated("disparity mapping") == kFrames &&
               integrated("laser mapping") == 2 * kFrames &&
               diagnostics.diagnosticCount("depth mapping", "frames dropped (duplicate stamp)") ==
                   1;
      },
      30.0))
      << "depth " << integrated("depth mapping") << ", disparity "
      << integrated("disparity mapping") << ", laser " << integrated("laser mapping")
      << " frames integrated";
  EXPECT_EQ(diagnostics.diagnosticCount("depth mapping", "frames dropped"), 1u);
  EXPECT_EQ(diagnostics.diagnosticCount("disparity mapping", "frames dropped"), 0u);
  EXPECT_EQ(diagnostics.diagnosticCount("laser mapping", "frames dropped"), 0u);

  SaveMap save;
  save.request.prefix = path("online");
  ASSERT_TRUE(ros::service::call("/map_server/save_map", save));
  ASSERT_TRUE(save.response.success) << save.response.message;

  std::string config;
  ASSERT_TRUE(ros::param::get("~config", config));
  int exit_code = -1;
  const std::string output =
      runCommand(std::string(OFFLINE_MAPPER_PATH) + " --config '" + config + "' --bag '" + bag +
                     "' --output-dir '" + folder_.string() + "' --name offline",
                 &exit_code);
  ASSERT_EQ(exit_code, 0) << output;
  EXPECT_NE(output.find("depth: " + std::to_string(kFrames) + " integrated, 1 skipped"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("skipped 1: duplicate stamp on /camera/depth/image"), std::string::npos)
      << output;

  // Voxel for voxel: the same voxels known, with the same log-odds.
  const VoxelDump online = knownVoxelsOf(path("online.ot"), kResolution);
  const VoxelDump offline = knownVoxelsOf(path("offline.ot"), kResolution);
  std::size_t depth_side = 0, stereo_side = 0, occupied = 0;
  for (const auto& [index, log_odds] : online) {
    (std::get<1>(index) >= 0 ? depth_side : stereo_side) += 1;
    occupied += log_odds > 0.0f ? 1 : 0;
  }
  EXPECT_GT(depth_side, 500u);
  EXPECT_GT(stereo_side, 100u);
  EXPECT_GT(occupied, 50u);
  EXPECT_EQ(online.size(), offline.size());
  std::size_t differing = 0;
  for (const auto& [index, log_odds] : online) {
    const auto other = offline.find(index);
    differing += other == offline.end() || other->second != log_odds ? 1 : 0;
  }
  EXPECT_EQ(differing, 0u) << "of " << online.size() << " voxels";
  RecordProperty("voxels", static_cast<int>(online.size()));
  RecordProperty("voxels_occupied", static_cast<int>(occupied));
  RecordProperty("voxels_depth_side", static_cast<int>(depth_side));
  RecordProperty("voxels_stereo_side", static_cast<int>(stereo_side));

  // Cell for cell: the same laser layer window and log-odds.
  const LogOddsRaster online_layer = readLayerFiles(path("online.laser.yaml"));
  const LogOddsRaster offline_layer = readLayerFiles(path("offline.laser.yaml"));
  ASSERT_EQ(online_layer.width, offline_layer.width);
  ASSERT_EQ(online_layer.height, offline_layer.height);
  EXPECT_EQ(online_layer.origin_cell, offline_layer.origin_cell);
  std::size_t known = 0, behind = 0, differing_cells = 0;
  for (std::size_t i = 0; i < online_layer.data.size(); ++i) {
    const float a = online_layer.data[i], b = offline_layer.data[i];
    if (std::isnan(a) != std::isnan(b) || (!std::isnan(a) && a != b)) ++differing_cells;
    if (std::isnan(a)) continue;
    ++known;
    // Only the rear (upside-down) scanner sees behind x = -1 m.
    const int x = online_layer.origin_cell.x() + static_cast<int>(i % online_layer.width);
    behind += (x + 0.5) * kResolution < -1.0 ? 1 : 0;
  }
  EXPECT_GT(known, 1000u);
  EXPECT_GT(behind, 300u);
  EXPECT_EQ(differing_cells, 0u) << "of " << online_layer.data.size() << " cells";
  RecordProperty("layer_cells_known", static_cast<int>(known));
  RecordProperty("layer_cells_behind", static_cast<int>(behind));
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "mapping_agreement");
  return occupancy_fusion::runTestsWhileSpinning();
}
