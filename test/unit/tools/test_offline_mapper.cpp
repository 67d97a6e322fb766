// End to end: simulated recordings -> the built offline_mapper -> map files, checked against the
// simulator's ground truth and read back with liboctomap and independent file readers.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <octomap/OcTree.h>
#include <ros/time.h>
#include <rosbag/bag.h>
#include <tf2_msgs/TFMessage.h>
#include <yaml-cpp/yaml.h>

#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/tools/ros_conversions.h"
#include "occupancy_fusion/tools/simulated_recording.h"
#include "tool_test_support.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

constexpr double kResolution = 0.05;
constexpr double kMinZ = 0.1;
constexpr double kMaxZ = 2.0;
constexpr int kFrames = 12;

std::string configText() {
  std::ostringstream text;
  text << "# as rosparam would load it into the point-cloud mapper\n"
       << "resolution: " << kResolution << "\nframe_id: map\n"
       << "sensor_model:\n  hit: 0.7\n  miss: 0.4\n  max_range: 8.0\n"
       << "occupancy_min_z: " << kMinZ << "\noccupancy_max_z: " << kMaxZ << "\n";
  return text.str();
}

class OfflineMapperTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::vector<std::unique_ptr<SimulatedSensor>> sensors;
    sensors.push_back(std::make_unique<PointCloudCameraSensor>(PointCloudCameraConfig()));
    dir_ = makeRoomRecordingDir(configText(), kFrames, sensors);
    mapped_ = mapBag(dir_ / "room.bag", "out", " --name room");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  // offline_mapper with mapper.yaml on `bag`, quiet, writing to <dir_>/<output_dir>.
  static RunResult mapBag(const fs::path& bag, const std::string& output_dir,
                          const std::string& extra_options = "") {
    return runTool(OFFLINE_MAPPER_PATH,
                   "--config '" + (dir_ / "mapper.yaml").string() + "' --bag '" + bag.string() +
                       "' --output-dir '" + (dir_ / output_dir).string() + "' --quiet" +
                       extra_options,
                   dir_);
  }

  static fs::path dir_;
  static RunResult mapped_;
};

fs::path OfflineMapperTest::dir_;
RunResult OfflineMapperTest::mapped_;

TEST_F(OfflineMapperTest, WritesEveryFileAndASummary) {
  ASSERT_EQ(mapped_.exit_code, 0) << mapped_.err;
  for (const char* extension :
       {".bt", ".ot", ".pcd", ".pgm", ".yaml", ".npy", ".png", ".laser.npy", ".laser.yaml"}) {
    const fs::path path = dir_ / "out" / (std::string("room") + extension);
    EXPECT_TRUE(fs::is_regular_file(path)) << path;
    EXPECT_GT(fs::file_size(path), 0u) << path;
  }
  EXPECT_NE(mapped_.out.find(std::to_string(kFrames) + " point_cloud integrated, 0 skipped"),
            std::string::npos)
      << mapped_.out;
  EXPECT_NE(mapped_.out.find("ms per integrated frame"), std::string::npos) << mapped_.out;
}

TEST_F(OfflineMapperTest, OccupiedVoxelsOfTheBtLieOnTheScenesSurfaces) {
  ASSERT_EQ(mapped_.exit_code, 0) << mapped_.err;
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary((dir_ / "out" / "room.bt").string()));
  ASSERT_NEAR(tree.getResolution(), kResolution, 1e-9);
  const sim::Scene scene = sim::makeRoomScene();
  const double diagonal = std::sqrt(3.0) * kResolution;
  std::size_t occupied = 0, near_surface = 0, free = 0, free_inside_solid = 0;
  for (auto leaf = tree.begin_leafs(); leaf != tree.end_leafs(); ++leaf) {
    const bool is_occupied = tree.isNodeOccupied(*leaf);
    for (const Eigen::Vector3d& centre : voxelCentres(leaf, kResolution)) {
      if (is_occupied) {
        ++occupied;
        if (scene.distanceToSurface(centre) <= diagonal) ++near_surface;
      } else {
        ++free;
        // Deep inside a solid: no ray can have crossed it.
        if (scene.isOccupied(centre) && scene.distanceToSurface(centre) > diagonal) {
          ++free_inside_solid;
        }
      }
    }
  }
  ASSERT_GT(occupied, 5000u);  // a dozen views of walls, floor and furniture
  ASSERT_GT(free, 50000u);
  EXPECT_GE(static_cast<double>(near_surface), 0.95 * occupied)
      << near_surface << " of " << occupied;
  EXPECT_LE(static_cast<double>(free_inside_solid), 0.001 * free)
      << free_inside_solid << " of " << free;
}

TEST_F(OfflineMapperTest, TwoDimensionalFilesAgreeWithEachOtherAndTheScene) {
  ASSERT_EQ(mapped_.exit_code, 0) << mapped_.err;
  const YAML::Node yaml = YAML::LoadFile((dir_ / "out" / "room.yaml").string());
  EXPECT_EQ(yaml["image"].as<std::string>(), "room.pgm");
  EXPECT_NEAR(yaml["resolution"].as<double>(), kResolution, 1e-9);
  const double origin_x = yaml["origin"][0].as<double>();
  const double origin_y = yaml["origin"][1].as<double>();
  const Pgm pgm = readPgm(dir_ / "out" / "room.pgm");
  const Npy npy = readNpy(dir_ / "out" / "room.npy");
  ASSERT_EQ(npy.rows, pgm.height);
  ASSERT_EQ(npy.cols, pgm.width);
  // The room is 8 x 6 m; the map cannot reach beyond its outer walls.
  EXPECT_LE(pgm.width * kResolution, 8.0 + 1e-6);
  EXPECT_LE(pgm.height * kResolution, 6.0 + 1e-6);

  const sim::Scene scene = sim::makeRoomScene();
  const double threshold = 0.0;  // log-odds of p = 0.5
  std::size_t occupied = 0, occupied_near_solid = 0, free = 0;
  for (int row = 0; row < pgm.height; ++row) {
    const int y = pgm.height - 1 - row;  // the pgm's first row is the highest y
    for (int x = 0; x < pgm.width; ++x) {
      const std::uint8_t pixel = pgm.pixels[static_cast<std::size_t>(row) * pgm.width + x];
      const float log_odds = npy.values[static_cast<std::size_t>(y) * npy.cols + x];
      const std::uint8_t expected = std::isnan(log_odds) ? 205 : (log_odds > threshold ? 0 : 254);
      ASSERT_EQ(pixel, expected) << "cell " << x << ", " << y;
      if (pixel == 254) ++free;
      if (pixel != 0) continue;
      ++occupied;
      // Some point of this column within the height band is near a surface.
      const Eigen::Vector2d centre(origin_x + (x + 0.5) * kResolution,
                                   origin_y + (y + 0.5) * kResolution);
      double nearest = 1e9;
      for (double z = kMinZ; z <= kMaxZ; z += kResolution / 2) {
        nearest = std::min(nearest, scene.distanceToSurface({centre.x(), centre.y(), z}));
      }
      if (nearest <= std::sqrt(3.0) * kResolution) ++occupied_near_solid;
    }
  }
  ASSERT_GT(occupied, 300u);  // the walls alone are 28 m long: 560 cells
  ASSERT_GT(free, 2000u);
  EXPECT_GE(static_cast<double>(occupied_near_solid), 0.95 * occupied);
}

// Appends two clouds nothing can place: one in a frame no tf mentions, one after the last pose.
void appendUnplaceableClouds(const fs::path& bag_path) {
  rosbag::Bag bag(bag_path.string(), rosbag::bagmode::Append);
  const std::vector<Eigen::Vector3f> points = {{1.0f, 0.0f, 2.0f}, {0.0f, 1.0f, 2.0f}};
  const ros::Time inside(1000.5), after(2000.0);
  bag.write("/cloud_in", inside, cloudFromPoints(points, "unmounted_camera", inside));
  bag.write("/cloud_in", after, cloudFromPoints(points, "camera_optical_frame", after));
  bag.close();
}

TEST_F(OfflineMapperTest, SkipsAndCountsCloudsWithoutTransform) {
  const fs::path bag = dir_ / "unplaceable.bag";
  fs::copy_file(dir_ / "room.bag", bag, fs::copy_options::overwrite_existing);
  appendUnplaceableClouds(bag);
  const RunResult result =
      mapBag(bag, "skip", " --set sensor_model/max_rnage=3 --set occupancy_max_z=1.5");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find(std::to_string(kFrames) + " point_cloud integrated, 2 skipped"),
            std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("skipped 1: no transform from 'unmounted_camera' to 'map'"),
            std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("skipped 1: no transform from 'camera_optical_frame' to 'map'"),
            std::string::npos)
      << result.out;
  EXPECT_NE(result.err.find("warning: skipping frame"), std::string::npos) << result.err;
  // The misspelt override is reported, the used one is not.
  EXPECT_NE(result.err.find("--set sensor_model/max_rnage was not read"), std::string::npos)
      << result.err;
  EXPECT_EQ(result.err.find("occupancy_max_z was not read"), std::string::npos) << result.err;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "skip" / "map.bt"));
}

TEST_F(OfflineMapperTest, SkipsACloudWithTheStampOfTheOneBeforeIt) {
  const fs::path bag_path = dir_ / "duplicate.bag";
  fs::copy_file(dir_ / "room.bag", bag_path, fs::copy_options::overwrite_existing);
  {
    rosbag::Bag bag(bag_path.string(), rosbag::bagmode::Append);
    const std::vector<Eigen::Vector3f> points = {{1.0f, 0.0f, 2.0f}, {0.0f, 1.0f, 2.0f}};
    const ros::Time stamp(1000.55);  // within the recorded poses
    for (int copy = 0; copy < 2; ++copy) {
      bag.write("/cloud_in", stamp, cloudFromPoints(points, "camera_optical_frame", stamp));
    }
  }
  const RunResult result = mapBag(bag_path, "duplicate");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find(std::to_string(kFrames + 1) + " point_cloud integrated, 1 skipped"),
            std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("skipped 1: duplicate stamp on /cloud_in"), std::string::npos)
      << result.out;
}

// A second pass appended after the first (a bag recorded from a looped playback): tf stamps go
// back 2.75 s. Its poses would mix with the first pass's in one tf buffer, so it is not mapped.
TEST_F(OfflineMapperTest, StopsWhereTheRecordingsTimeJumpsBack) {
  const fs::path bag_path = dir_ / "looped.bag";
  fs::copy_file(dir_ / "room.bag", bag_path, fs::copy_options::overwrite_existing);
  {
    rosbag::Bag bag(bag_path.string(), rosbag::bagmode::Append);
    const ros::Time first_pose(1000.0), replay(2000.0);
    geometry_msgs::TransformStamped pose;
    pose.header.frame_id = "map";
    pose.child_frame_id = "odom";
    pose.header.stamp = first_pose;
    pose.transform.rotation.w = 1.0;
    tf2_msgs::TFMessage poses;
    poses.transforms.push_back(pose);
    bag.write("/tf", replay, poses);
    const std::vector<Eigen::Vector3f> points = {{1.0f, 0.0f, 2.0f}, {0.0f, 1.0f, 2.0f}};
    const ros::Time stamp(1000.55);
    bag.write("/cloud_in", replay + ros::Duration(0.1),
              cloudFromPoints(points, "camera_optical_frame", stamp));
  }
  const RunResult result = mapBag(bag_path, "looped");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find(std::to_string(kFrames) + " point_cloud integrated"), std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("tf stamps jump back by 2.75"), std::string::npos) << result.out;
}

TEST_F(OfflineMapperTest, FailsWhenNoFrameCanBePlaced) {
  const RunResult result = mapBag(dir_ / "room.bag", "none", " --set frame_id=nowhere");
  EXPECT_EQ(result.exit_code, 1) << result.err;
  EXPECT_NE(result.out.find("frames: 0 integrated, " + std::to_string(kFrames) + " skipped"),
            std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("no transform from 'camera_optical_frame' to 'nowhere'"),
            std::string::npos)
      << result.out;
}

TEST_F(OfflineMapperTest, BadArgumentsExitWithTwoAndSayWhy) {
  const std::string config = " --config '" + (dir_ / "mapper.yaml").string() + "'";
  const std::string bag = " --bag '" + (dir_ / "room.bag").string() + "'";
  const std::string out = " --output-dir '" + (dir_ / "bad").string() + "'";
  const struct {
    std::string arguments;
    std::string message;
  } cases[] = {
      {config + out, "missing input: give --bag"},
      {config + bag, "missing --output-dir"},
      {config + out + " --bag /nonexistent/in.bag", "no such file: /nonexistent/in.bag"},
      {config + bag + out + " --frobnicate 3", "unknown option '--frobnicate'"},
      {config + bag + out + " stray", "unexpected argument 'stray'"},
      {config + bag + out + " --set resolution=fine", "resolution"},
      {config + bag + out + " --set sensor_model/hit=1.5", "sensor_model/hit"},
      {config + bag + out + " --set resolution", "--set 'resolution': expected key=value"},
      {config + bag + out + " --cloud-topic /missing", "/missing"},
      {config + " --bag '" + (dir_ / "mapper.yaml").string() + "'" + out, "cannot open bag"},
  };
  for (const auto& test_case : cases) {
    const RunResult result = runTool(OFFLINE_MAPPER_PATH, test_case.arguments, dir_);
    EXPECT_EQ(result.exit_code, 2) << test_case.arguments << "\n" << result.err;
    EXPECT_NE(result.err.find(test_case.message), std::string::npos) << test_case.arguments << "\n"
                                                                     << result.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "bad" / "map.bt"));
}

TEST(SimulateRecording, WritesABagAndRejectsBadArguments) {
  const fs::path dir = makeTempDir();
  const RunResult good = runTool(
      SIMULATE_RECORDING_PATH,
      "--scene corridor --frames 3 --rate 10 --output '" + (dir / "c.bag").string() + "'", dir);
  EXPECT_EQ(good.exit_code, 0) << good.err;
  EXPECT_TRUE(fs::is_regular_file(dir / "c.bag"));
  for (const std::string& arguments :
       {std::string("--scene nowhere --output x.bag"), std::string("--frames 0 --output x.bag"),
        std::string("--rate fast --output x.bag"), std::string("--frames 3")}) {
    const RunResult bad = runTool(SIMULATE_RECORDING_PATH, arguments, dir);
    EXPECT_EQ(bad.exit_code, 2) << arguments;
    EXPECT_NE(bad.err.find("error:"), std::string::npos) << arguments;
  }
  // Deterministic: the same options give the same bag, byte for byte.
  const std::string same = "--scene room --frames 2 --output '";
  ASSERT_EQ(runTool(SIMULATE_RECORDING_PATH, same + (dir / "a.bag").string() + "'", dir).exit_code,
            0);
  ASSERT_EQ(runTool(SIMULATE_RECORDING_PATH, same + (dir / "b.bag").string() + "'", dir).exit_code,
            0);
  EXPECT_EQ(readText(dir / "a.bag"), readText(dir / "b.bag"));
  const RunResult unknown_scene =
      runTool(SIMULATE_RECORDING_PATH, "--scene nowhere --output x.bag", dir);
  EXPECT_NE(unknown_scene.err.find("room"), std::string::npos);  // lists the known scenes
  fs::remove_all(dir);
}

}  // namespace
}  // namespace occupancy_fusion
