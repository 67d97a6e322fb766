// Checks the LaserMapper's two products, fed by the Simulator's two laser scanners in the room
// scene, against the scene's analytic ground truth: the vehicle-frame local grid (`local_grid`)
// and the shared map's 2D layer (through the MapServer's projected_map). Then sends bad scans and
// checks that they are rejected and leave the map as it was, and that the mapper keeps mapping.
#include <cmath>
#include <mutex>
#include <string>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "occupancy_fusion/sim/scenes.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

struct Settings {
  int min_scans = 80;
  double scan_height = 0.3;  // m, the scanners' height above the floor
};

// Latest local grid and projected_map, and the LaserMapper's counters from /diagnostics.
// The laser layer's two products and the LaserMapper's counts, as last received.
struct State {
  nav_msgs::OccupancyGrid::ConstPtr local, projected;
  std::size_t front_integrated = 0, rear_integrated = 0, front_rejected = 0;
};

State stateOf(const MapObserver& observer) {
  State state;
  state.local = observer.latest<nav_msgs::OccupancyGrid>("local_grid");
  state.projected = observer.latest<nav_msgs::OccupancyGrid>("projected_map");
  const DiagnosticValues values = observer.diagnostics("laser mapping");
  state.front_integrated = countIn(values, "front scans integrated");
  state.rear_integrated = countIn(values, "rear scans integrated");
  state.front_rejected = countIn(values, "front scans rejected");
  return state;
}

Settings g_settings;
MapObserver* g_observer = nullptr;
tf2_ros::Buffer* g_tf = nullptr;

// Occupied cells lie within `tolerance` of a true surface in the scan plane; free cells' centres
// are free in the scene. Cells of the grid are mapped into the world by world_T_grid.
struct Agreement {
  std::size_t occupied = 0, occupied_near_surface = 0;
  std::size_t free = 0, free_correct = 0;
  std::size_t known_ahead = 0, known_behind = 0;  // known cells with grid x > 1 m, < -1 m
};

Agreement compareWithScene(const nav_msgs::OccupancyGrid& grid,
                           const Eigen::Isometry3d& world_T_grid, double tolerance) {
  const sim::Scene scene = sim::makeRoomScene();
  Agreement result;
  for (int y = 0; y < static_cast<int>(grid.info.height); ++y) {
    for (int x = 0; x < static_cast<int>(grid.info.width); ++x) {
      const std::int8_t value = grid.data[static_cast<std::size_t>(x + grid.info.width * y)];
      if (value < 0) continue;
      const Eigen::Vector2d centre = cellCentre(grid, x, y);
      result.known_ahead += centre.x() > 1.0 ? 1 : 0;
      result.known_behind += centre.x() < -1.0 ? 1 : 0;
      const Eigen::Vector3d world = world_T_grid * Eigen::Vector3d(centre.x(), centre.y(), 0.0) +
                                    Eigen::Vector3d(0.0, 0.0, g_settings.scan_height);
      if (value > 50) {
        ++result.occupied;
        result.occupied_near_surface += scene.distanceToSurface(world) <= tolerance ? 1 : 0;
      } else if (value < 50) {
        ++result.free;
        result.free_correct += scene.isOccupied(world) ? 0 : 1;
      }
    }
  }
  return result;
}

double ratio(std::size_t part, std::size_t whole) {
  return whole == 0 ? 0.0 : static_cast<double>(part) / whole;
}

// The state once the map is built and the robot stands still; later tests build on it.
State g_frozen;

// projected_map follows the scans (projected_map_rate), not the MapServer's publish_rate (1 Hz
// here): over 2 s of scans at 2 x 10 Hz, a timer at publish_rate would send at most 3.
TEST(SimLaserMapping, ProjectedMapFollowsTheScans) {
  ASSERT_TRUE(waitUntil([] { return stateOf(*g_observer).projected != nullptr; }, 60.0));
  const State before = stateOf(*g_observer);
  const std::size_t messages_before = g_observer->received("projected_map");
  ros::WallDuration(2.0).sleep();
  const State after = stateOf(*g_observer);
  const std::size_t scans = after.front_integrated + after.rear_integrated -
                            before.front_integrated - before.rear_integrated;
  const std::size_t messages = g_observer->received("projected_map") - messages_before;
  ROS_INFO("projected_map: %zu messages in 2 s, %zu scans integrated", messages, scans);
  ASSERT_GE(scans, 10u);
  EXPECT_GE(messages, 8u);
}

TEST(SimLaserMapping, BothProductsMatchGroundTruth) {
  const std::size_t min_scans = static_cast<std::size_t>(g_settings.min_scans) / 2;
  ASSERT_TRUE(waitUntil(
      [&] {
        const auto s = stateOf(*g_observer);
        return s.front_integrated >= min_scans && s.rear_integrated >= min_scans && s.local &&
               s.projected;
      },
      60.0))
      << "front " << stateOf(*g_observer).front_integrated << ", rear "
      << stateOf(*g_observer).rear_integrated << " scans integrated";
  ASSERT_TRUE(setSimulatorPaused(true));
  // Scans in flight are integrated and published (the counts kept still over two diagnostics
  // periods); then both products stay as they are (the local grid is re-fused from the same
  // latest scans).
  std::size_t settled = 0;
  ASSERT_TRUE(waitUntilSteady(
      [] {
        const auto s = stateOf(*g_observer);
        return s.front_integrated + s.rear_integrated;
      },
      2.5, 20.0, &settled));
  g_frozen = stateOf(*g_observer);

  // Local grid: in base_link, placed in the world by the robot's pose at the grid's stamp (the
  // newest scan's).
  const nav_msgs::OccupancyGrid& local = *g_frozen.local;
  EXPECT_EQ(local.header.frame_id, "base_link");
  EXPECT_NEAR(local.info.resolution, 0.05, 1e-6);
  EXPECT_EQ(local.info.width, 240u);
  EXPECT_NEAR(local.info.origin.position.x, -6.0, 1e-6);
  const Eigen::Isometry3d map_T_base = tf2::transformToEigen(
      g_tf->lookupTransform("map", "base_link", local.header.stamp, ros::Duration(2.0)));
  // A cell's half diagonal plus three range-error sigmas and the scan noise.
  const double tolerance = 0.5 * std::sqrt(2.0) * 0.05 + 3.0 * 0.05;
  const Agreement in_local = compareWithScene(local, map_T_base, tolerance);
  ROS_INFO(
      "local grid: %zu occupied, %.2f %% near a surface; %zu free, %.2f %% free; "
      "%zu known ahead, %zu behind",
      in_local.occupied, 100.0 * ratio(in_local.occupied_near_surface, in_local.occupied),
      in_local.free, 100.0 * ratio(in_local.free_correct, in_local.free), in_local.known_ahead,
      in_local.known_behind);
  EXPECT_GE(in_local.occupied, 300u);
  EXPECT_GE(ratio(in_local.occupied_near_surface, in_local.occupied), 0.95);
  EXPECT_GE(in_local.free, 5000u);
  EXPECT_GE(ratio(in_local.free_correct, in_local.free), 0.98);
  // Both scanners contribute: the front one ahead of the robot, the rear one behind it.
  EXPECT_GE(in_local.known_ahead, 2000u);
  EXPECT_GE(in_local.known_behind, 2000u);

  // Shared 2D layer, as the MapServer's fused view shows it (no 3D input here). The sensor model
  // writes no cell behind a hit's peak whose log-ratio is negligible (|L| < 0.05), so what many
  // scans add up to occupied lies within the same band as in the local grid: a cell's half
  // diagonal plus three sigmas of a surface (inside a solid, or beyond a thin wall), never in front
  // of it (the free-cell check below).
  const nav_msgs::OccupancyGrid& projected = *g_frozen.projected;
  EXPECT_EQ(projected.header.frame_id, "map");
  const double window = 0.5 * std::sqrt(2.0) * 0.05 + 3.0 * 0.05;
  const Agreement in_world = compareWithScene(projected, Eigen::Isometry3d::Identity(), window);
  ROS_INFO(
      "projected_map: %zu occupied, %.2f %% near a surface; "
      "%zu free, %.2f %% free",
      in_world.occupied, 100.0 * ratio(in_world.occupied_near_surface, in_world.occupied),
      in_world.free, 100.0 * ratio(in_world.free_correct, in_world.free));
  EXPECT_GE(in_world.occupied, 400u);
  EXPECT_GE(ratio(in_world.occupied_near_surface, in_world.occupied), 0.95);
  EXPECT_GE(in_world.free, 8000u);
  EXPECT_GE(ratio(in_world.free_correct, in_world.free), 0.98);
  // Where the inner faces of the front and back walls are known (the table, sphere, cylinder and
  // cabinet shade parts of them), they are occupied, and the cells two cells in front of them
  // free: the occupied band starts at the true surface.
  std::size_t face_known = 0, face_occupied = 0, front_known = 0, front_free = 0;
  for (double y = -2.5; y <= 2.5; y += 0.05) {
    for (const double face_x : {3.91, -3.91}) {
      const std::int8_t face = cellAt(projected, face_x, y);
      const std::int8_t front = cellAt(projected, face_x - std::copysign(0.1, face_x), y);
      face_known += face >= 0 ? 1 : 0;
      face_occupied += face == 100 ? 1 : 0;
      front_known += front >= 0 ? 1 : 0;
      front_free += front == 0 ? 1 : 0;
    }
  }
  ROS_INFO("wall faces: %zu known, %zu occupied; 0.1 m in front: %zu known, %zu free", face_known,
           face_occupied, front_known, front_free);
  EXPECT_GE(face_known, 150u);  // of 202
  EXPECT_GE(ratio(face_occupied, face_known), 0.98);
  EXPECT_GE(front_known, 150u);
  EXPECT_GE(ratio(front_free, front_known), 0.98);
  // Known places: the inner faces of the front and back walls, open floor around the circle.
  EXPECT_EQ(cellAt(projected, 3.91, 0.0), 100);
  EXPECT_EQ(cellAt(projected, -3.91, 0.0), 100);
  EXPECT_EQ(cellAt(projected, 0.0, -2.0), 0);
  EXPECT_EQ(cellAt(projected, -3.0, 0.0), 0);
  EXPECT_EQ(cellAt(projected, 3.0, 0.0), 0);
}

sensor_msgs::LaserScan validLookingScan() {
  sensor_msgs::LaserScan scan;
  scan.header.frame_id = "front_laser";
  scan.angle_min = -1.0f;
  scan.angle_max = 1.0f;
  scan.angle_increment = 0.01f;
  scan.range_min = 0.05f;
  scan.range_max = 10.0f;
  scan.ranges.assign(201, 0.5f);  // a wall 0.5 m away everywhere: would change the map
  return scan;
}

TEST(SimLaserMapping, BadScansAreRejectedAndLeaveTheMapUnchanged) {
  ASSERT_TRUE(g_frozen.projected);
  ros::NodeHandle node_handle;
  ros::Publisher bad = node_handle.advertise<sensor_msgs::LaserScan>("front_laser/scan", 5);
  ASSERT_TRUE(waitUntil([&] { return bad.getNumSubscribers() > 0; }, 5.0));
  const State before = stateOf(*g_observer);

  sensor_msgs::LaserScan zero_increment = validLookingScan();
  zero_increment.angle_increment = 0.0f;
  sensor_msgs::LaserScan wrong_count = validLookingScan();
  wrong_count.ranges.resize(150);  // the angles describe 201 beams
  for (sensor_msgs::LaserScan* scan : {&zero_increment, &wrong_count}) {
    scan->header.stamp = ros::Time::now();
    bad.publish(*scan);
    ros::WallDuration(0.2).sleep();
  }
  ASSERT_TRUE(waitUntil(
      [&] { return stateOf(*g_observer).front_rejected >= before.front_rejected + 2; }, 5.0))
      << "rejected " << stateOf(*g_observer).front_rejected - before.front_rejected;
  ros::WallDuration(1.0).sleep();  // four MapServer cycles
  const State after = stateOf(*g_observer);
  EXPECT_EQ(after.front_rejected, before.front_rejected + 2);
  EXPECT_EQ(after.front_integrated, before.front_integrated);
  // The MapServer sends projected_map only when the map changed: nothing new, or the same data.
  EXPECT_EQ(after.projected->data, g_frozen.projected->data);

  // The mapper is still running: it maps again once the robot moves.
  ASSERT_TRUE(setSimulatorPaused(false));
  EXPECT_TRUE(waitUntil(
      [&] { return stateOf(*g_observer).front_integrated >= after.front_integrated + 5; }, 10.0));
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sim_laser_mapping_test");
  ros::NodeHandle node_handle;
  ros::NodeHandle private_node_handle("~");
  occupancy_fusion::Settings& settings = occupancy_fusion::g_settings;
  private_node_handle.param("min_scans", settings.min_scans, settings.min_scans);
  private_node_handle.param("scan_height", settings.scan_height, settings.scan_height);
  tf2_ros::Buffer tf_buffer;
  tf2_ros::TransformListener tf_listener(tf_buffer);
  occupancy_fusion::g_tf = &tf_buffer;
  occupancy_fusion::MapObserver observer(node_handle);
  observer.watch<nav_msgs::OccupancyGrid>("local_grid");
  observer.watch<nav_msgs::OccupancyGrid>("projected_map");
  occupancy_fusion::g_observer = &observer;
  return occupancy_fusion::runTestsWhileSpinning();
}
