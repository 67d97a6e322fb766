// End to end for offline_mapper's input kinds: simulated bags with depth images, disparity and
// two laser scanners, 7-Scenes-layout depth folders, Middlebury-layout PFM folders and CARMEN
// logs written here, each mapped by the built tool and checked against the simulator's ground
// truth; bad frames are skipped and counted.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <opencv2/imgcodecs.hpp>

#include "occupancy_fusion/map/layer_files.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/trajectory.h"
#include "occupancy_fusion/tools/ros_conversions.h"
#include "occupancy_fusion/tools/rosbag_reader.h"
#include "occupancy_fusion/tools/simulated_recording.h"
#include "tool_test_support.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

constexpr double kResolution = 0.05;
constexpr int kFrames = 8;

// The integrators' parameters for the simulated sensors at 5 cm: a narrow depth model (Eq. 7
// with k / (sigma sqrt(2 pi)) < 0.5) and the simulated matcher's disparity noise.
std::string configText() {
  std::ostringstream text;
  text << "resolution: " << kResolution << "\nframe_id: map\n"
       << "sensor_model:\n  hit: 0.7\n  miss: 0.4\n  max_range: 8.0\n"
       << "depth:\n  k: 0.05\n  sigma: 0.05\n  max_range: 8.0\n"
       << "stereo:\n  disparity_sigma_px: 0.1\n  max_range: 8.0\n"
       // Few frames of different views: unknown neighbours must occlude less than the default
       // (Eq. 1 at 0.5 lets a new view reach only a few voxels deep, the paper's Fig. 5a).
       << "  unknown_neighbour_occupancy: 0.2\n"
       << "laser:\n  method: exact\n  range_sigma: 0.01\n";
  return text.str();
}

std::string quoted(const fs::path& path) { return "'" + path.string() + "'"; }

// Voxels of a .bt file classified against the scene.
struct VoxelCheck {
  std::size_t occupied = 0;
  std::size_t occupied_near_surface = 0;  // within `tolerance` of a surface
  // Farther than `tolerance` from every surface in the room's open space (not inside a solid,
  // not behind the outer walls): space a camera saw through.
  std::size_t occupied_in_open_space = 0;
  std::size_t free = 0;
  std::size_t free_inside_solid = 0;  // deeper than `tolerance` inside a solid
};

VoxelCheck checkVoxels(const fs::path& bt, const sim::Scene& scene, double tolerance) {
  octomap::OcTree tree(0.1);
  EXPECT_TRUE(tree.readBinary(bt.string())) << bt;
  VoxelCheck check;
  for (auto leaf = tree.begin_leafs(); leaf != tree.end_leafs(); ++leaf) {
    const bool occupied = tree.isNodeOccupied(*leaf);
    for (const Eigen::Vector3d& centre : voxelCentres(leaf, kResolution)) {
      const double distance = scene.distanceToSurface(centre);
      if (occupied) {
        ++check.occupied;
        if (distance <= tolerance) ++check.occupied_near_surface;
        const bool in_room = std::abs(centre.x()) < 3.9 && std::abs(centre.y()) < 2.9;
        if (distance > tolerance && in_room && !scene.isOccupied(centre)) {
          ++check.occupied_in_open_space;
        }
      } else {
        ++check.free;
        if (scene.isOccupied(centre) && distance > tolerance) ++check.free_inside_solid;
      }
    }
  }
  return check;
}

// near_fraction: the share of occupied voxels within the tolerance of a surface. The stereo
// method continues each ray behind its point until P(I_v) of Eq. 8 reaches 0.99, about 2.3
// sigma_z (Eq. 7) deep, so its occupied voxels reach farther behind surfaces than the depth
// method's; in front of surfaces both must leave space free.
void expectOnSurfaces(const VoxelCheck& check, std::size_t min_occupied,
                      double near_fraction = 0.95) {
  EXPECT_GT(check.occupied, min_occupied);
  EXPECT_GT(check.free, 10 * min_occupied);
  EXPECT_GE(static_cast<double>(check.occupied_near_surface), near_fraction * check.occupied)
      << check.occupied_near_surface << " of " << check.occupied;
  // The simulated matcher's white noise (0.1 px: sigma_z = 0.15 m at 5 m) puts a few points
  // in front of the surfaces.
  EXPECT_LE(static_cast<double>(check.occupied_in_open_space), 0.02 * check.occupied)
      << check.occupied_in_open_space << " of " << check.occupied;
  EXPECT_LE(static_cast<double>(check.free_inside_solid), 0.001 * check.free)
      << check.free_inside_solid << " of " << check.free;
}

// Cells of the 2D view (only the laser layer when nothing 3D was mapped) against the scene cut
// at the scanners' heights.
struct CellCheck {
  std::size_t occupied = 0;
  std::size_t occupied_near_surface = 0;
  std::size_t free = 0;
  std::size_t free_inside_solid = 0;
};

CellCheck checkLaserCells(const fs::path& npy_path, const fs::path& yaml_path,
                          const sim::Scene& scene, const std::vector<double>& heights,
                          double tolerance) {
  const Npy npy = readNpy(npy_path);
  std::ifstream yaml(yaml_path);
  std::string line;
  double origin_x = 0.0, origin_y = 0.0;
  while (std::getline(yaml, line)) {
    if (line.rfind("origin:", 0) == 0)
      std::sscanf(line.c_str(), "origin: [%lf, %lf", &origin_x, &origin_y);
  }
  CellCheck check;
  for (int y = 0; y < npy.rows; ++y) {
    for (int x = 0; x < npy.cols; ++x) {
      const float log_odds = npy.values[static_cast<std::size_t>(y) * npy.cols + x];
      if (std::isnan(log_odds)) continue;
      const double cx = origin_x + (x + 0.5) * kResolution, cy = origin_y + (y + 0.5) * kResolution;
      double nearest = 1e9;
      bool inside_deep = true;
      for (double z : heights) {
        const Eigen::Vector3d point(cx, cy, z);
        nearest = std::min(nearest, scene.distanceToSurface(point));
        inside_deep =
            inside_deep && scene.isOccupied(point) && scene.distanceToSurface(point) > tolerance;
      }
      if (log_odds > 0.0f) {
        ++check.occupied;
        if (nearest <= tolerance) ++check.occupied_near_surface;
      } else {
        ++check.free;
        if (inside_deep) ++check.free_inside_solid;
      }
    }
  }
  return check;
}

class InputKindsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = makeRoomRecordingDir(configText(), kFrames,
                                makeSimulatedSensors({"depth", "disparity", "scan"}));
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static RunResult map(const std::string& inputs, const std::string& name,
                       const std::string& extra = "") {
    return runTool(OFFLINE_MAPPER_PATH,
                   "--config " + quoted(dir_ / "mapper.yaml") + " " + inputs + " --output-dir " +
                       quoted(dir_ / name) + " --name " + name + " --quiet " + extra,
                   dir_);
  }

  static fs::path dir_;
};

fs::path InputKindsTest::dir_;

TEST_F(InputKindsTest, BagWithDepthDisparityAndTwoScannersMakesOneMap) {
  const RunResult result = map("--bag " + quoted(dir_ / "room.bag"), "all");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const std::string n = std::to_string(kFrames);
  EXPECT_NE(result.out.find("  depth: " + n + " integrated, 0 skipped"), std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("  disparity: " + n + " integrated, 0 skipped"), std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("  laser: " + std::to_string(2 * kFrames) + " integrated, 0 skipped"),
            std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("ms per frame"), std::string::npos) << result.out;
  const VoxelCheck voxels =
      checkVoxels(dir_ / "all" / "all.bt", sim::makeRoomScene(), 2.0 * kResolution);
  expectOnSurfaces(voxels, 3000, 0.8);
}

TEST_F(InputKindsTest, EachCameraAloneMapsTheScenesSurfaces) {
  for (const std::string topic :
       {"--depth-topic /camera/depth/image", "--disparity-topic /stereo/disparity"}) {
    const RunResult result = map("--bag " + quoted(dir_ / "room.bag") + " " + topic, "camera");
    ASSERT_EQ(result.exit_code, 0) << topic << "\n" << result.err;
    EXPECT_NE(result.out.find(std::to_string(kFrames) + " integrated, 0 skipped"),
              std::string::npos)
        << result.out;
    // The disparity model spreads hits by sigma_z = lambda z^2 (Eq. 7): about 1.5 voxels at 4 m.
    const VoxelCheck voxels =
        checkVoxels(dir_ / "camera" / "camera.bt", sim::makeRoomScene(), 2.0 * kResolution);
    SCOPED_TRACE(topic);
    expectOnSurfaces(voxels, 1500, topic.find("disparity") != std::string::npos ? 0.8 : 0.95);
  }
}

// Each scanner alone: the rear one is mounted upside down, so its scans must be mirrored to land
// on the walls.
TEST_F(InputKindsTest, EachLaserScannerAloneMapsTheWallsAtItsHeight) {
  for (const std::string topic : {"/scan_front", "/scan_rear"}) {
    const RunResult result =
        map("--bag " + quoted(dir_ / "room.bag") + " --scan-topic " + topic, "laser");
    ASSERT_EQ(result.exit_code, 0) << topic << "\n" << result.err;
    EXPECT_NE(result.out.find("laser: " + std::to_string(kFrames) + " integrated, 0 skipped"),
              std::string::npos)
        << result.out;
    const CellCheck cells =
        checkLaserCells(dir_ / "laser" / "laser.npy", dir_ / "laser" / "laser.yaml",
                        sim::makeRoomScene(), {0.3, 0.35}, 2.0 * kResolution);
    SCOPED_TRACE(topic);
    EXPECT_GT(cells.occupied, 200u);  // the walls alone are 28 m long
    EXPECT_GT(cells.free, 3000u);
    EXPECT_GE(static_cast<double>(cells.occupied_near_surface), 0.95 * cells.occupied)
        << cells.occupied_near_surface << " of " << cells.occupied;
    EXPECT_LE(static_cast<double>(cells.free_inside_solid), 0.005 * cells.free)
        << cells.free_inside_solid << " of " << cells.free;
    // With lasers only, the fused view is the laser layer: the layer's own files (what the
    // MapServer's load_map resumes) hold the same cells with the same log-odds.
    const LogOddsRaster layer = readLayerFiles((dir_ / "laser" / "laser.laser.yaml").string());
    const Npy fused = readNpy(dir_ / "laser" / "laser.npy");
    ASSERT_EQ(layer.width, fused.cols);
    ASSERT_EQ(layer.height, fused.rows);
    std::size_t differing = 0;
    for (std::size_t i = 0; i < layer.data.size(); ++i) {
      const float a = layer.data[i], b = fused.values[i];
      if (std::isnan(a) != std::isnan(b) || (!std::isnan(a) && a != b)) ++differing;
    }
    EXPECT_EQ(differing, 0u);
  }
}

// Frames nothing can decode or place: skipped, counted per reason, the rest mapped.
TEST_F(InputKindsTest, BadFramesInABagAreSkippedAndCounted) {
  const fs::path bag_path = dir_ / "bad.bag";
  fs::copy_file(dir_ / "room.bag", bag_path, fs::copy_options::overwrite_existing);
  {
    rosbag::Bag bag(bag_path.string(), rosbag::bagmode::Append);
    const ros::Time stamp(1000.5);
    sensor_msgs::Image colour = depthImageMessage(std::vector<float>(4, 1.0f), 2, 2, true,
                                                  "depth_camera_optical_frame", stamp);
    colour.encoding = "rgb8";
    bag.write("/camera/depth/image", stamp, colour);
    // Between two recorded scans: with the sensor_frame override below it is a scan of its
    // own, not a duplicate of the recorded one at `stamp`.
    const ros::Time scan_stamp(1000.55);
    sensor_msgs::LaserScan scan;
    scan.header.frame_id = "unmounted_laser";
    scan.header.stamp = scan_stamp;
    scan.angle_min = -1.0f;
    scan.angle_max = 1.0f;
    scan.angle_increment = 0.5f;
    scan.range_min = 0.1f;
    scan.range_max = 10.0f;
    scan.ranges.assign(5, 2.0f);
    bag.write("/scan_front", scan_stamp, scan);
    bag.close();
  }
  const RunResult result = map("--bag " + quoted(bag_path), "bad");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("depth: " + std::to_string(kFrames) + " integrated, 1 skipped"),
            std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("laser: " + std::to_string(2 * kFrames) + " integrated, 1 skipped"),
            std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("skipped 1: unreadable message on /camera/depth/image (first: "
                            "encoding 'rgb8' is not a depth encoding"),
            std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("skipped 1: no transform from 'unmounted_laser' to 'map'"),
            std::string::npos)
      << result.out;

  // A laser observation source (the laser mapper's per-scanner block) whose sensor_frame
  // overrides the scans' frame: the stray scan is placed too.
  std::ofstream(dir_ / "sources.yaml")
      << "observation_sources: front\nfront: {topic: scan_front, sensor_frame: laser_front}\n";
  const RunResult with_source = map("--bag " + quoted(bag_path) + " --scan-topic /scan_front",
                                    "source", "--config " + quoted(dir_ / "sources.yaml"));
  ASSERT_EQ(with_source.exit_code, 0) << with_source.err;
  EXPECT_NE(
      with_source.out.find("laser: " + std::to_string(kFrames + 1) + " integrated, 0 skipped"),
      std::string::npos)
      << with_source.out;
}

// A 7-Scenes folder written here: 16-bit PNGs in mm (OpenCV), camera-to-world poses, K.
TEST_F(InputKindsTest, SevenScenesFolderIsMappedWithItsPoses) {
  const fs::path folder = dir_ / "seven" / "seq-01";
  fs::create_directories(folder);
  const DepthImageCameraConfig camera;
  std::ofstream(folder.parent_path() / "camera-intrinsics.txt")
      << camera.camera.fx << " 0 " << camera.camera.cx << "\n0 " << camera.camera.fy << " "
      << camera.camera.cy << "\n0 0 1\n";
  fs::copy_file(folder.parent_path() / "camera-intrinsics.txt", folder / "camera-intrinsics.txt");
  const sim::Scene scene = sim::makeRoomScene();
  const SimulatedWorld world = makeSimulatedWorld("room", 6);
  for (int k = 0; k < 6; ++k) {
    const Eigen::Isometry3d T_world_camera =
        world.T_map_base[k] * camera.T_base_link * sim::opticalFrameInBody();
    const sim::DepthImage depth = sim::renderDepth(scene, camera.camera, T_world_camera, 6.0);
    cv::Mat millimetres(depth.height, depth.width, CV_16UC1);
    for (int v = 0; v < depth.height; ++v)
      for (int u = 0; u < depth.width; ++u) {
        const float z = depth.at(u, v);
        millimetres.at<std::uint16_t>(v, u) =
            std::isfinite(z) ? static_cast<std::uint16_t>(std::lround(z * 1000.0f)) : 0;
      }
    std::ostringstream stem;
    stem << "frame-" << std::setw(6) << std::setfill('0') << k;
    ASSERT_TRUE(cv::imwrite((folder / (stem.str() + ".depth.png")).string(), millimetres));
    if (k == 4) continue;  // a depth image without its pose
    std::ofstream pose(folder / (stem.str() + ".pose.txt"));
    pose << std::setprecision(12) << T_world_camera.matrix() << "\n";
  }
  std::ofstream(folder / "frame-000005.depth.png") << "not a png";  // unreadable
  const RunResult result = map("--depth-folder " + quoted(folder), "seven");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("depth: 4 integrated, 2 skipped"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("frame-000004.pose.txt is missing"), std::string::npos) << result.out;
  expectOnSurfaces(checkVoxels(dir_ / "seven" / "seven.bt", scene, 2.0 * kResolution), 1000);
}

void writePfm(const fs::path& path, const sim::DisparityImage& image) {
  std::ofstream file(path, std::ios::binary);
  file << "Pf\n" << image.width << " " << image.height << "\n-1.0\n";
  for (int v = image.height - 1; v >= 0; --v) {  // rows bottom to top
    for (int u = 0; u < image.width; ++u) {
      const float d = image.at(u, v);
      const float stored = std::isfinite(d) ? d : std::numeric_limits<float>::infinity();
      file.write(reinterpret_cast<const char*>(&stored), sizeof(float));  // little-endian host
    }
  }
}

// A Middlebury-layout folder: calib.txt, disp0_NNN.pfm, pose0_NNN.txt.
TEST_F(InputKindsTest, MiddleburyFolderIsMappedWithItsPoses) {
  const fs::path folder = dir_ / "middlebury";
  fs::create_directories(folder);
  const DisparityCameraConfig stereo;
  const sim::PinholeCamera& c = stereo.camera;
  std::ofstream(folder / "calib.txt")
      << "cam0=[" << c.fx << " 0 " << c.cx << "; 0 " << c.fy << " " << c.cy << "; 0 0 1]\n"
      << "cam1=[" << c.fx << " 0 " << c.cx << "; 0 " << c.fy << " " << c.cy << "; 0 0 1]\n"
      << "doffs=0\nbaseline=" << stereo.baseline * 1000.0 << "\nwidth=" << c.width
      << "\nheight=" << c.height << "\nndisp=128\n";
  const sim::Scene scene = sim::makeRoomScene();
  const SimulatedWorld world = makeSimulatedWorld("room", 6);
  for (int k = 0; k < 5; ++k) {
    const Eigen::Isometry3d T_world_camera =
        world.T_map_base[k] * stereo.T_base_link * sim::opticalFrameInBody();
    const std::string id = "_00" + std::to_string(k);
    writePfm(folder / ("disp0" + id + ".pfm"),
             sim::renderDisparity(scene, c, stereo.baseline, T_world_camera, 6.0));
    std::ofstream(folder / ("pose0" + id + ".txt"))
        << std::setprecision(12) << T_world_camera.matrix() << "\n";
  }
  std::ofstream(folder / "disp0_005.pfm") << "Pf\n160 120\n-1.0\n";  // no data: unreadable
  const RunResult result = map("--middlebury-folder " + quoted(folder), "midd");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("disparity: 5 integrated, 1 skipped"), std::string::npos) << result.out;
  expectOnSurfaces(checkVoxels(dir_ / "midd" / "midd.bt", scene, 2.0 * kResolution), 1000, 0.8);
}

// A CARMEN log written here from simulated scans (no-returns as 81.83 m, as the logs store them).
std::vector<sim::LaserScan> writeCarmenLog(const fs::path& path, const sim::Scene& scene,
                                           std::vector<Eigen::Isometry3d>* poses) {
  const SimulatedWorld world = makeSimulatedWorld("room", 5);
  sim::LaserScanner scanner;  // 361 beams over 180 degrees, CARMEN's layout
  std::ofstream log(path);
  log << "# CARMEN log written by the test\nPARAM robot_front_laser_max 30.0 nohost 0\n";
  std::vector<sim::LaserScan> scans;
  for (int k = 0; k < 5; ++k) {
    const Eigen::Isometry3d T_world_laser =
        world.T_map_base[k] * Eigen::Translation3d(0.0, 0.0, 0.3);
    poses->push_back(T_world_laser);
    scans.push_back(sim::renderScan(scene, scanner, T_world_laser, k));
    const Eigen::Vector3d x = T_world_laser.translation();
    const double theta = std::atan2(T_world_laser.linear()(1, 0), T_world_laser.linear()(0, 0));
    log << "FLASER " << scans.back().ranges.size();
    for (float range : scans.back().ranges) log << " " << (std::isfinite(range) ? range : 81.83f);
    log << std::setprecision(10) << " " << x.x() << " " << x.y() << " " << theta << " " << x.x()
        << " " << x.y() << " " << theta << " " << 100.0 + k << " testhost " << 100.0 + k << "\n";
  }
  return scans;
}

TEST_F(InputKindsTest, CarmenLogMapsTheWallsAndWritesASingleScanInItsSensorFrame) {
  const sim::Scene scene = sim::makeRoomScene();
  std::vector<Eigen::Isometry3d> poses;
  const std::vector<sim::LaserScan> scans = writeCarmenLog(dir_ / "room.log", scene, &poses);
  const RunResult result =
      map("--carmen " + quoted(dir_ / "room.log"), "carmen", "--single-scan 2");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("laser: 5 integrated, 0 skipped"), std::string::npos) << result.out;
  const CellCheck cells =
      checkLaserCells(dir_ / "carmen" / "carmen.npy", dir_ / "carmen" / "carmen.yaml", scene, {0.3},
                      2.0 * kResolution);
  EXPECT_GT(cells.occupied, 200u);
  EXPECT_GE(static_cast<double>(cells.occupied_near_surface), 0.95 * cells.occupied);
  EXPECT_LE(static_cast<double>(cells.free_inside_solid), 0.005 * cells.free);

  // The single scan: 60 m x 30 m of 5 cm cells, the sensor at the middle of the lower long edge
  // facing +y, so beam angle a points along a + pi/2 in the grid.
  for (const char* extension : {".npy", ".pgm", ".yaml", ".png"}) {
    EXPECT_TRUE(fs::is_regular_file(dir_ / "carmen" / (std::string("carmen_scan") + extension)));
  }
  const Npy grid = readNpy(dir_ / "carmen" / "carmen_scan.npy");
  ASSERT_EQ(grid.cols, 1200);
  ASSERT_EQ(grid.rows, 600);
  const auto cellAt = [&](double x, double y) {
    const int column = static_cast<int>(std::floor(x / kResolution)) + grid.cols / 2;
    const int row = static_cast<int>(std::floor(y / kResolution));
    return grid.values[static_cast<std::size_t>(row) * grid.cols + column];
  };
  const sim::LaserScan& scan = scans[2];
  int hits = 0, occupied_at_hit = 0, free_half_way = 0, unknown_behind = 0;
  for (std::size_t beam = 0; beam < scan.ranges.size(); ++beam) {
    const double range = scan.ranges[beam];
    if (!std::isfinite(range)) continue;
    const double angle = scan.angle(static_cast<int>(beam)) + M_PI / 2;
    const Eigen::Vector2d direction(std::cos(angle), std::sin(angle));
    ++hits;
    float best = -1e9f;  // the hit's cell or a neighbour along the beam
    for (double offset : {-kResolution, 0.0, kResolution}) {
      const Eigen::Vector2d p = (range + offset) * direction;
      const float value = cellAt(p.x(), p.y());
      if (!std::isnan(value)) best = std::max(best, value);
    }
    if (best > 0.0f) ++occupied_at_hit;
    const Eigen::Vector2d half = 0.5 * range * direction;
    if (cellAt(half.x(), half.y()) < 0.0f) ++free_half_way;
    const Eigen::Vector2d behind = (range + 0.5) * direction;
    if (std::isnan(cellAt(behind.x(), behind.y()))) ++unknown_behind;
  }
  ASSERT_GT(hits, 300);
  EXPECT_GE(occupied_at_hit, 0.95 * hits);
  EXPECT_GE(free_half_way, 0.95 * hits);
  EXPECT_GE(unknown_behind, 0.9 * hits);
  EXPECT_NE(result.out.find("in its sensor frame: 1200 x 600 cells"), std::string::npos)
      << result.out;
}

TEST_F(InputKindsTest, BadInputArgumentsExitWithTwo) {
  const std::string config =
      "--config " + quoted(dir_ / "mapper.yaml") + " --output-dir " + quoted(dir_ / "usage");
  const struct {
    std::string arguments;
    std::string message;
  } cases[] = {
      {config, "missing input"},
      {config + " --depth-folder /nonexistent", "no such folder: /nonexistent"},
      {config + " --carmen /nonexistent.log", "no such file: /nonexistent.log"},
      {config + " --depth-folder " + quoted(dir_), "depth folder"},
      {config + " --middlebury-folder " + quoted(dir_ / "usage_none"), "no such folder"},
      {config + " --carmen " + quoted(dir_ / "mapper.yaml"), "no FLASER line"},
      {config + " --carmen " + quoted(dir_ / "mapper.yaml") + " --scan-topic /scan_front",
       "topic options need a --bag"},
      {config + " --bag " + quoted(dir_ / "room.bag") + " --depth-topic /scan_front",
       "no sensor_msgs/Image topic '/scan_front'"},
      {config + " --bag " + quoted(dir_ / "room.bag") + " --set depth/sigma=-1", "depth/sigma"},
      {config + " --bag " + quoted(dir_ / "room.bag") + " --set stereo/method=magic",
       "stereo/method"},
      {config + " --bag " + quoted(dir_ / "room.bag") + " --set laser/method=magic",
       "laser/method"},
  };
  for (const auto& test_case : cases) {
    const RunResult result = runTool(OFFLINE_MAPPER_PATH, test_case.arguments, dir_);
    EXPECT_EQ(result.exit_code, 2) << test_case.arguments << "\n" << result.err;
    EXPECT_NE(result.err.find(test_case.message), std::string::npos) << test_case.arguments << "\n"
                                                                     << result.err;
  }
  // --single-scan beyond the scans read: the map is written, then exit 2.
  const RunResult beyond = map("--bag " + quoted(dir_ / "room.bag") + " --scan-topic /scan_front",
                               "beyond", "--single-scan 1000");
  EXPECT_EQ(beyond.exit_code, 2);
  EXPECT_NE(beyond.err.find("--single-scan 1000: the inputs hold " + std::to_string(kFrames) +
                            " laser scans"),
            std::string::npos)
      << beyond.err;
}

struct DisparityCollector : FrameConsumer {
  void onPointCloud(const PointCloudFrame&) override {}
  void onDepthImage(const DepthImageFrame&) override {}
  void onDisparityImage(const DisparityFrame& frame) override { frames.push_back(frame); }
  void onLaserScan(const LaserScanFrame&) override {}
  void onUnreadable(const FrameHeader&, const std::string& why) override { errors.push_back(why); }
  std::vector<DisparityFrame> frames;
  std::vector<std::string> errors;
};

// A DisparityImage without camera_info (as some recordings have): f and T from the message, the
// principal point at the image centre; values outside [min, max] disparity are no match.
TEST(RosbagReaderDisparity, WithoutCameraInfoUsesTheImageCentre) {
  ros::Time::init();
  const fs::path dir = makeTempDir();
  StereoCamera camera;
  camera.fx = 200.0;
  camera.baseline = 0.25;
  const std::vector<float> values = {0.0f, 10.0f, 20.0f, 300.0f, 40.0f, 50.0f};  // 3 x 2
  {
    rosbag::Bag bag((dir / "d.bag").string(), rosbag::bagmode::Write);
    const ros::Time stamp(5.0);
    bag.write("/stereo/disparity", stamp,
              disparityMessage(values, 3, 2, camera, 1.0, 256.0, "cam", stamp));
    bag.close();
  }
  RosbagReader reader({(dir / "d.bag").string()}, RosbagTopics());
  EXPECT_EQ(reader.disparityTopicsWithoutCameraInfo(),
            std::vector<std::string>{"/stereo/disparity"});
  EXPECT_NE(reader.description().find("principal point at the image centre"), std::string::npos);
  DisparityCollector collector;
  reader.read(&collector, nullptr);
  ASSERT_EQ(collector.frames.size(), 1u);
  const DisparityFrame& frame = collector.frames[0];
  EXPECT_DOUBLE_EQ(frame.camera.cx, 1.0);
  EXPECT_DOUBLE_EQ(frame.camera.cy, 0.5);
  EXPECT_DOUBLE_EQ(frame.camera.fx, 200.0);
  EXPECT_DOUBLE_EQ(frame.camera.baseline, 0.25);
  EXPECT_TRUE(std::isnan(frame.disparity[0]));  // 0 < min_disparity: no match
  EXPECT_FLOAT_EQ(frame.disparity[1], 10.0f);
  EXPECT_TRUE(std::isnan(frame.disparity[3]));  // 300 > max_disparity
  EXPECT_FLOAT_EQ(frame.disparity[5], 50.0f);
  EXPECT_EQ(frame.header.kind, "disparity");
  fs::remove_all(dir);
}

TEST(SimulateRecordingSensors, WritesTheChosenSensorsAndRejectsUnknownOnes) {
  const fs::path dir = makeTempDir();
  const RunResult good = runTool(SIMULATE_RECORDING_PATH,
                                 "--scene corridor --frames 2 --sensors scan,disparity "
                                 "--disparity-patches 0.5 --output " +
                                     quoted(dir / "c.bag"),
                                 dir);
  ASSERT_EQ(good.exit_code, 0) << good.err;
  rosbag::Bag bag((dir / "c.bag").string(), rosbag::bagmode::Read);
  rosbag::View view(bag);
  std::map<std::string, std::string> types;
  std::map<std::string, int> counts;
  for (const rosbag::MessageInstance& message : view) {
    types[message.getTopic()] = message.getDataType();
    ++counts[message.getTopic()];
  }
  bag.close();
  EXPECT_EQ(types["/scan_front"], "sensor_msgs/LaserScan");
  EXPECT_EQ(types["/scan_rear"], "sensor_msgs/LaserScan");
  EXPECT_EQ(types["/stereo/disparity"], "stereo_msgs/DisparityImage");
  EXPECT_EQ(types["/stereo/left/camera_info"], "sensor_msgs/CameraInfo");
  EXPECT_EQ(counts["/stereo/disparity"], 2);
  EXPECT_EQ(types.count("/cloud_in"), 0u);
  EXPECT_EQ(types.count("/camera/depth/image"), 0u);
  for (const std::string& sensors : {std::string("lidar"), std::string("scan,scan")}) {
    const RunResult bad =
        runTool(SIMULATE_RECORDING_PATH,
                "--sensors " + sensors + " --output " + quoted(dir / "x.bag"), dir);
    EXPECT_EQ(bad.exit_code, 2) << sensors;
    EXPECT_NE(bad.err.find("--sensors"), std::string::npos) << bad.err;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace occupancy_fusion
