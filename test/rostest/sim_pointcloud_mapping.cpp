// Checks the maps published by the MapServer, fed by the PointCloudMapper with the Simulator's
// depth camera in the room scene, against the scene's analytic ground truth; then the services.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/OccupancyGrid.h>
#include <octomap/OcTree.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Empty.h>
#include <visualization_msgs/MarkerArray.h>

#include "occupancy_fusion/BoundingBoxQuery.h"
#include "occupancy_fusion/SaveMap.h"
#include "occupancy_fusion/sim/scenes.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

using Point = std::array<float, 3>;

struct Settings {
  int min_clouds = 40;
  double resolution = 0.05;
  double min_z = 0.05;
  double max_z = 2.0;
};

// Keeps the latest message of every output and the counters from /diagnostics.
// The three map outputs the test compares, as last received, and when each arrived.
struct Snapshot {
  nav_msgs::OccupancyGrid::ConstPtr grid;
  visualization_msgs::MarkerArray::ConstPtr markers;
  sensor_msgs::PointCloud2::ConstPtr cloud;
  ros::WallTime grid_time, markers_time, cloud_time;
};

void watchOutputs(MapObserver* observer, std::atomic<bool>* saw_incremental_refresh) {
  observer->watch<nav_msgs::OccupancyGrid>("projected_map");
  observer->watch<visualization_msgs::MarkerArray>("occupied_cells_vis_array");
  observer->watch<sensor_msgs::PointCloud2>("octomap_point_cloud_centers");
  observer->onDiagnostics(
      [saw_incremental_refresh](const diagnostic_msgs::DiagnosticStatus& status) {
        if (!isTask(status, "map publishing")) return;
        const std::size_t refreshed = diagnosticCount(status, "cache blocks refreshed");
        const std::size_t blocks = diagnosticCount(status, "map blocks");
        const bool full = diagnosticValue(status, "cache full rebuild") == "True";
        // A cycle that re-read some, but not all, blocks: cost followed the change.
        if (!full && refreshed > 0 && refreshed < blocks) *saw_incremental_refresh = true;
      });
}

Snapshot snapshotOf(const MapObserver& observer) {
  Snapshot snapshot;
  snapshot.grid = observer.latest<nav_msgs::OccupancyGrid>("projected_map");
  snapshot.markers = observer.latest<visualization_msgs::MarkerArray>("occupied_cells_vis_array");
  snapshot.cloud = observer.latest<sensor_msgs::PointCloud2>("octomap_point_cloud_centers");
  snapshot.grid_time = observer.arrival("projected_map");
  snapshot.markers_time = observer.arrival("occupied_cells_vis_array");
  snapshot.cloud_time = observer.arrival("octomap_point_cloud_centers");
  return snapshot;
}

std::size_t cloudsIntegrated(const MapObserver& observer) {
  return observer.diagnosticCount("point cloud mapping", "clouds integrated");
}

Settings g_settings;
MapObserver* g_observer = nullptr;
std::atomic<bool> g_saw_incremental_refresh{false};

// Waits for a snapshot whose three outputs all arrived after `since`.
Snapshot snapshotAfter(const ros::WallTime& since, double timeout_seconds) {
  waitUntil(
      [&] {
        const auto s = snapshotOf(*g_observer);
        return s.grid && s.markers && s.cloud && s.grid_time > since && s.markers_time > since &&
               s.cloud_time > since;
      },
      timeout_seconds);
  return snapshotOf(*g_observer);
}

// Back to the cloud's own floats (exactly), so that equal voxel centres compare equal.
std::vector<Point> asFloats(const std::vector<Eigen::Vector3d>& points) {
  std::vector<Point> floats;
  for (const Eigen::Vector3d& p : points) {
    floats.push_back(
        {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
  }
  return floats;
}

std::vector<Point> markerPoints(const visualization_msgs::Marker& marker) {
  std::vector<Point> points;
  for (const auto& p : marker.points) {
    points.push_back({static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
  }
  return points;
}

// Whether the vertical segment over (x, y) within the height band meets a solid.
bool bandHitsSolid(const sim::Scene& scene, const Eigen::Vector2d& xy) {
  return columnHitsSolid(scene, xy, g_settings.min_z, g_settings.max_z,
                         0.5 * g_settings.resolution);
}

// Whether the columns over the cell's centre and its four corners all meet a solid: the cell lies
// under an obstacle, not on its outline (where a voxel is partly free and may be seen as free).
bool cellUnderSolid(const sim::Scene& scene, const Eigen::Vector2d& centre) {
  const double half = 0.5 * g_settings.resolution;
  for (const Eigen::Vector2d& offset :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(-half, -half), Eigen::Vector2d(half, -half),
        Eigen::Vector2d(-half, half), Eigen::Vector2d(half, half)}) {
    if (!bandHitsSolid(scene, centre + offset)) return false;
  }
  return true;
}

// Obstacles of the room scene whose top surface in the band (or, for the walls, whose face) the
// camera sees wherever it stands: the table (0.75 m high, seen from the camera at 1 m) and the
// walls. Over the far side of the sphere, cylinder and cabinet the camera sees free space above
// an occluded surface, which the grid rightly reports as free.
bool topSurfaceVisible(const Eigen::Vector2d& xy) {
  const bool in_table = xy.x() > 0.7 && xy.x() < 2.3 && xy.y() > 0.55 && xy.y() < 1.45;
  const bool in_walls = std::abs(xy.x()) > 3.9 || std::abs(xy.y()) > 2.9;
  return in_table || in_walls;
}

std::size_t countInBox(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& min,
                       const Eigen::Vector3d& max) {
  return std::count_if(points.begin(), points.end(), [&](const Eigen::Vector3d& v) {
    return (v.array() >= min.array()).all() && (v.array() <= max.array()).all();
  });
}

std::string readFile(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream content;
  content << file.rdbuf();
  return content.str();
}

// Skips whitespace and '#' comment lines between the header fields of a PGM file.
void skipPgmComments(std::istream& stream) {
  stream >> std::ws;
  while (stream.peek() == '#') {
    std::string comment;
    std::getline(stream, comment);
    stream >> std::ws;
  }
}

// The snapshot taken once the map is complete and frozen; the service tests build on it.
Snapshot g_final;

TEST(SimPointCloudMapping, MapMatchesGroundTruth) {
  ASSERT_TRUE(waitUntil(
      [] {
        return cloudsIntegrated(*g_observer) >= static_cast<std::size_t>(g_settings.min_clouds);
      },
      60.0))
      << "only " << cloudsIntegrated(*g_observer) << " clouds integrated";
  ASSERT_TRUE(setSimulatorPaused(true));
  // Let clouds in flight be integrated and published (the count kept still over two diagnostics
  // periods); then the map stays as it is, and the files saved below must hold exactly it.
  std::size_t settled = 0;
  ASSERT_TRUE(waitUntilSteady([] { return cloudsIntegrated(*g_observer); }, 2.5, 20.0, &settled));
  g_final = snapshotOf(*g_observer);
  ASSERT_TRUE(g_final.grid && g_final.markers && g_final.cloud);

  const sim::Scene scene = sim::makeRoomScene();
  const double voxel_diagonal = std::sqrt(3.0) * g_settings.resolution;

  // Occupied voxel centres lie on the scene's surfaces.
  const std::vector<Eigen::Vector3d> centres = cloudPoints(*g_final.cloud);
  EXPECT_EQ(g_final.cloud->header.frame_id, "map");
  const double near_surface = fractionNearSurface(centres, scene, voxel_diagonal);
  ROS_INFO("%zu occupied voxels, %.2f %% within a voxel diagonal of a surface", centres.size(),
           100.0 * near_surface);
  EXPECT_GE(centres.size(), 20000u);
  EXPECT_GE(near_surface, 0.95);

  // The markers show exactly those voxels, as cubes of the voxel size.
  ASSERT_EQ(g_final.markers->markers.size(), 1u);
  const visualization_msgs::Marker& cubes = g_final.markers->markers[0];
  EXPECT_EQ(cubes.type, visualization_msgs::Marker::CUBE_LIST);
  EXPECT_EQ(cubes.header.frame_id, "map");
  EXPECT_NEAR(cubes.scale.x, g_settings.resolution, 1e-9);
  EXPECT_EQ(cubes.colors.size(), cubes.points.size());
  std::vector<Point> marker_centres = markerPoints(cubes);
  std::vector<Point> sorted_centres = asFloats(centres);
  std::sort(marker_centres.begin(), marker_centres.end());
  std::sort(sorted_centres.begin(), sorted_centres.end());
  EXPECT_EQ(marker_centres, sorted_centres);

  // Projected grid: free cells are free in the scene over the band; cells over a solid in the
  // band are occupied where the camera can see that solid.
  const nav_msgs::OccupancyGrid& grid = *g_final.grid;
  EXPECT_NEAR(grid.info.resolution, g_settings.resolution, 1e-6);
  std::size_t free_cells = 0, free_correct = 0, solid_cells = 0, solid_occupied = 0;
  for (int y = 0; y < static_cast<int>(grid.info.height); ++y) {
    for (int x = 0; x < static_cast<int>(grid.info.width); ++x) {
      const std::int8_t value = grid.data[static_cast<std::size_t>(x + grid.info.width * y)];
      if (value < 0) continue;
      const Eigen::Vector2d centre = cellCentre(grid, x, y);
      if (value == 0) {
        ++free_cells;
        free_correct += bandHitsSolid(scene, centre) ? 0 : 1;
      }
      if (cellUnderSolid(scene, centre) && topSurfaceVisible(centre)) {
        ++solid_cells;
        solid_occupied += value == 100 ? 1 : 0;
      }
    }
  }
  ROS_INFO(
      "grid: %zu free cells, %.2f %% free in the scene; %zu cells over solids, %.2f %% "
      "occupied",
      free_cells, 100.0 * free_correct / free_cells, solid_cells,
      100.0 * solid_occupied / solid_cells);
  EXPECT_GE(free_cells, 5000u);
  EXPECT_GE(static_cast<double>(free_correct) / free_cells, 0.98);
  EXPECT_GE(solid_cells, 400u);
  EXPECT_GE(static_cast<double>(solid_occupied) / solid_cells, 0.98);
  // Known places: the table top (seen from above) and open floor around the robot's circle.
  EXPECT_EQ(cellAt(grid, 1.5, 1.0), 100);
  EXPECT_EQ(cellAt(grid, 0.0, -2.2), 0);
  EXPECT_EQ(cellAt(grid, -3.0, 0.0), 0);
  EXPECT_EQ(cellAt(grid, 3.0, 0.0), 0);

  // Publishing re-read only the changed blocks while the map grew.
  EXPECT_TRUE(g_saw_incremental_refresh.load());
}

TEST(SimPointCloudMapping, SaveMapWritesReadableFiles) {
  ASSERT_TRUE(g_final.grid && g_final.cloud);
  const TemporaryFolder temporary;
  const std::filesystem::path& folder = temporary.path();
  SaveMap save;
  save.request.prefix = (folder / "room").string();
  ASSERT_TRUE(ros::service::call("/map_server/save_map", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  EXPECT_EQ(save.response.files.size(), 6u);  // .ot, .bt, .pgm, .yaml, .laser.npy, .laser.yaml

  // .bt: liboctomap reads it, with as many occupied voxels as were published.
  octomap::OcTree tree(save.request.prefix + ".bt");
  EXPECT_NEAR(tree.getResolution(), g_settings.resolution, 1e-9);
  double occupied_voxels = 0.0;
  for (auto leaf = tree.begin_leafs(); leaf != tree.end_leafs(); ++leaf) {
    if (tree.isNodeOccupied(*leaf))
      occupied_voxels += std::pow(leaf.getSize() / tree.getResolution(), 3);
  }
  EXPECT_NEAR(occupied_voxels, static_cast<double>(cloudPoints(*g_final.cloud).size()), 0.5);

  // .pgm: map_server's encoding of the published grid, top row = highest y.
  const nav_msgs::OccupancyGrid& grid = *g_final.grid;
  std::istringstream pgm(readFile(save.request.prefix + ".pgm"));
  std::string magic;
  int width = 0, height = 0, max_value = 0;
  pgm >> magic;
  skipPgmComments(pgm);
  pgm >> width;
  skipPgmComments(pgm);
  pgm >> height;
  skipPgmComments(pgm);
  pgm >> max_value;
  pgm.get();  // the single whitespace before the pixels
  ASSERT_EQ(magic, "P5");
  ASSERT_EQ(width, static_cast<int>(grid.info.width));
  ASSERT_EQ(height, static_cast<int>(grid.info.height));
  ASSERT_EQ(max_value, 255);
  std::vector<char> pixels(static_cast<std::size_t>(width) * height);
  pgm.read(pixels.data(), static_cast<std::streamsize>(pixels.size()));
  ASSERT_EQ(pgm.gcount(), static_cast<std::streamsize>(pixels.size()));
  std::size_t mismatches = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const std::int8_t cell = grid.data[static_cast<std::size_t>(x + width * y)];
      const int expected = cell == 100 ? 0 : (cell == 0 ? 254 : 205);
      const auto pixel = static_cast<unsigned char>(
          pixels[static_cast<std::size_t>(x + width * (height - 1 - y))]);
      mismatches += pixel == expected ? 0 : 1;
    }
  }
  EXPECT_EQ(mismatches, 0u);

  // .yaml: names the image and the grid's geometry.
  const std::string yaml = readFile(save.request.prefix + ".yaml");
  EXPECT_NE(yaml.find("image: room.pgm"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("resolution: 0.05"), std::string::npos) << yaml;
}

TEST(SimPointCloudMapping, ClearBoxEmptiesTheBox) {
  ASSERT_TRUE(g_final.cloud);
  const std::vector<Eigen::Vector3d> before = cloudPoints(*g_final.cloud);
  // Around the table, floor under it included.
  BoundingBoxQuery clear;
  clear.request.min.x = 0.6;
  clear.request.min.y = 0.45;
  clear.request.min.z = -0.1;
  clear.request.max.x = 2.4;
  clear.request.max.y = 1.55;
  clear.request.max.z = 1.0;
  const Eigen::Vector3d min(0.6, 0.45, -0.1), max(2.4, 1.55, 1.0);
  const std::size_t inside_before = countInBox(before, min, max);
  ASSERT_GT(inside_before, 200u);
  const ros::WallTime call_time = ros::WallTime::now();
  ASSERT_TRUE(ros::service::call("/map_server/clear_bbx", clear));
  const Snapshot after = snapshotAfter(call_time, 5.0);
  ASSERT_GT(after.cloud_time, call_time);
  const std::vector<Eigen::Vector3d> remaining = cloudPoints(*after.cloud);
  EXPECT_EQ(countInBox(remaining, min, max), 0u);
  EXPECT_EQ(remaining.size(), before.size() - inside_before);
  // Cleared voxels become free (octomap_server's semantics), so the table cell turns free.
  EXPECT_EQ(cellAt(*after.grid, 1.5, 1.0), 0);
  g_final = after;
}

TEST(SimPointCloudMapping, ResetEmptiesTheMap) {
  const ros::WallTime call_time = ros::WallTime::now();
  std_srvs::Empty reset;
  ASSERT_TRUE(ros::service::call("/map_server/reset", reset));
  const Snapshot after = snapshotAfter(call_time, 5.0);
  ASSERT_GT(after.cloud_time, call_time);
  EXPECT_EQ(after.cloud->width * after.cloud->height, 0u);
  ASSERT_EQ(after.markers->markers.size(), 1u);
  EXPECT_EQ(after.markers->markers[0].action, visualization_msgs::Marker::DELETE);
  EXPECT_TRUE(std::all_of(after.grid->data.begin(), after.grid->data.end(),
                          [](std::int8_t v) { return v == -1; }));
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sim_pointcloud_mapping_test");
  ros::NodeHandle node_handle;
  ros::NodeHandle private_node_handle("~");
  occupancy_fusion::Settings& settings = occupancy_fusion::g_settings;
  private_node_handle.param("min_clouds", settings.min_clouds, settings.min_clouds);
  private_node_handle.param("resolution", settings.resolution, settings.resolution);
  private_node_handle.param("occupancy_min_z", settings.min_z, settings.min_z);
  private_node_handle.param("occupancy_max_z", settings.max_z, settings.max_z);
  occupancy_fusion::MapObserver observer(node_handle);
  occupancy_fusion::watchOutputs(&observer, &occupancy_fusion::g_saw_incremental_refresh);
  occupancy_fusion::g_observer = &observer;
  return occupancy_fusion::runTestsWhileSpinning();
}
