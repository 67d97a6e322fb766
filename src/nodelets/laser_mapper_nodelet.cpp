// LaserMapper nodelet: one sensor_msgs/LaserScan subscriber and tf2 message filter per
// observation source (costmap_2d's style); every scan goes through Yguel et al.'s polar laser
// integrator into two products:
//  - the shared map's world-frame 2D layer (scanner pose in the map frame), through the mapping
//    session, by the rules offline_mapper applies (source settings, tilt, upside-down scanners,
//    duplicate stamps); the MapServer's projected_map shows it fused with the 3D map;
//  - the vehicle-frame local grid (the paper's V-grid, LocalLaserGrid: scanner poses in the
//    vehicle frame, placed by the same placeScan rule), fused every cycle from the latest scan of
//    each source and published as `local_grid` (nav_msgs/OccupancyGrid) while it has subscribers.
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

#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"
#include "occupancy_fusion/params/laser_config_reader.h"
#include "occupancy_fusion/ros/conversions.h"
#include "occupancy_fusion/ros/mapper_nodelet_base.h"

namespace occupancy_fusion {
namespace {

using ScanMessage = sensor_msgs::LaserScan;

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
  // One observation source: its subscriber, filter, and its scanner in the local grid with its
  // latest scan (the world layer's integrator is the session's).
  struct Source {
    LaserSourceConfig config;
    message_filters::Subscriber<ScanMessage> subscriber;
    std::unique_ptr<tf2_ros::MessageFilter<ScanMessage>> filter;
    // Guarded by LaserMapper::local_mutex_:
    int scanner = -1;             // in local_grid_, once a scan placed it
    std::optional<Pose2D> mount;  // the scanner in the vehicle frame
    LaserScan latest;             // in the mount's orientation
    ros::Time latest_stamp;
    std::atomic<std::size_t> integrated{0};
    std::atomic<std::size_t> dropped{0};   // no transform in time
    std::atomic<std::size_t> rejected{0};  // bad scan or pose, tilted scanner, failed lookup
  };

  void onInit() override {
    setUpMapper([this](const ParameterSource& parameters) {
      config_ = readLaserMapperConfig(parameters);
      MappingSessionConfig session;
      session.laser_sources = config_.sources;
      // The frames' source is the topic as subscribed (resolved in the nodelet's namespace), as
      // every mapper names it; the session finds a scan's source by it.
      for (LaserSourceConfig& source : session.laser_sources) {
        source.topic = getNodeHandle().resolveName(source.topic);
      }
      startSession(session);
    });
    // Before the first scan can arrive. Every scanner has its own integrator (its source's
    // settings): the grid's shared one is unused.
    local_grid_ =
        std::make_unique<LocalLaserGrid>(config_.local_grid.grid, PolarLaserIntegratorConfig());
    for (const LaserSourceConfig& source : config_.sources) subscribe(source);
    startLocalGrid();
    startDiagnostics(
        "laser mapping", {kRejected, MappingSession::kDropTiltedScanPlane},
        [this](diagnostic_updater::DiagnosticStatusWrapper& status) { fillDiagnostics(status); });
    NODELET_INFO("mapping %zu laser source(s) into map '%s' (frame '%s') and a local grid in '%s'",
                 sources_.size(), map().name().c_str(), map().frameId().c_str(),
                 config_.local_grid.frame_id.c_str());
  }

  void subscribe(const LaserSourceConfig& config) {
    sources_.push_back(std::make_unique<Source>());
    Source* source = sources_.back().get();
    source->config = config;
    source->subscriber.subscribe(getNodeHandle(), config.topic, queueSize());
    std::vector<std::string> targets = {config_.local_grid.frame_id};
    if (config_.write_world_layer) targets.push_back(placementFrame());
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

  // Whether the scan was integrated: into the world layer by the session (when
  // write_world_layer), and kept for the local grid.
  bool onScan(const ScanMessage& message, Source* source) {
    const auto start = std::chrono::steady_clock::now();
    LaserScanFrame frame;
    frame.header = frameHeaderOf(message.header, "laser", source->subscriber.getTopic());
    const std::string sensor_frame = session().sensorFrameOf(frame.header);
    Eigen::Isometry3d vehicle_T_sensor;
    try {
      frame.scan = checkedLaserScan(message);
      // Both poses first, so a failed lookup leaves both products untouched.
      vehicle_T_sensor = tf2::transformToEigen(tfBuffer().lookupTransform(
          config_.local_grid.frame_id, sensor_frame, message.header.stamp));
      if (config_.write_world_layer) {  // with reanchoring the session places it by odometry
        frame.header.T_map_sensor = tf2::transformToEigen(
            tfBuffer().lookupTransform(placementFrame(), sensor_frame, message.header.stamp));
      }
    } catch (const std::exception& error) {  // bad scan, tf2 lookup
      reject(source, kRejected, error.what());
      return false;
    }
    PlacedScan in_vehicle;
    try {
      in_vehicle = placeScan(frame.scan, vehicle_T_sensor, session().maxTiltOf(frame.header));
    } catch (const std::invalid_argument& error) {  // tilted or not finite in the vehicle frame
      reject(source, MappingSession::kDropTiltedScanPlane, error.what());
      return false;
    }
    if (config_.write_world_layer &&
        !integrateFrame(frame, "scan of source '" + source->config.name + "'")) {
      ++source->rejected;
      return false;
    }
    keepForLocalGrid(std::move(in_vehicle), message.header.stamp, source);
    ++source->integrated;
    last_scan_ms_ = millisecondsSince(start);
    return true;
  }

  void reject(Source* source, const char* reason, const char* what) {
    ++source->rejected;
    countDropped(reason);
    NODELET_ERROR_THROTTLE(5.0, "source '%s' (topic '%s'): scan dropped: %s",
                           source->config.name.c_str(), source->config.topic.c_str(), what);
  }

  // The scanners are fixed on the vehicle: the local grid (and its exact overlay) is rebuilt only
  // when a source's mount changes.
  void keepForLocalGrid(PlacedScan placed, const ros::Time& stamp, Source* source) {
    std::lock_guard<std::mutex> lock(local_mutex_);
    constexpr double kMountTolerance = 1e-6;  // m and rad
    const Pose2D& mount = placed.sensor;
    if (source->scanner < 0) {
      source->scanner = local_grid_->addScanner(mount, source->config.integrator);
    } else if (std::abs(source->mount->x - mount.x) > kMountTolerance ||
               std::abs(source->mount->y - mount.y) > kMountTolerance ||
               std::abs(source->mount->yaw - mount.yaw) > kMountTolerance) {
      local_grid_->moveScanner(source->scanner, mount);
    }
    source->mount = mount;
    source->latest = std::move(placed.scan);
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
      if (local_grid_->scannerCount() == 0) return;  // no scan yet
      std::vector<LaserScan> scans(static_cast<std::size_t>(local_grid_->scannerCount()));
      ros::Time newest;
      for (const auto& source : sources_) {
        if (source->scanner < 0) continue;
        scans[static_cast<std::size_t>(source->scanner)] = source->latest;
        newest = std::max(newest, source->latest_stamp);
      }
      toOccupancyGrid(local_grid_->fuse(scans), message.get());
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
  std::unique_ptr<LocalLaserGrid> local_grid_;  // guarded by local_mutex_
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
