// LaserMapper nodelet: one sensor_msgs/LaserScan subscriber and tf2 message filter per
// observation source (costmap_2d's style); every scan goes through Yguel et al.'s polar laser
// integrator into two products:
//  - the shared map's world-frame 2D layer (scanner pose in the map frame), which the MapServer's
//    projected_map shows fused with the 3D map;
//  - the vehicle-frame local grid (the paper's V-grid, scanner pose in the vehicle frame), fused
//    every cycle from the latest scan of each source and published as `local_grid`
//    (nav_msgs/OccupancyGrid) while it has subscribers.
// With ~publish_map it also publishes the shared map itself, for a mapper running alone.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <message_filters/subscriber.h>
#include <nav_msgs/OccupancyGrid.h>
#include <sensor_msgs/LaserScan.h>
#include <pluginlib/class_list_macros.hpp>

#include "occupancy_fusion/integrators/polar_laser_integrator.h"
#include "occupancy_fusion/params/laser_config_reader.h"
#include "occupancy_fusion/ros/mapper_nodelet_base.h"

namespace occupancy_fusion {
namespace {

using ScanMessage = sensor_msgs::LaserScan;

bool isFinite(const Eigen::Isometry3d& pose) { return pose.matrix().allFinite(); }

// Log-ratio sum (Eq. 8) of one scanner's grid into the fused grid; NaN means no information.
void addLogRatios(const LogOddsRaster& from, LogOddsRaster* into) {
  for (std::size_t i = 0; i < into->data.size(); ++i) {
    const float value = from.data[i];
    if (std::isnan(value)) continue;
    into->data[i] = std::isnan(into->data[i]) ? value : into->data[i] + value;
  }
}

// Occupancy probability in percent, p = 1 / (1 + exp(-L)); -1 where unknown.
void toOccupancyGrid(const LogOddsRaster& raster, nav_msgs::OccupancyGrid* grid) {
  grid->info.resolution = static_cast<float>(raster.resolution);
  grid->info.width = static_cast<std::uint32_t>(raster.width);
  grid->info.height = static_cast<std::uint32_t>(raster.height);
  grid->info.origin.position.x = raster.origin_cell.x() * raster.resolution;
  grid->info.origin.position.y = raster.origin_cell.y() * raster.resolution;
  grid->info.origin.orientation.w = 1.0;
  grid->data.resize(raster.data.size());
  for (std::size_t i = 0; i < raster.data.size(); ++i) {
    const float log_ratio = raster.data[i];
    grid->data[i] =
        std::isnan(log_ratio)
            ? std::int8_t{-1}
            : static_cast<std::int8_t>(std::lround(100.0 / (1.0 + std::exp(-log_ratio))));
  }
}

double millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace

class LaserMapper : public MapperNodeletBase {
 private:
  static constexpr const char* kRejected = "rejected: bad scan or pose, tilted scanner";
  // One observation source: its subscriber, filter, integrator for the world layer, and its
  // latest scan with its pose in the vehicle frame for the local grid.
  struct Source {
    LaserSourceConfig config;
    std::unique_ptr<PolarLaserIntegrator> world_integrator;
    message_filters::Subscriber<ScanMessage> subscriber;
    std::unique_ptr<tf2_ros::MessageFilter<ScanMessage>> filter;
    // Guarded by LaserMapper::local_mutex_:
    std::unique_ptr<LocalLaserGrid> local_grid;  // one scanner: this source at `mount`
    std::optional<Pose2D> mount;                 // the scanner in the vehicle frame
    LaserScan latest;                            // in the mount's orientation
    ros::Time latest_stamp;
    std::atomic<std::size_t> integrated{0};
    std::atomic<std::size_t> dropped{0};   // no transform in time
    std::atomic<std::size_t> rejected{0};  // bad scan or pose, tilted scanner, failed lookup
  };

  void onInit() override {
    setUpMapper(
        [this](const ParameterSource& parameters) { config_ = readLaserMapperConfig(parameters); });
    for (const LaserSourceConfig& source : config_.sources) subscribe(source);
    startLocalGrid();
    startDiagnostics(
        "laser mapping", {kRejected},
        [this](diagnostic_updater::DiagnosticStatusWrapper& status) { fillDiagnostics(status); });
    NODELET_INFO("mapping %zu laser source(s) into map '%s' (frame '%s') and a local grid in '%s'",
                 sources_.size(), map().name().c_str(), map().frameId().c_str(),
                 config_.local_grid.frame_id.c_str());
  }

  void subscribe(const LaserSourceConfig& config) {
    sources_.push_back(std::make_unique<Source>());
    Source* source = sources_.back().get();
    source->config = config;
    source->world_integrator = std::make_unique<PolarLaserIntegrator>(config.integrator);
    source->subscriber.subscribe(getNodeHandle(), config.topic, queueSize());
    std::vector<std::string> targets = {config_.local_grid.frame_id};
    if (config_.write_world_layer) targets.push_back(map().frameId());
    source->filter = makeTransformFilter<ScanMessage>(
        source->subscriber, targets,
        [this, source](const ScanMessage& scan) { return onScan(scan, source); },
        [this, source](const ScanMessage& scan) {
          ++source->dropped;
          NODELET_WARN_THROTTLE(5.0, "source '%s': no transform from '%s' at %.3f: scan dropped",
                                source->config.name.c_str(), scan.header.frame_id.c_str(),
                                scan.header.stamp.toSec());
        });
  }

  // The scanner's pose in `frame` as the core's planar pose; the scan mirrored when the scanner
  // is upside down in that frame (REP-103: it then sweeps clockwise).
  Pose2D planarPoseIn(const std::string& frame, const std::string& sensor_frame,
                      const ros::Time& stamp, double max_tilt, bool* upside_down) const {
    const Eigen::Isometry3d pose =
        tf2::transformToEigen(tfBuffer().lookupTransform(frame, sensor_frame, stamp));
    if (!isFinite(pose)) {
      throw std::invalid_argument("pose of '" + sensor_frame + "' in '" + frame +
                                  "' is not finite");
    }
    return planarPose(pose, max_tilt, upside_down);
  }

  // Whether the scan was integrated.
  bool onScan(const ScanMessage& message, Source* source) {
    const auto start = std::chrono::steady_clock::now();
    const std::string& sensor_frame =
        source->config.sensor_frame.empty() ? message.header.frame_id : source->config.sensor_frame;
    try {
      const LaserScan scan = checkedLaserScan(message);
      // Both poses first, so a failed lookup leaves both products untouched.
      bool upside_in_vehicle = false, upside_in_map = false;
      const Pose2D in_vehicle =
          planarPoseIn(config_.local_grid.frame_id, sensor_frame, message.header.stamp,
                       source->config.max_tilt, &upside_in_vehicle);
      std::optional<Pose2D> in_map;
      if (config_.write_world_layer) {
        in_map = planarPoseIn(map().frameId(), sensor_frame, message.header.stamp,
                              source->config.max_tilt, &upside_in_map);
      }
      if (in_map) {
        source->world_integrator->integrateIntoLayer(upside_in_map ? mirrorScan(scan) : scan,
                                                     *in_map, &map().layer());
      }
      keepForLocalGrid(upside_in_vehicle ? mirrorScan(scan) : scan, in_vehicle,
                       message.header.stamp, source);
    } catch (const std::exception& error) {  // bad scan, tf2 lookup, tilted scanner
      ++source->rejected;
      countDropped(kRejected);
      NODELET_ERROR_THROTTLE(5.0, "source '%s' (topic '%s'): scan dropped: %s",
                             source->config.name.c_str(), source->config.topic.c_str(),
                             error.what());
      return false;
    }
    ++source->integrated;
    last_scan_ms_ = millisecondsSince(start);
    return true;
  }

  // The scanners are fixed on the vehicle: the local grid (and its exact overlay) is rebuilt only
  // when a source's mount changes.
  void keepForLocalGrid(LaserScan scan, const Pose2D& mount, const ros::Time& stamp,
                        Source* source) {
    std::lock_guard<std::mutex> lock(local_mutex_);
    constexpr double kMountTolerance = 1e-6;  // m and rad
    const bool moved = !source->mount || std::abs(source->mount->x - mount.x) > kMountTolerance ||
                       std::abs(source->mount->y - mount.y) > kMountTolerance ||
                       std::abs(source->mount->yaw - mount.yaw) > kMountTolerance;
    if (moved) {
      source->local_grid =
          std::make_unique<LocalLaserGrid>(config_.local_grid.grid, source->config.integrator);
      source->local_grid->addScanner(mount);
      source->mount = mount;
    }
    source->latest = std::move(scan);
    source->latest_stamp = stamp;
  }

  void startLocalGrid() {
    local_grid_publisher_ = getNodeHandle().advertise<nav_msgs::OccupancyGrid>("local_grid", 1);
    local_grid_timer_ =
        getNodeHandle().createTimer(ros::Duration(1.0 / config_.local_grid.publish_rate),
                                    [this](const ros::TimerEvent&) { publishLocalGrid(); });
  }

  // One V-grid cycle: every source's latest scan through its own pose, log-ratios summed.
  void publishLocalGrid() {
    if (local_grid_publisher_.getNumSubscribers() == 0) return;
    const auto start = std::chrono::steady_clock::now();
    auto message = boost::make_shared<nav_msgs::OccupancyGrid>();
    {
      std::lock_guard<std::mutex> lock(local_mutex_);
      std::optional<LogOddsRaster> fused;
      ros::Time newest;
      for (const auto& source : sources_) {
        if (!source->local_grid) continue;  // no scan yet
        const LogOddsRaster& grid = source->local_grid->fuse({source->latest});
        if (!fused) {
          fused = grid;
        } else {
          addLogRatios(grid, &*fused);
        }
        newest = std::max(newest, source->latest_stamp);
      }
      if (!fused) return;
      toOccupancyGrid(*fused, message.get());
      message->header.stamp = newest;  // the vehicle pose the grid belongs to
    }
    message->header.frame_id = config_.local_grid.frame_id;
    message->info.map_load_time = message->header.stamp;
    local_grid_publisher_.publish(message);
    ++local_grid_cycles_;
    last_local_grid_ms_ = millisecondsSince(start);
  }

  void fillDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) {
    std::size_t integrated = 0, dropped = 0, rejected = 0;
    for (const auto& source : sources_) {
      integrated += source->integrated;
      dropped += source->dropped;
      rejected += source->rejected;
      status.add(source->config.name + " scans integrated", source->integrated.load());
      status.add(source->config.name + " scans without transform", source->dropped.load());
      status.add(source->config.name + " scans rejected", source->rejected.load());
    }
    status.summary(integrated > 0 ? diagnostic_msgs::DiagnosticStatus::OK
                                  : diagnostic_msgs::DiagnosticStatus::WARN,
                   integrated > 0 ? "mapping" : "no scan integrated yet");
    status.add("scans integrated", integrated);
    status.add("scans without transform", dropped);
    status.add("scans rejected", rejected);
    status.add("last scan ms", last_scan_ms_.load());
    status.add("local grid cycles", local_grid_cycles_.load());
    status.add("last local grid ms", last_local_grid_ms_.load());
  }

  LaserMapperConfig config_;
  std::vector<std::unique_ptr<Source>> sources_;

  std::mutex local_mutex_;
  ros::Publisher local_grid_publisher_;

  std::atomic<double> last_scan_ms_{0.0};
  std::atomic<std::size_t> local_grid_cycles_{0};
  std::atomic<double> last_local_grid_ms_{0.0};
  // Last, so that it is destroyed (stopped, waiting for a running cycle) before what its cycle
  // uses.
  ros::Timer local_grid_timer_;
};

}  // namespace occupancy_fusion

PLUGINLIB_EXPORT_CLASS(occupancy_fusion::LaserMapper, nodelet::Nodelet)
