// Helpers shared by the rostests' test nodes: waiting, pausing the Simulator, reading published
// clouds, grids and diagnostics, checking them against a scene's analytic ground truth, running a
// tool and reading the map files it saves; the tests' temporary folders (../common/test_folder.h).
// Header-only: every test/rostest/<name>.cpp is its own executable.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <std_srvs/SetBool.h>
#include <Eigen/Core>

#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/sim/scenes.h"

#include "../common/test_folder.h"

namespace occupancy_fusion {

// Polls `condition` every 50 ms (wall time) until it holds or the timeout passes; its last value.
inline bool waitUntil(const std::function<bool()>& condition, double timeout_seconds) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_seconds);
  while (ros::ok() && ros::WallTime::now() < deadline) {
    if (condition()) return true;
    ros::WallDuration(0.05).sleep();
  }
  return condition();
}

// Waits until `count` (a counter the mappers report in their 1 Hz diagnostics) kept its value
// for `quiet_seconds` of wall time, so that what was in flight has been processed and reported;
// whether it did within the timeout. `*settled` gets the last value.
inline bool waitUntilSteady(const std::function<std::size_t()>& count, double quiet_seconds,
                            double timeout_seconds, std::size_t* settled) {
  std::size_t last = count();
  ros::WallTime stable_since = ros::WallTime::now();
  const bool steady = waitUntil(
      [&] {
        const std::size_t now = count();
        if (now != last) {
          last = now;
          stable_since = ros::WallTime::now();
        }
        return ros::WallTime::now() - stable_since > ros::WallDuration(quiet_seconds);
      },
      timeout_seconds);
  *settled = last;
  return steady;
}

// Stops (true) or resumes (false) the Simulator's robot and sensors through /simulator/pause.
inline bool setSimulatorPaused(bool paused) {
  std_srvs::SetBool pause;
  pause.request.data = paused;
  return ros::service::call("/simulator/pause", pause) && pause.response.success;
}

// Runs the tests while two threads serve the test node's subscriptions.
inline int runTestsWhileSpinning() {
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  return result;
}

// x, y, z of every point of a cloud of FLOAT32 coordinates (the MapServer's voxel centres).
inline std::vector<Eigen::Vector3d> cloudPoints(const sensor_msgs::PointCloud2& cloud) {
  std::vector<Eigen::Vector3d> points;
  sensor_msgs::PointCloud2ConstIterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  for (; x != x.end(); ++x, ++y, ++z) points.emplace_back(*x, *y, *z);
  return points;
}

// How many of the points lie within `tolerance` of one of the scene's surfaces.
inline std::size_t countNearSurface(const std::vector<Eigen::Vector3d>& points,
                                    const sim::Scene& scene, double tolerance) {
  std::size_t near = 0;
  for (const Eigen::Vector3d& p : points) near += scene.distanceToSurface(p) <= tolerance ? 1 : 0;
  return near;
}

// The same as a fraction of the points; 0 without points.
inline double fractionNearSurface(const std::vector<Eigen::Vector3d>& points,
                                  const sim::Scene& scene, double tolerance) {
  return points.empty()
             ? 0.0
             : static_cast<double>(countNearSurface(points, scene, tolerance)) / points.size();
}

inline Eigen::Vector2d cellCentre(const nav_msgs::OccupancyGrid& grid, int x, int y) {
  return {grid.info.origin.position.x + (x + 0.5) * grid.info.resolution,
          grid.info.origin.position.y + (y + 0.5) * grid.info.resolution};
}

// The grid's value at a point of its frame's plane; -1 (unknown) outside the grid.
inline std::int8_t cellAt(const nav_msgs::OccupancyGrid& grid, double px, double py) {
  const int x =
      static_cast<int>(std::floor((px - grid.info.origin.position.x) / grid.info.resolution));
  const int y =
      static_cast<int>(std::floor((py - grid.info.origin.position.y) / grid.info.resolution));
  if (x < 0 || y < 0 || x >= static_cast<int>(grid.info.width) ||
      y >= static_cast<int>(grid.info.height)) {
    return -1;
  }
  return grid.data[static_cast<std::size_t>(x + grid.info.width * y)];
}

// Whether the vertical segment over (x, y) from min_z to max_z, sampled every `step`, meets a
// solid.
inline bool columnHitsSolid(const sim::Scene& scene, const Eigen::Vector2d& xy, double min_z,
                            double max_z, double step) {
  for (double z = min_z; z <= max_z; z += step) {
    if (scene.isOccupied({xy.x(), xy.y(), z})) return true;
  }
  return false;
}

// Whether a /diagnostics status is the task `task` ("<node>: <task>").
inline bool isTask(const diagnostic_msgs::DiagnosticStatus& status, const std::string& task) {
  const std::string& name = status.name;
  return name.size() >= task.size() &&
         name.compare(name.size() - task.size(), task.size(), task) == 0;
}

// The value of `key` in a status; "" when it has none.
inline std::string diagnosticValue(const diagnostic_msgs::DiagnosticStatus& status,
                                   const std::string& key) {
  for (const auto& entry : status.values) {
    if (entry.key == key) return entry.value;
  }
  return "";
}

// The value of `key` in a status as a count; 0 when it has none.
inline std::size_t diagnosticCount(const diagnostic_msgs::DiagnosticStatus& status,
                                   const std::string& key) {
  for (const auto& entry : status.values) {
    if (entry.key == key) return std::stoul(entry.value);
  }
  return 0;
}

// Runs a shell command; its output (stdout and stderr) and, in exit_code, pclose's status.
inline std::string runCommand(const std::string& command, int* exit_code) {
  std::string output;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return output;
  std::array<char, 4096> buffer;
  while (fgets(buffer.data(), buffer.size(), pipe) != nullptr) output += buffer.data();
  *exit_code = pclose(pipe);
  return output;
}

// The known voxels of a saved .ot map (voxel index -> log-odds), to compare two maps voxel for
// voxel.
using VoxelDump = std::map<std::tuple<int, int, int>, float>;
inline VoxelDump knownVoxelsOf(const std::string& ot_path, double resolution) {
  VoxelMapConfig config;
  config.resolution = resolution;
  const std::unique_ptr<VoxelMap> map = readOctomapFile(ot_path, config);
  VoxelDump voxels;
  map->forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    voxels[{index.x(), index.y(), index.z()}] = log_odds;
  });
  return voxels;
}

}  // namespace occupancy_fusion
