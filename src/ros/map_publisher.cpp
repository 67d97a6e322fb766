#include "occupancy_fusion/ros/map_publisher.h"

#include "occupancy_fusion/mapping/submap_files.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <nav_msgs/OccupancyGrid.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <visualization_msgs/MarkerArray.h>

#include "occupancy_fusion/IntegratedStamps.h"
#include "occupancy_fusion/Octomap.h"
#include "occupancy_fusion/map/octomap_conversion.h"
#include "occupancy_fusion/mapping/map_saving.h"
#include "occupancy_fusion/params/config_readers.h"
#include "occupancy_fusion/ros/conversions.h"

namespace occupancy_fusion {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Times one call into the shared map for MapLockStatistics (no statistics: times nothing).
class MapCallTimer {
 public:
  MapCallTimer(MapLockStatistics* statistics, const char* what)
      : statistics_(statistics), what_(what), start_(Clock::now()) {}
  ~MapCallTimer() {
    if (statistics_ != nullptr) statistics_->recordHold(what_, millisecondsSince(start_));
  }
  MapCallTimer(const MapCallTimer&) = delete;
  MapCallTimer& operator=(const MapCallTimer&) = delete;

 private:
  MapLockStatistics* statistics_;
  const char* what_;
  Clock::time_point start_;
};

// Rainbow from blue (low) to red (high) over the height range of the occupied voxels, so floors,
// furniture and ceilings read apart (octomap_server colours by height the same way).
std_msgs::ColorRGBA heightColor(double normalized_height) {
  const double hue = (1.0 - std::clamp(normalized_height, 0.0, 1.0)) * 240.0;  // degrees
  const double sector = hue / 60.0;
  const double fraction = sector - std::floor(sector);
  double r = 0.0, g = 0.0, b = 0.0;
  switch (static_cast<int>(sector)) {
    case 0:
      r = 1.0;
      g = fraction;
      break;
    case 1:
      r = 1.0 - fraction;
      g = 1.0;
      break;
    case 2:
      g = 1.0;
      b = fraction;
      break;
    default:
      g = 1.0 - fraction;
      b = 1.0;
      break;
  }
  std_msgs::ColorRGBA color;
  color.r = static_cast<float>(r);
  color.g = static_cast<float>(g);
  color.b = static_cast<float>(b);
  color.a = 1.0f;
  return color;
}

}  // namespace

void MapLockStatistics::recordHold(const char* what, double milliseconds) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (milliseconds <= longest_hold_ms_) return;
  longest_hold_ms_ = milliseconds;
  longest_hold_call_ = what;
}

void MapLockStatistics::recordReadWait(double milliseconds) {
  const std::lock_guard<std::mutex> lock(mutex_);
  longest_read_wait_ms_ = std::max(longest_read_wait_ms_, milliseconds);
}

double MapLockStatistics::longestHoldMs() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return longest_hold_ms_;
}

std::string MapLockStatistics::longestHoldCall() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return longest_hold_call_;
}

double MapLockStatistics::longestReadWaitMs() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return longest_read_wait_ms_;
}

void MapPublisherConfig::validate() const {
  if (!(publish_rate > 0.0) || !std::isfinite(publish_rate)) {
    throw std::invalid_argument("publish_rate must be a positive number of Hz, got " +
                                std::to_string(publish_rate));
  }
  if (!(projected_map_rate >= 0.0) || !std::isfinite(projected_map_rate)) {
    throw std::invalid_argument("projected_map_rate must be >= 0 Hz (0: at publish_rate), got " +
                                std::to_string(projected_map_rate));
  }
  if (save_prefix.empty()) throw std::invalid_argument("save_prefix must not be empty");
  grid.validate();
}

MapPublisherConfig readMapPublisherConfig(const ParameterSource& source) {
  MapPublisherConfig config;
  source.get("publish_rate", &config.publish_rate);
  source.get("projected_map_rate", &config.projected_map_rate);
  source.get("save_prefix", &config.save_prefix);
  config.grid = readFusedGridConfig(source);
  config.validate();
  return config;
}

MapPublisher::MapPublisher(const ros::NodeHandle& node_handle,
                           const ros::NodeHandle& private_node_handle, const std::string& name,
                           std::shared_ptr<SharedMap> map, const MapPublisherConfig& config)
    : name_(name),
      map_(std::move(map)),
      config_(config),
      grid_view_(config.grid),
      diagnostics_(node_handle, private_node_handle, name) {
  config_.validate();
  ros::NodeHandle topics(node_handle);
  // Latched: a late subscriber gets the last map at once instead of waiting for a change.
  grid_publisher_ = topics.advertise<nav_msgs::OccupancyGrid>("projected_map", 1, true);
  grid_stamps_publisher_ = topics.advertise<IntegratedStamps>("projected_map_stamps", 1, true);
  markers_publisher_ =
      topics.advertise<visualization_msgs::MarkerArray>("occupied_cells_vis_array", 1, true);
  cloud_publisher_ =
      topics.advertise<sensor_msgs::PointCloud2>("octomap_point_cloud_centers", 1, true);
  binary_publisher_ = topics.advertise<Octomap>("octomap_binary", 1, true);

  ros::NodeHandle services(private_node_handle);
  reset_service_ = services.advertiseService("reset", &MapPublisher::onReset, this);
  clear_box_service_ = services.advertiseService("clear_bbx", &MapPublisher::onClearBox, this);
  save_map_service_ = services.advertiseService("save_map", &MapPublisher::onSaveMap, this);

  diagnostics_.setHardwareID("map '" + map_->name() + "'");
  diagnostics_.add("map publishing", this, &MapPublisher::fillDiagnostics);
  // Ticks at publish_rate, or often enough to send a correction soon after it moved the map.
  timer_ = topics.createWallTimer(
      ros::WallDuration(std::min(1.0 / config_.publish_rate, kCorrectionCheckSeconds)),
      &MapPublisher::onTimer, this);
  grid_thread_ = std::thread(&MapPublisher::sendGridAsFramesArrive, this);
}

MapPublisher::~MapPublisher() {
  // Members go in reverse order, so diagnostics_ would be destroyed while timer_ still fires
  // onTimer, which uses it (ThreadSanitizer saw the Updater's mutex destroyed right after a
  // cycle on another thread when a MapServer was unloaded). stop() also waits for a running cycle.
  timer_.stop();
  {
    const std::lock_guard<std::mutex> lock(stop_mutex_);
    stopping_ = true;
  }
  stop_requested_.notify_all();
  map_->wakeWaiters();
  grid_thread_.join();
}

void MapPublisher::sendGridAsFramesArrive() {
  // A frame integrated wakes it; changes without a frame (corrections, clear_bbx, a reset) are
  // sent at publish_rate. After a message the next waits 1 / projected_map_rate and at least three
  // times the message's own time: projected_map takes at most a quarter of a core, however large.
  const bool follow_frames = config_.projected_map_rate > 0.0;
  const auto seconds = [](double value) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(value));
  };
  const Clock::duration period = seconds(1.0 / config_.publish_rate);
  const Clock::duration min_interval =
      follow_frames ? seconds(1.0 / config_.projected_map_rate) : period;
  std::uint64_t frames_seen = map_->integratedCount();
  Clock::time_point last_check = Clock::now();
  Clock::time_point due = last_check;  // the next message not before
  while (true) {
    // Read before stopping_: the destructor's wakeWaiters() after it then ends the wait at once.
    const std::uint64_t wake_calls = map_->wakeCalls();
    {
      const std::lock_guard<std::mutex> lock(stop_mutex_);
      if (stopping_) return;
    }
    if (follow_frames) map_->waitForIntegrated(frames_seen, last_check + period, wake_calls);
    {
      std::unique_lock<std::mutex> lock(stop_mutex_);
      const Clock::time_point until = follow_frames ? due : std::max(due, last_check + period);
      if (stop_requested_.wait_until(lock, until, [this] { return stopping_; })) return;
    }
    frames_seen = map_->integratedCount();
    const Clock::time_point start = Clock::now();
    last_check = start;
    if (!needsSending(grid_publisher_, grid_sent_)) continue;
    publishGrid(ros::Time::now());
    const Clock::time_point end = Clock::now();
    due = std::max(start + min_interval, end + 3 * (end - start));
  }
}

GridTimings MapPublisher::lastGridTimings() const {
  const std::lock_guard<std::mutex> lock(grid_timings_mutex_);
  return grid_timings_;
}

std::uint64_t MapPublisher::movesResampled() const {
  const MapReanchoring* reanchoring = map_->reanchoring();
  return reanchoring != nullptr ? reanchoring->fusion().movesResampled() : 0;
}

void MapPublisher::onTimer(const ros::WallTimerEvent& /*event*/) {
  const ros::WallTime now = ros::WallTime::now();
  // A correction is sent once the map holds it re-sampled, not up to a publish_rate period later
  // (0.5 s at the shipped 2 Hz, on top of the 0.5-0.7 s it takes on a large floor); projected_map
  // too, without waiting for the next frame.
  const std::uint64_t moves = movesResampled();
  if (moves != moves_sent_) map_->wakeWaiters();
  if (now >= next_cycle_ || moves != moves_sent_) {
    moves_sent_ = moves;
    next_cycle_ = now + ros::WallDuration(1.0 / config_.publish_rate);
    publishCycle();
  }
  // Paced by wall time: Updater::update() waits until ROS time passes its next due time, which a
  // looped bag's clock, jumping back, never reaches again.
  if (now >= next_diagnostics_) {
    diagnostics_.force_update();
    next_diagnostics_ = now + ros::WallDuration(1.0);
  }
}

MapPublisher::SentVersion MapPublisher::currentVersion() const {
  return {map_->voxels().version(), map_->layer().version()};
}

bool MapPublisher::needsSending(const ros::Publisher& publisher, const SentVersion& sent) const {
  return publisher.getNumSubscribers() > 0 && !(sent == currentVersion());
}

void MapPublisher::publishCycle() {
  const ros::Time stamp = ros::Time::now();
  {
    // A trivial read waits exactly as long as a mapper's write still holds the lock.
    const auto start = Clock::now();
    map_->voxels().version();
    lock_statistics_.recordReadWait(millisecondsSince(start));
  }
  PublishTimings& t = timings_;
  const std::uint64_t cycles = t.cycles + 1;
  t = PublishTimings();
  t.cycles = cycles;
  const bool markers = needsSending(markers_publisher_, markers_sent_);
  const bool cloud = needsSending(cloud_publisher_, cloud_sent_);
  if (markers || cloud) refreshCache();
  if (markers) publishMarkers(stamp);
  if (cloud) publishCloud(stamp);
  if (needsSending(binary_publisher_, binary_sent_)) publishBinary(stamp);
  t.occupied_voxels = cache_.occupiedCount();
  t.map_blocks = map_->voxels().blockCount();
  ROS_DEBUG_NAMED("publishing",
                  "%s: cache %.2f ms (%zu blocks%s), markers %.2f ms, cloud %.2f ms, binary %.2f "
                  "ms; %zu occupied voxels in %zu blocks",
                  name_.c_str(), t.cache_ms, t.cache_blocks_refreshed,
                  t.cache_full_rebuild ? ", full rebuild" : "", t.markers_ms, t.cloud_ms,
                  t.binary_ms, t.occupied_voxels, t.map_blocks);
}

void MapPublisher::refreshCache() {
  const auto start = Clock::now();
  OccupiedVoxelCache::RefreshStats stats;
  {
    const MapCallTimer timer(&lock_statistics_, "occupied-voxel cache refresh");
    stats = cache_.refresh(map_->voxels());
  }
  timings_.cache_ms = millisecondsSince(start);
  timings_.cache_blocks_refreshed = stats.blocks_refreshed;
  timings_.cache_full_rebuild = stats.full_rebuild;
}

void MapPublisher::publishGrid(const ros::Time& stamp) {
  const auto start = Clock::now();
  // Both read before the map: later writes are sent next time, and every frame listed is in it.
  const std::vector<SharedMap::IntegratedFrame> integrated =
      map_->integratedSince(grid_frames_listed_);
  const SentVersion version = currentVersion();
  OccupancyRaster raster;
  {
    const MapCallTimer timer(&lock_statistics_, "projected_map update");
    raster = grid_view_.update(map_->voxels(), &map_->layer());
  }
  auto grid = boost::make_shared<nav_msgs::OccupancyGrid>();
  toOccupancyGridMessage(raster, map_->frameId(), stamp, grid.get());
  if (!integrated.empty()) grid_frames_listed_ = integrated.back().number;
  if (grid_stamps_publisher_.getNumSubscribers() > 0) {
    auto stamps = boost::make_shared<IntegratedStamps>();
    stamps->header = grid->header;
    for (const SharedMap::IntegratedFrame& frame : integrated) {
      stamps->sources.push_back(frame.source);
      stamps->stamps.push_back(frame.stamp);
    }
    grid_stamps_publisher_.publish(stamps);
  }
  grid_publisher_.publish(grid);
  grid_sent_ = version;
  const std::lock_guard<std::mutex> lock(grid_timings_mutex_);
  ++grid_timings_.published;
  grid_timings_.grid_ms = millisecondsSince(start);
  grid_timings_.grid_blocks_processed = grid_view_.lastUpdateStats().map_blocks_processed;
}

void MapPublisher::publishMarkers(const ros::Time& stamp) {
  const auto start = Clock::now();
  float min_z = std::numeric_limits<float>::infinity();
  float max_z = -std::numeric_limits<float>::infinity();
  cache_.forEachCentre([&](const Eigen::Vector3f& centre) {
    min_z = std::min(min_z, centre.z());
    max_z = std::max(max_z, centre.z());
  });
  const double height_span = std::max(1e-6, static_cast<double>(max_z) - min_z);

  auto markers = boost::make_shared<visualization_msgs::MarkerArray>();
  visualization_msgs::Marker cubes;
  cubes.header.frame_id = map_->frameId();
  cubes.header.stamp = stamp;
  cubes.ns = "occupied_cells";
  cubes.id = 0;
  cubes.type = visualization_msgs::Marker::CUBE_LIST;
  cubes.pose.orientation.w = 1.0;
  cubes.scale.x = cubes.scale.y = cubes.scale.z = map_->voxels().resolution();
  cubes.color.a = 1.0f;
  cubes.points.reserve(cache_.occupiedCount());
  cubes.colors.reserve(cache_.occupiedCount());
  cache_.forEachCentre([&](const Eigen::Vector3f& centre) {
    geometry_msgs::Point point;
    point.x = centre.x();
    point.y = centre.y();
    point.z = centre.z();
    cubes.points.push_back(point);
    cubes.colors.push_back(heightColor((centre.z() - min_z) / height_span));
  });
  // An empty CUBE_LIST is removed rather than sent (rviz keeps the last one otherwise).
  cubes.action =
      cubes.points.empty() ? visualization_msgs::Marker::DELETE : visualization_msgs::Marker::ADD;
  markers->markers.push_back(std::move(cubes));
  markers_publisher_.publish(markers);
  markers_sent_ = {cache_.mapVersion(), map_->layer().version()};
  timings_.markers_ms = millisecondsSince(start);
}

void MapPublisher::publishCloud(const ros::Time& stamp) {
  const auto start = Clock::now();
  auto cloud = boost::make_shared<sensor_msgs::PointCloud2>();
  cloud->header.frame_id = map_->frameId();
  cloud->header.stamp = stamp;
  resizeXyzCloud(cache_.occupiedCount(), cloud.get());
  sensor_msgs::PointCloud2Iterator<float> x(*cloud, "x"), y(*cloud, "y"), z(*cloud, "z");
  cache_.forEachCentre([&](const Eigen::Vector3f& centre) {
    *x = centre.x();
    *y = centre.y();
    *z = centre.z();
    ++x, ++y, ++z;
  });
  cloud_publisher_.publish(cloud);
  cloud_sent_ = {cache_.mapVersion(), map_->layer().version()};
  timings_.cloud_ms = millisecondsSince(start);
}

void MapPublisher::publishBinary(const ros::Time& stamp) {
  // The message holds the whole tree, so this cost necessarily follows the map's size.
  const auto start = Clock::now();
  const SentVersion version = currentVersion();
  std::vector<VoxelMap::BlockCopy> blocks;
  {
    const MapCallTimer timer(&lock_statistics_, "octomap_binary block copy");
    blocks = map_->voxels().copyBlocks();  // the tree is built without the map's lock
  }
  const VoxelMap& voxels = map_->voxels();
  const std::unique_ptr<octomap::OcTree> tree =
      toOcTree(blocks, voxels.resolution(), voxels.model());
  std::stringstream stream;
  tree->writeBinaryData(stream);
  const std::string bytes = stream.str();
  auto message = boost::make_shared<Octomap>();
  message->header.frame_id = map_->frameId();
  message->header.stamp = stamp;
  message->binary = true;
  message->id = tree->getTreeType();
  message->resolution = tree->getResolution();
  message->data.assign(bytes.begin(), bytes.end());
  binary_publisher_.publish(message);
  binary_sent_ = version;
  timings_.binary_ms = millisecondsSince(start);
}

void MapPublisher::fillDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const PublishTimings& t = timings_;
  const VoxelMap& voxels = map_->voxels();
  const SpillStatus spill = voxels.spillStatus();
  if (spill.failures > 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   (spill.enabled ? "spill store failed (blocks dropped or unreadable): "
                                  : "no spill store, evicted blocks are dropped: ") +
                       spill.last_error);
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "publishing");
  }
  status.add("publish cycles", t.cycles);
  status.add("cache ms", t.cache_ms);
  status.add("cache blocks refreshed", t.cache_blocks_refreshed);
  status.add("cache full rebuild", t.cache_full_rebuild);
  const GridTimings grid = lastGridTimings();
  status.add("projected_map messages", grid.published);
  status.add("grid ms", grid.grid_ms);
  status.add("grid blocks processed", grid.grid_blocks_processed);
  status.add("markers ms", t.markers_ms);
  status.add("cloud ms", t.cloud_ms);
  status.add("binary ms", t.binary_ms);
  status.add("occupied voxels", t.occupied_voxels);
  status.add("map blocks", voxels.blockCount());
  status.add("known voxels", voxels.knownVoxelCount());
  status.add("memory bytes", voxels.memoryBytes());
  status.add("evicted blocks", voxels.evictedBlockCount());
  if (!spill.folder.empty()) {
    status.add("spill folder", spill.folder);
    status.add("spill store open", spill.enabled);
    status.add("spilled blocks", spill.spilled_blocks);
    status.add("blocks written to the spill store", spill.blocks_written);
    status.add("blocks paged in", spill.blocks_paged_in);
    status.add("blocks paged in, read before the write lock", spill.blocks_read_ahead);
    status.add("blocks paged in, read under the write lock", spill.blocks_read_under_lock);
    status.add("spill store failures", spill.failures);
    if (spill.checkpoints) {
      status.add("checkpoints written", spill.checkpoints_written);
      status.add("last checkpoint", spill.last_checkpoint_stamp);
      status.add("blocks changed since the last checkpoint", spill.unsaved_blocks);
      status.add("blocks resumed from the store", spill.resumed_blocks);
      status.add("resumed checkpoint", spill.resumed_stamp);
    }
  }
  status.add("layer cells", map_->layer().knownCellCount());
  const TileSpillStatus layer_spill = map_->layer().spillStatus();
  if (layer_spill.enabled) {
    status.add("layer tiles in the spill store", layer_spill.spilled_tiles);
    status.add("layer tiles written to the spill store", layer_spill.tiles_written);
    status.add("layer tiles paged in", layer_spill.tiles_paged_in);
    status.add("layer spill failures", layer_spill.failures);
    if (layer_spill.failures > 0 && spill.failures == 0) {
      status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                     "the laser layer's spill store failed (tiles kept in memory or unreadable)");
    }
  }
  if (const MapReanchoring* reanchoring = map_->reanchoring()) {
    const ReanchoringStatistics corrections = reanchoring->statistics();
    status.add("reanchoring", sourceName(reanchoring->config().source));
    status.add("submaps", reanchoring->fusion().submaps().size());
    status.add("submaps memory bytes",
               reanchoring->fusion().memoryBytes() + reanchoring->keptScanBytes());
    status.add("submaps spilled bytes (max_memory_mb)",
               reanchoring->fusion().spilledBytes() + reanchoring->spilledScanBytes());
    status.add("corrections applied", corrections.corrections);
    status.add("submaps moved", corrections.submaps_moved);
    status.add("slowest correction, map moved (ms)", 1e3 * corrections.slowest_move_seconds);
    status.add("slowest correction (ms)", 1e3 * corrections.slowest_correction_seconds);
    status.add("last path keyframes", corrections.path_keyframes);
    status.add("last path keyframes matched with the odometry", corrections.path_corrections);
    if (corrections.path_keyframes > 0 && corrections.path_corrections == 0) {
      status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                     "no keyframe of the SLAM path matches the odometry heard "
                     "(reanchoring/base_frame, reanchoring/odom_frame?)");
    }
  }
  status.add("longest lock hold (ms)", lock_statistics_.longestHoldMs());
  status.add("longest lock hold (call)", lock_statistics_.longestHoldCall());
  status.add("longest wait for a read (ms)", lock_statistics_.longestReadWaitMs());
}

bool MapPublisher::onReset(std_srvs::Empty::Request& /*request*/,
                           std_srvs::Empty::Response& /*response*/) {
  {
    const MapCallTimer timer(&lock_statistics_, "~reset");
    map_->reset();
  }
  ROS_INFO("%s: map '%s' reset", name_.c_str(), map_->name().c_str());
  return true;
}

bool MapPublisher::onClearBox(BoundingBoxQuery::Request& request,
                              BoundingBoxQuery::Response& /*response*/) {
  const Eigen::Vector3d min(request.min.x, request.min.y, request.min.z);
  const Eigen::Vector3d max(request.max.x, request.max.y, request.max.z);
  std::size_t voxels = 0, cells = 0;
  {
    const MapCallTimer timer(&lock_statistics_, "~clear_bbx (voxels)");
    voxels = map_->voxels().clearBox(min, max);
  }
  {
    // The 2D layer has no height: its cells under the box's footprint are cleared too.
    const MapCallTimer timer(&lock_statistics_, "~clear_bbx (layer)");
    cells = map_->layer().clearBox(min.head<2>(), max.head<2>());
  }
  ROS_INFO("%s: cleared %zu voxels and %zu layer cells in [%.2f %.2f %.2f] - [%.2f %.2f %.2f]",
           name_.c_str(), voxels, cells, min.x(), min.y(), min.z(), max.x(), max.y(), max.z());
  return true;
}

bool MapPublisher::onSaveMap(SaveMap::Request& request, SaveMap::Response& response) {
  const std::string prefix = request.prefix.empty() ? config_.save_prefix : request.prefix;
  try {
    saveMapFiles(*map_, config_.grid, prefix, &response.files, &lock_statistics_);
    response.success = true;
    response.message =
        "saved map '" + map_->name() + "' as " + prefix + ".{ot,bt,pgm,yaml,laser.yaml,laser.npy}";
    ROS_INFO("%s: %s", name_.c_str(), response.message.c_str());
  } catch (const std::exception& error) {
    response.success = false;
    response.message = error.what();
    ROS_ERROR("%s: saving the map to '%s' failed: %s", name_.c_str(), prefix.c_str(), error.what());
  }
  return true;
}

void saveMapFiles(SharedMap& map, const FusedGridConfig& grid, const std::string& prefix,
                  std::vector<std::string>* written, MapLockStatistics* lock_statistics) {
  MapSaveOptions options;
  options.band = grid;
  const SavedMapFiles saved = saveMap(map.voxels(), map.layer(), prefix, options, written,
                                      [lock_statistics](const char* what, double milliseconds) {
                                        if (lock_statistics != nullptr)
                                          lock_statistics->recordHold(what, milliseconds);
                                      });
  if (saved.octomap_skipped_voxels > 0) {
    ROS_WARN(
        "saving map '%s': %zu voxels lie outside OctoMap's 16-bit key range and are not in "
        "the .ot/.bt files",
        map.name().c_str(), saved.octomap_skipped_voxels);
  }
  if (map.reanchoring() != nullptr) {
    const std::string path = submapFilePath(prefix);
    writeSubmapFile(map.reanchoring(), path);
    written->push_back(path);
  }
}

}  // namespace occupancy_fusion
