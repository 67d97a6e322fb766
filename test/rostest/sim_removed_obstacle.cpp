// Checks that every mapper clears an obstacle taken away in front of a standing robot, through
// mapping.launch: the box is mapped, then removed (~set_obstacle false); each map's
// projected_map_stamps say which frames each projected_map holds, so the frames a mapper needed
// until projected_map kept less than 5 % of the box's occupied cells are counted exactly (frames
// rendered after the removal returned). Goals: 5 frames for the cameras' mappers, 3 scans for the
// laser; the voxels in the box fall below 5 % of theirs as well.
#include <algorithm>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/SetBool.h>

#include "occupancy_fusion/IntegratedStamps.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

// obstacle/box of the launch file, m.
const Eigen::AlignedBox3d kBox(Eigen::Vector3d(1.6, -0.5, 0.0), Eigen::Vector3d(2.0, 0.3, 0.9));

// One mapping.launch (namespace) and the sensor topic whose frames count.
struct MapUnderTest {
  std::string name;
  std::string source;  // resolved input topic, as projected_map_stamps lists it
  int goal_frames = 0;
  bool has_voxels = true;

  std::mutex mutex;
  ros::Time removed;             // zero until the box is taken away
  std::size_t cells_before = 0;  // the box's occupied cells in the last grid before the removal
  std::size_t voxels_before = 0;
  // After the removal: per grid and per voxel cloud (same cycle, same stamp) the box's count;
  // per stamp list, the frames of `source` rendered after the removal.
  std::vector<std::pair<ros::Time, std::size_t>> cells, voxels;
  std::vector<std::pair<ros::Time, std::size_t>> frames;

  // Frames the map had integrated after the removal when the count of `after` first fell below
  // 5 % of `before` (-1: never), and the frames seen in all.
  int framesToClear(const std::vector<std::pair<ros::Time, std::size_t>>& after,
                    std::size_t before) const {
    for (const auto& [stamp, count] : after) {
      if (static_cast<double>(count) >= 0.05 * static_cast<double>(before)) continue;
      const int held = framesHeldAt(stamp);
      if (held > 0) return held;
    }
    return -1;
  }
  int framesHeldAt(const ros::Time& stamp) const {
    int held = 0;
    for (const auto& [list_stamp, count] : frames) held += list_stamp <= stamp ? count : 0;
    return held;
  }
};

std::vector<MapUnderTest*> g_maps;

// Occupied cells of `grid` whose centre lies inside the box's footprint (by half a cell more).
std::size_t boxCells(const nav_msgs::OccupancyGrid& grid) {
  const double margin = 0.5 * grid.info.resolution;
  std::size_t count = 0;
  for (int y = 0; y < static_cast<int>(grid.info.height); ++y) {
    for (int x = 0; x < static_cast<int>(grid.info.width); ++x) {
      if (grid.data[static_cast<std::size_t>(x + grid.info.width * y)] <= 50) continue;
      const Eigen::Vector2d centre = cellCentre(grid, x, y);
      if (centre.x() > kBox.min().x() - margin && centre.x() < kBox.max().x() + margin &&
          centre.y() > kBox.min().y() - margin && centre.y() < kBox.max().y() + margin) {
        ++count;
      }
    }
  }
  return count;
}

// Occupied voxel centres inside the box, above the floor's voxels.
std::size_t boxVoxels(const sensor_msgs::PointCloud2& cloud) {
  std::size_t count = 0;
  for (const Eigen::Vector3d& point : cloudPoints(cloud)) {
    const bool inside = (point.head<2>().array() > kBox.min().head<2>().array() - 0.05).all() &&
                        (point.head<2>().array() < kBox.max().head<2>().array() + 0.05).all();
    if (inside && point.z() > 0.1 && point.z() < kBox.max().z() + 0.05) ++count;
  }
  return count;
}

void onStamps(MapUnderTest* map, const IntegratedStamps::ConstPtr& stamps) {
  std::lock_guard<std::mutex> lock(map->mutex);
  if (map->removed.isZero()) return;
  std::size_t count = 0;
  for (std::size_t i = 0; i < stamps->sources.size(); ++i) {
    count += stamps->sources[i] == map->source && stamps->stamps[i] > map->removed ? 1 : 0;
  }
  map->frames.emplace_back(stamps->header.stamp, count);
}

void onGrid(MapUnderTest* map, const nav_msgs::OccupancyGrid::ConstPtr& grid) {
  std::lock_guard<std::mutex> lock(map->mutex);
  if (map->removed.isZero()) {
    map->cells_before = boxCells(*grid);
  } else {
    map->cells.emplace_back(grid->header.stamp, boxCells(*grid));
  }
}

void onVoxels(MapUnderTest* map, const sensor_msgs::PointCloud2::ConstPtr& cloud) {
  std::lock_guard<std::mutex> lock(map->mutex);
  if (map->removed.isZero()) {
    map->voxels_before = boxVoxels(*cloud);
  } else {
    map->voxels.emplace_back(cloud->header.stamp, boxVoxels(*cloud));
  }
}

TEST(SimRemovedObstacle, EveryMapperClearsTheBoxWithinItsGoal) {
  // Mapped first, long enough for its voxels to reach the clamping maximum (the slowest to clear).
  ASSERT_TRUE(waitUntil(
      [] {
        return std::all_of(g_maps.begin(), g_maps.end(), [](MapUnderTest* map) {
          std::lock_guard<std::mutex> lock(map->mutex);
          return map->cells_before >= 8 && (!map->has_voxels || map->voxels_before >= 20);
        });
      },
      60.0))
      << "the box never showed in every map";
  ros::WallDuration(4.0).sleep();
  std_srvs::SetBool remove;
  remove.request.data = false;
  ASSERT_TRUE(ros::service::call("/simulator/set_obstacle", remove) && remove.response.success);
  const ros::Time removed = ros::Time::now();
  for (MapUnderTest* map : g_maps) {
    std::lock_guard<std::mutex> lock(map->mutex);
    map->removed = removed;
  }
  // Frames enough for the slowest goal twice over (5 Hz cameras).
  waitUntil(
      [] {
        return std::all_of(g_maps.begin(), g_maps.end(), [](MapUnderTest* map) {
          std::lock_guard<std::mutex> lock(map->mutex);
          return !map->frames.empty() && map->framesHeldAt(map->frames.back().first) >= 12;
        });
      },
      15.0);
  for (MapUnderTest* map : g_maps) {
    std::lock_guard<std::mutex> lock(map->mutex);
    SCOPED_TRACE(map->name);
    const int cells_cleared = map->framesToClear(map->cells, map->cells_before);
    const int voxels_cleared = map->framesToClear(map->voxels, map->voxels_before);
    ROS_INFO(
        "%s: the box's projected_map cells %zu -> %zu, voxels %zu -> %zu; below 5 %% after "
        "%d and %d frames (%d seen)",
        map->name.c_str(), map->cells_before, map->cells.empty() ? 0 : map->cells.back().second,
        map->voxels_before, map->voxels.empty() ? 0 : map->voxels.back().second, cells_cleared,
        voxels_cleared, map->frames.empty() ? 0 : map->framesHeldAt(map->frames.back().first));
    EXPECT_GE(cells_cleared, 1);
    EXPECT_LE(cells_cleared, map->goal_frames) << map->cells_before << " cells before";
    if (map->has_voxels) {
      EXPECT_GE(voxels_cleared, 1);
      EXPECT_LE(voxels_cleared, map->goal_frames) << map->voxels_before << " voxels before";
    }
  }
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  using occupancy_fusion::MapUnderTest;
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sim_removed_obstacle");
  ros::NodeHandle node_handle;
  MapUnderTest depth, stereo, cloud, laser;
  depth.name = "depth", depth.source = "/camera/depth/image", depth.goal_frames = 5;
  stereo.name = "stereo", stereo.source = "/stereo/disparity", stereo.goal_frames = 5;
  cloud.name = "cloud", cloud.source = "/camera/depth/points", cloud.goal_frames = 5;
  laser.name = "laser", laser.source = "/front_laser/scan", laser.goal_frames = 3;
  laser.has_voxels = false;
  occupancy_fusion::g_maps = {&depth, &stereo, &cloud, &laser};
  std::vector<ros::Subscriber> subscribers;
  for (MapUnderTest* map : occupancy_fusion::g_maps) {
    const std::string ns = "/" + map->name + "/";
    subscribers.push_back(node_handle.subscribe<occupancy_fusion::IntegratedStamps>(
        ns + "projected_map_stamps", 100,
        boost::function<void(const occupancy_fusion::IntegratedStamps::ConstPtr&)>(
            [map](const auto& stamps) { occupancy_fusion::onStamps(map, stamps); })));
    subscribers.push_back(node_handle.subscribe<nav_msgs::OccupancyGrid>(
        ns + "projected_map", 10,
        boost::function<void(const nav_msgs::OccupancyGrid::ConstPtr&)>(
            [map](const auto& grid) { occupancy_fusion::onGrid(map, grid); })));
    subscribers.push_back(node_handle.subscribe<sensor_msgs::PointCloud2>(
        ns + "octomap_point_cloud_centers", 10,
        boost::function<void(const sensor_msgs::PointCloud2::ConstPtr&)>(
            [map](const auto& cloud) { occupancy_fusion::onVoxels(map, cloud); })));
  }
  return occupancy_fusion::runTestsWhileSpinning();
}
