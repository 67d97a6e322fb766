// Helpers shared by the rostests' test nodes: waiting, pausing the Simulator, reading published
// clouds, grids and diagnostics, checking them against a scene's analytic ground truth, running a
// tool and reading the map files it saves; the tests' temporary folders (../common/test_folder.h).
// Header-only: every test/rostest/<name>.cpp is its own executable.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>
#include <typeindex>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <diagnostic_msgs/DiagnosticStatus.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nodelet/NodeletLoad.h>
#include <nodelet/NodeletUnload.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>
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

using DiagnosticValues = std::map<std::string, std::string>;

// The value of `key` as a count; 0 when absent.
inline std::size_t countIn(const DiagnosticValues& values, const std::string& key) {
  const auto found = values.find(key);
  return found == values.end() ? 0 : std::stoul(found->second);
}

// The rostests' one observer of a running map graph: per watched topic its latest message, how
// many came and when the last one came (wall time); per diagnostic task its latest values. Tests
// that record more (histories, the images behind a map) pass a callback to watch() or
// onDiagnostics(). Every callback runs under no lock of the observer.
class MapObserver {
 public:
  explicit MapObserver(ros::NodeHandle& node_handle) : node_handle_(node_handle) {
    diagnostics_subscriber_ = node_handle_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 50,
        [this](const diagnostic_msgs::DiagnosticArray::ConstPtr& array) { onArray(*array); });
  }
  // The spinner's threads may be inside a callback while the test suite tears down: shut the
  // subscriptions down first (shutdown() waits for a running callback).
  ~MapObserver() {
    diagnostics_subscriber_.shutdown();
    for (auto& [topic, subscriber] : watched_) subscriber.shutdown();
  }
  MapObserver(const MapObserver&) = delete;
  MapObserver& operator=(const MapObserver&) = delete;

  // not_before: messages stamped earlier are ignored. A latched topic's new subscription can be
  // handed the latched message of a publisher that is already gone (an unloaded nodelet) while
  // its link is not torn down yet.
  template <class Message>
  void watch(const std::string& topic, std::uint32_t queue_size = 1,
             std::function<void(const typename Message::ConstPtr&)> also = {},
             const ros::Time& not_before = ros::Time()) {
    const ros::Subscriber subscriber = node_handle_.subscribe<Message>(
        topic, queue_size,
        [this, topic, also, not_before](const typename Message::ConstPtr& message) {
          if constexpr (ros::message_traits::HasHeader<Message>::value) {
            if (message->header.stamp < not_before) return;
          }
          {
            std::lock_guard<std::mutex> lock(mutex_);
            Latest& latest = latest_[topic];
            latest.message = message;
            latest.type = std::type_index(typeid(Message));
            ++latest.count;
            latest.arrival = ros::WallTime::now();
          }
          if (also) also(message);
        });
    std::lock_guard<std::mutex> lock(mutex_);
    watched_.emplace(topic, subscriber);
  }
  // Stops watching `topic` and forgets what came on it: a later watch() starts afresh.
  void unwatch(const std::string& topic) {
    std::vector<ros::Subscriber> stopped;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto [first, last] = watched_.equal_range(topic);
      for (auto it = first; it != last; ++it) stopped.push_back(it->second);
      watched_.erase(first, last);
    }
    // Outside the lock: shutdown() waits for a running callback, which takes it.
    for (ros::Subscriber& subscriber : stopped) subscriber.shutdown();
    std::lock_guard<std::mutex> lock(mutex_);
    latest_.erase(topic);
  }
  // The latest message on a watched topic; null before the first.
  template <class Message>
  typename Message::ConstPtr latest(const std::string& topic) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto found = latest_.find(topic);
    if (found == latest_.end() || !found->second.message) return {};
    if (found->second.type != std::type_index(typeid(Message))) {
      ADD_FAILURE() << topic << " is watched with another message type";
      return {};
    }
    return boost::static_pointer_cast<const Message>(found->second.message);
  }
  std::size_t received(const std::string& topic) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto found = latest_.find(topic);
    return found == latest_.end() ? 0 : found->second.count;
  }
  ros::WallTime arrival(const std::string& topic) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto found = latest_.find(topic);
    return found == latest_.end() ? ros::WallTime() : found->second.arrival;
  }

  // The latest values of the diagnostic task whose status name ends in `task` ("<node>: <task>");
  // empty until it reported values (diagnostic_updater's first status, "Node starting up", has
  // none).
  DiagnosticValues diagnostics(const std::string& task) const {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [name, values] : diagnostics_) {
      if (endsWith(name, task)) return values;
    }
    return {};
  }
  // When the task's latest values came (wall time); zero before.
  ros::WallTime diagnosticsArrival(const std::string& task) const {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [name, arrival] : diagnostics_arrivals_) {
      if (endsWith(name, task)) return arrival;
    }
    return {};
  }
  // The value of `key` in the task's latest values as a count; 0 when absent.
  std::size_t diagnosticCount(const std::string& task, const std::string& key) const {
    return countIn(diagnostics(task), key);
  }
  // The task's first values that came after `after` (wall time); waits up to `timeout_seconds`
  // and fails the test without them.
  DiagnosticValues diagnosticsAfter(const std::string& task, const ros::WallTime& after,
                                    double timeout_seconds = 5.0) const {
    const bool fresh = waitUntil([&] { return diagnosticsArrival(task) > after; }, timeout_seconds);
    EXPECT_TRUE(fresh) << "no diagnostics from '" << task << "'";
    return diagnostics(task);
  }
  // Waits (up to `timeout_seconds`) until `key` of `task` reads `value`; its last value.
  std::size_t waitForCount(const std::string& task, const std::string& key, std::size_t value,
                           double timeout_seconds = 5.0) const {
    waitUntil([&] { return diagnosticCount(task, key) == value; }, timeout_seconds);
    return diagnosticCount(task, key);
  }
  void onDiagnostics(std::function<void(const diagnostic_msgs::DiagnosticStatus&)> hook) {
    std::lock_guard<std::mutex> lock(mutex_);
    diagnostics_hooks_.push_back(std::move(hook));
  }

 private:
  struct Latest {
    boost::shared_ptr<const void> message;
    std::type_index type = std::type_index(typeid(void));
    std::size_t count = 0;
    ros::WallTime arrival;
  };
  static bool endsWith(const std::string& name, const std::string& task) {
    return name.size() >= task.size() &&
           name.compare(name.size() - task.size(), task.size(), task) == 0;
  }
  void onArray(const diagnostic_msgs::DiagnosticArray& array) {
    std::vector<std::function<void(const diagnostic_msgs::DiagnosticStatus&)>> hooks;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& status : array.status) {
        if (status.values.empty()) continue;
        DiagnosticValues& values = diagnostics_[status.name];
        values.clear();
        for (const auto& entry : status.values) values[entry.key] = entry.value;
        diagnostics_arrivals_[status.name] = ros::WallTime::now();
      }
      hooks = diagnostics_hooks_;
    }
    for (const auto& status : array.status) {
      for (const auto& hook : hooks) hook(status);
    }
  }

  ros::NodeHandle node_handle_;
  mutable std::mutex mutex_;
  ros::Subscriber diagnostics_subscriber_;
  std::multimap<std::string, ros::Subscriber> watched_;  // by topic, one per watch()
  std::map<std::string, Latest> latest_;
  std::map<std::string, DiagnosticValues> diagnostics_;
  std::map<std::string, ros::WallTime> diagnostics_arrivals_;
  std::vector<std::function<void(const diagnostic_msgs::DiagnosticStatus&)>> diagnostics_hooks_;
};

// A 32FC1 image of `values` (row-major, width x height).
inline sensor_msgs::Image floatImage(const std::vector<float>& values, int width, int height,
                                     const std::string& frame, const ros::Time& stamp) {
  sensor_msgs::Image image;
  image.header.frame_id = frame;
  image.header.stamp = stamp;
  image.width = width;
  image.height = height;
  image.encoding = "32FC1";
  image.step = width * sizeof(float);
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(values.data());
  image.data.assign(bytes, bytes + values.size() * sizeof(float));
  return image;
}

// A file's bytes ("" when it cannot be read).
inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Loads / unloads a nodelet in a running manager through its services, as `nodelet load` and
// `nodelet unload` do. remappings: (from, to) names for the nodelet.
inline bool loadNodelet(const std::string& name, const std::string& type,
                        const std::vector<std::pair<std::string, std::string>>& remappings = {},
                        const std::string& manager = "/manager") {
  nodelet::NodeletLoad load;
  load.request.name = name;
  load.request.type = type;
  for (const auto& [from, to] : remappings) {
    load.request.remap_source_args.push_back(from);
    load.request.remap_target_args.push_back(to);
  }
  return ros::service::call(manager + "/load_nodelet", load) && load.response.success;
}
inline bool unloadNodelet(const std::string& name, const std::string& manager = "/manager") {
  nodelet::NodeletUnload unload;
  unload.request.name = name;
  return ros::service::call(manager + "/unload_nodelet", unload) && unload.response.success;
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
