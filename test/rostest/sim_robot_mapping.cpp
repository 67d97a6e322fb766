// Checks mapping.launch with all four mappers in one manager on the Simulator: the fused map
// (the MapServer's occupied voxel centres and projected_map) against the room scene's ground
// truth, each mapper's share of it, and each mapper's diagnostics (the keys every mapper reports
// alike, see FrameStatistics) against the frames this node saw on the same topics, and what the
// MapServer says each projected_map holds (projected_map_stamps) against the frames sent.
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <stereo_msgs/DisparityImage.h>

#include "occupancy_fusion/IntegratedStamps.h"
#include "occupancy_fusion/sim/scenes.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

struct Settings {
  int min_images = 25;
  int min_scans = 100;
  double rate_scale = 1.0;  // the simulator's sensor rates, as a fraction of the nominal ones
};
Settings g_settings;

// The diagnostics task of each mapper, the topics it reads and their nominal total rate.
struct MapperUnderTest {
  std::string task;
  std::vector<std::string> topics;
  double rate_hz;
};
const std::vector<MapperUnderTest> kMappers = {
    {"depth_mapper: depth mapping", {"camera/depth/image"}, 5.0},
    {"disparity_mapper: disparity mapping", {"stereo/disparity"}, 5.0},
    {"laser_mapper: laser mapping", {"front_laser/scan", "rear_laser/scan"}, 20.0},
    {"point_cloud_mapper: point cloud mapping", {"camera/depth/points"}, 5.0},
};

// Every key of a mapper's latest diagnostics status, by task.
using Values = DiagnosticValues;

// The stamps of every frame the sensors sent, by resolved topic, and every projected_map_stamps
// message (what each projected_map held).
struct StampLog {
  std::mutex mutex;
  std::map<std::string, std::vector<ros::Time>> sent;
  std::vector<IntegratedStamps::ConstPtr> published;

  template <class Message>
  std::function<void(const typename Message::ConstPtr&)> recorder(const std::string& topic) {
    return [this, topic](const typename Message::ConstPtr& message) {
      const std::lock_guard<std::mutex> lock(mutex);
      sent["/" + topic].push_back(message->header.stamp);
    };
  }
};
StampLog g_stamps;

// The sensors' topics (the frames the simulator sent, as a second subscriber sees them) and the
// map's outputs.
void watchRobot(MapObserver* observer) {
  const auto watch_sensor = [&](auto message_type, const std::string& topic) {
    using Message = decltype(message_type);
    observer->watch<Message>(topic, 100, g_stamps.recorder<Message>(topic));
  };
  watch_sensor(sensor_msgs::Image(), "camera/depth/image");
  watch_sensor(stereo_msgs::DisparityImage(), "stereo/disparity");
  watch_sensor(sensor_msgs::LaserScan(), "front_laser/scan");
  watch_sensor(sensor_msgs::LaserScan(), "rear_laser/scan");
  watch_sensor(sensor_msgs::PointCloud2(), "camera/depth/points");
  observer->watch<sensor_msgs::PointCloud2>("octomap_point_cloud_centers");
  observer->watch<nav_msgs::OccupancyGrid>("projected_map");
  observer->watch<IntegratedStamps>("projected_map_stamps", 100,
                                    [](const IntegratedStamps::ConstPtr& message) {
                                      const std::lock_guard<std::mutex> lock(g_stamps.mutex);
                                      g_stamps.published.push_back(message);
                                    });
}

// projected_map_stamps: each projected_map lists the frames integrated since the one before it.
// Every listed frame is one a sensor sent (its stamp within the microsecond the frames' double
// seconds keep), none is listed twice, a topic's frames come in order, the last list is the last
// grid's, and after the sensors stopped and the mappers settled the lists hold (nearly) every
// frame sent since this node subscribed. Returns the frames listed per topic.
std::map<std::string, std::size_t> expectListsOfWhatTheGridsHold(
    const nav_msgs::OccupancyGrid& last_grid) {
  const std::lock_guard<std::mutex> lock(g_stamps.mutex);
  std::map<std::string, std::size_t> listed;
  EXPECT_FALSE(g_stamps.published.empty());
  if (g_stamps.published.empty()) return listed;
  const auto sentFrameAt = [](const std::vector<ros::Time>& sent, const ros::Time& stamp) {
    return std::any_of(sent.begin(), sent.end(), [&](const ros::Time& frame) {
      return std::abs((frame - stamp).toSec()) <= 1e-6;
    });
  };
  std::map<std::string, ros::Time> previous;
  for (const IntegratedStamps::ConstPtr& message : g_stamps.published) {
    EXPECT_EQ(message->sources.size(), message->stamps.size());
    for (std::size_t i = 0; i < std::min(message->sources.size(), message->stamps.size()); ++i) {
      const std::string& source = message->sources[i];
      const ros::Time& stamp = message->stamps[i];
      if (g_stamps.sent.count(source) == 0) {
        ADD_FAILURE() << "not a sensor topic: " << source;
        continue;
      }
      const std::vector<ros::Time>& sent = g_stamps.sent[source];
      // Frames sent before this node's subscription connected were not seen here.
      if (stamp + ros::Duration(1e-6) < *std::min_element(sent.begin(), sent.end())) continue;
      EXPECT_TRUE(sentFrameAt(sent, stamp)) << source << " " << stamp;
      EXPECT_GT(stamp, previous[source]) << source << ": listed twice or out of order";
      previous[source] = stamp;
      ++listed[source];
    }
  }
  EXPECT_EQ(g_stamps.published.back()->header.stamp, last_grid.header.stamp)
      << "the last list is not the last grid's";
  for (const auto& [topic, sent] : g_stamps.sent) {
    EXPECT_LE(listed[topic], sent.size()) << topic;
    // A frame may have been dropped (tf), and the first of them came before the lists did.
    EXPECT_GE(double(listed[topic]), 0.9 * double(sent.size()) - 3.0) << topic;
  }
  return listed;
}

double number(const Values& values, const std::string& key) {
  const auto found = values.find(key);
  if (found == values.end()) {
    ADD_FAILURE() << "diagnostics key '" << key << "' missing";
    return std::nan("");
  }
  return std::stod(found->second);
}

std::size_t count(const Values& values, const std::string& key) {
  return static_cast<std::size_t>(number(values, key));
}

// Keys every mapper reports, whatever its sensor.
const std::vector<std::string> kUniformKeys = {"frames received",
                                               "input rate (Hz)",
                                               "frames integrated",
                                               "frames waiting",
                                               "frames dropped",
                                               "tf failures",
                                               "integration ms (last)",
                                               "integration ms (mean)",
                                               "integration ms (max)",
                                               "frames dropped (tf: no transform while queued)",
                                               "frames dropped (tf: lookup failed)"};

class SimRobotMapping : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ros::NodeHandle node_handle;
    observer_ = new MapObserver(node_handle);
    watchRobot(observer_);
  }
  static void TearDownTestSuite() { delete observer_; }
  static MapObserver* observer_;
};
MapObserver* SimRobotMapping::observer_ = nullptr;

// The frames each mapper received and this node saw, taken while the simulator is paused: the
// mappers may have subscribed seconds before this node (a loaded machine starts the test node
// late), so the counts are compared from this baseline on.
struct FrameCounts {
  std::map<std::string, std::size_t> received, sent;
};

FrameCounts pausedFrameCounts(MapObserver& observer) {
  FrameCounts counts;
  EXPECT_TRUE(waitUntil(
      [&] {
        for (const MapperUnderTest& mapper : kMappers) {
          if (!observer.diagnostics(mapper.task).count("frames received")) return false;
          for (const std::string& topic : mapper.topics) {
            if (observer.received(topic) == 0) return false;
          }
        }
        return true;
      },
      60.0));
  EXPECT_TRUE(setSimulatorPaused(true));
  const auto sum = [&] {
    std::size_t total = 0;
    for (const MapperUnderTest& mapper : kMappers) {
      total += count(observer.diagnostics(mapper.task), "frames received");
      for (const std::string& topic : mapper.topics) total += observer.received(topic);
    }
    return total;
  };
  std::size_t settled = 0;
  EXPECT_TRUE(waitUntilSteady(sum, 2.5, 20.0, &settled));
  for (const MapperUnderTest& mapper : kMappers) {
    counts.received[mapper.task] = count(observer.diagnostics(mapper.task), "frames received");
    for (const std::string& topic : mapper.topics) {
      counts.sent[mapper.task] += observer.received(topic);
    }
  }
  EXPECT_TRUE(setSimulatorPaused(false));
  return counts;
}

TEST_F(SimRobotMapping, FusedMapAndDiagnosticsOfAllFourMappers) {
  MapObserver& observer = *observer_;
  const FrameCounts baseline = pausedFrameCounts(observer);
  // Run until every camera sent min_images and the scanners min_scans.
  ASSERT_TRUE(waitUntil(
      [&] {
        return observer.received("camera/depth/image") >= std::size_t(g_settings.min_images) &&
               observer.received("stereo/disparity") >= std::size_t(g_settings.min_images) &&
               observer.received("front_laser/scan") + observer.received("rear_laser/scan") >=
                   std::size_t(g_settings.min_scans);
      },
      60.0));
  // The input rates, measured by the mappers while the sensors run (one-second windows).
  std::map<std::string, double> rates;
  for (const MapperUnderTest& mapper : kMappers) {
    rates[mapper.task] = number(observer.diagnostics(mapper.task), "input rate (Hz)");
  }
  ASSERT_TRUE(setSimulatorPaused(true));
  // Let every queued frame through (the mappers' outcome counts kept still over two diagnostics
  // periods, and no frame left waiting in a tf filter: a loaded machine can delay a frame's
  // transform past a quiet period) and the map server publish the last of them.
  const auto sum = [&](const std::string& key) {
    std::size_t total = 0;
    for (const MapperUnderTest& mapper : kMappers) {
      total += count(observer.diagnostics(mapper.task), key);
    }
    return total;
  };
  ASSERT_TRUE(waitUntil(
      [&] {
        std::size_t settled = 0;
        const bool steady = waitUntilSteady(
            [&] { return sum("frames integrated") + sum("frames dropped"); }, 2.5, 20.0, &settled);
        return steady && sum("frames waiting") == 0;
      },
      40.0));

  for (const MapperUnderTest& mapper : kMappers) {
    SCOPED_TRACE(mapper.task);
    const Values values = observer.diagnostics(mapper.task);
    for (const std::string& key : kUniformKeys) EXPECT_EQ(values.count(key), 1u) << key;
    std::size_t sent = 0;
    for (const std::string& topic : mapper.topics) sent += observer.received(topic);
    const std::size_t received = count(values, "frames received");
    const std::size_t integrated = count(values, "frames integrated");
    // The simulator sends to both subscribers alike since the baseline (a frame or two per topic
    // may be in flight, or left behind by a full subscriber queue on a loaded machine).
    const double sent_since = double(sent - baseline.sent.at(mapper.task));
    EXPECT_NEAR(double(received - baseline.received.at(mapper.task)), sent_since,
                2.0 * mapper.topics.size() + 0.05 * sent_since);
    // Nothing is left in the tf2 filter, and every frame has an outcome.
    EXPECT_EQ(count(values, "frames waiting"), 0u);
    EXPECT_EQ(received, integrated + count(values, "frames dropped"));
    // The simulator sends tf before each frame, so nearly all are integrated.
    EXPECT_GE(double(integrated), 0.9 * double(received));
    EXPECT_LE(count(values, "tf failures"), count(values, "frames dropped"));
    const double mean_ms = number(values, "integration ms (mean)");
    EXPECT_GT(mean_ms, 0.0);
    EXPECT_LE(mean_ms, number(values, "integration ms (max)"));
    EXPECT_LE(number(values, "integration ms (last)"), number(values, "integration ms (max)"));
    EXPECT_LT(mean_ms, 2000.0);
    // The mappers count the rate over about one second: below 5 Hz one frame more or less in
    // that window is a large fraction of it (scaled-down rates only).
    const double rate_hz = mapper.rate_hz * g_settings.rate_scale;
    const double slack_hz = rate_hz < 5.0 ? 1.0 : 0.0;
    EXPECT_GT(rates[mapper.task], std::max(0.4 * rate_hz - slack_hz, 0.0));
    EXPECT_LT(rates[mapper.task], 1.6 * rate_hz + slack_hz);
  }

  // Each mapper's share of the fused map: the sensor-specific keys of its diagnostics.
  const Values depth = observer.diagnostics(kMappers[0].task);
  const Values disparity = observer.diagnostics(kMappers[1].task);
  const Values laser = observer.diagnostics(kMappers[2].task);
  const Values cloud = observer.diagnostics(kMappers[3].task);
  EXPECT_GT(count(depth, "last image voxels updated"), 1000u);
  EXPECT_GT(count(disparity, "last image voxels updated"), 1000u);
  EXPECT_GT(count(cloud, "last cloud points"), 5000u);
  EXPECT_GE(count(laser, "front scans integrated"), std::size_t(g_settings.min_scans / 3));
  EXPECT_GE(count(laser, "rear scans integrated"), std::size_t(g_settings.min_scans / 3));

  const sim::Scene scene = sim::makeRoomScene();
  // The 3D map (depth, disparity and point cloud): occupied voxel centres on the true surfaces.
  const sensor_msgs::PointCloud2::ConstPtr centres_message =
      observer.latest<sensor_msgs::PointCloud2>("octomap_point_cloud_centers");
  ASSERT_TRUE(centres_message);
  const std::vector<Eigen::Vector3d> centres = cloudPoints(*centres_message);
  const double tolerance = std::sqrt(3.0) * 0.05 + 0.1;  // a voxel diagonal and stereo error
  const double near = fractionNearSurface(centres, scene, tolerance);
  std::printf("%zu occupied voxels, %.1f %% within %.2f m of a surface\n", centres.size(),
              100.0 * near, tolerance);
  EXPECT_GE(centres.size(), 5000u);
  EXPECT_GE(near, 0.95);

  // projected_map: the 3D map's column projection fused with the laser layer; its occupied cells
  // lie on a solid's outline.
  const nav_msgs::OccupancyGrid::ConstPtr projected =
      observer.latest<nav_msgs::OccupancyGrid>("projected_map");
  ASSERT_TRUE(projected);
  std::size_t occupied = 0, on_outline = 0;
  for (std::uint32_t y = 0; y < projected->info.height; ++y) {
    for (std::uint32_t x = 0; x < projected->info.width; ++x) {
      if (projected->data[x + projected->info.width * y] != 100) continue;
      ++occupied;
      const Eigen::Vector2d centre = cellCentre(*projected, int(x), int(y));
      double nearest = INFINITY;
      for (double z = 0.05; z <= 2.0; z += 0.05) {
        nearest = std::min(nearest, scene.distanceToSurface({centre.x(), centre.y(), z}));
      }
      on_outline += nearest <= 0.1 ? 1 : 0;
    }
  }
  std::printf("projected_map: %zu occupied cells, %zu on an outline\n", occupied, on_outline);
  EXPECT_GE(occupied, 400u);
  EXPECT_GE(double(on_outline) / double(occupied), 0.95);
  // The room's walls at x = +-4 m are seen by the laser scanners (10 m range, both ways) in
  // every turn, and by the cameras only in part of it.
  EXPECT_EQ(cellAt(*projected, 3.91, 0.0), 100);
  EXPECT_EQ(cellAt(*projected, -3.91, 0.0), 100);
  const std::map<std::string, std::size_t> listed = expectListsOfWhatTheGridsHold(*projected);
  // No frame is listed that its mapper did not integrate.
  for (const MapperUnderTest& mapper : kMappers) {
    std::size_t frames = 0;
    for (const std::string& topic : mapper.topics) {
      const auto found = listed.find("/" + topic);
      frames += found == listed.end() ? 0 : found->second;
    }
    EXPECT_LE(frames, count(observer.diagnostics(mapper.task), "frames integrated")) << mapper.task;
  }
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sim_robot_mapping");
  ros::NodeHandle private_handle("~");
  private_handle.param("min_images", occupancy_fusion::g_settings.min_images,
                       occupancy_fusion::g_settings.min_images);
  private_handle.param("min_scans", occupancy_fusion::g_settings.min_scans,
                       occupancy_fusion::g_settings.min_scans);
  private_handle.param("rate_scale", occupancy_fusion::g_settings.rate_scale,
                       occupancy_fusion::g_settings.rate_scale);
  return occupancy_fusion::runTestsWhileSpinning();
}
