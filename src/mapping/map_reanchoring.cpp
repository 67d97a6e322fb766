#include "occupancy_fusion/mapping/map_reanchoring.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "occupancy_fusion/mapping/mapping_session.h"  // placeScan
#include "submap_spill_file.h"

namespace occupancy_fusion {
namespace {

// Tells reanchorings apart for the drawing threads' integrators (an address may be reused).
std::uint64_t nextSerial() {
  static std::atomic<std::uint64_t> serial{0};
  return ++serial;
}

void requirePositive(double value, const char* name, bool zero_allowed) {
  if (std::isfinite(value) && (value > 0.0 || (zero_allowed && value == 0.0))) return;
  throw std::invalid_argument(std::string(name) +
                              (zero_allowed ? " must be >= 0" : " must be > 0") + ", got " +
                              std::to_string(value));
}

// The submaps spill (reanchoring/max_memory_mb) next to the map's spill store when it has one.
SubmapFusionConfig fusionConfig(const ReanchoringConfig& config, const VoxelMap& map) {
  SubmapFusionConfig fusion = config.fusion;
  if (fusion.spill_folder.empty()) fusion.spill_folder = map.config().spill_folder;
  return fusion;
}

template <class T>
void appendValue(std::string* bytes, const T& value) {
  bytes->append(reinterpret_cast<const char*>(&value), sizeof(value));
}

template <class T>
T takeValue(const std::string& bytes, std::size_t* at) {
  T value{};
  if (*at + sizeof(value) > bytes.size()) throw std::runtime_error("kept scans: record ends early");
  std::copy_n(bytes.data() + *at, sizeof(value), reinterpret_cast<char*>(&value));
  *at += sizeof(value);
  return value;
}

}  // namespace

const char* sourceName(ReanchoringConfig::Source source) {
  switch (source) {
    case ReanchoringConfig::Source::kTf:
      return "tf";
    case ReanchoringConfig::Source::kPath:
      return "path";
    case ReanchoringConfig::Source::kNone:
      break;
  }
  return "none";
}

void ReanchoringConfig::validate() const {
  if (enabled() && (odom_frame.empty() || base_frame.empty())) {
    throw std::invalid_argument("reanchoring/odom_frame and reanchoring/base_frame must be set");
  }
  requirePositive(submap_distance, "reanchoring/submap_distance (m)", false);
  requirePositive(submap_seconds, "reanchoring/submap_seconds (s, 0: no limit)", true);
  requirePositive(keep_scan_distance, "ReanchoringConfig.keep_scan_distance (m)", true);
  requirePositive(keep_scan_angle, "ReanchoringConfig.keep_scan_angle (rad)", true);
  requirePositive(keep_scan_seconds, "ReanchoringConfig.keep_scan_seconds (s)", true);
  fusion.validate();
  trajectory.validate();
}

ReanchoringConfig readReanchoringConfig(const ParameterSource& source) {
  ReanchoringConfig config;
  std::string name = sourceName(config.source);
  source.get("reanchoring/source", &name);
  if (name == "none") {
    config.source = ReanchoringConfig::Source::kNone;
  } else if (name == "tf") {
    config.source = ReanchoringConfig::Source::kTf;
  } else if (name == "path") {
    config.source = ReanchoringConfig::Source::kPath;
  } else {
    throw std::invalid_argument("reanchoring/source must be none, tf or path, got '" + name + "'");
  }
  source.get("reanchoring/odom_frame", &config.odom_frame);
  source.get("reanchoring/base_frame", &config.base_frame);
  source.get("reanchoring/submap_distance", &config.submap_distance);
  source.get("reanchoring/submap_seconds", &config.submap_seconds);
  source.get("reanchoring/min_shift", &config.fusion.min_shift);
  double max_memory_mb = 0.0;
  source.get("reanchoring/max_memory_mb", &max_memory_mb);
  if (!(max_memory_mb >= 0.0) || !std::isfinite(max_memory_mb)) {
    throw std::invalid_argument("reanchoring/max_memory_mb must be >= 0 (0: unbounded), got " +
                                std::to_string(max_memory_mb));
  }
  // Three quarters for the submaps' changes, a quarter for the laser scans kept to draw them.
  const auto bound = static_cast<std::size_t>(max_memory_mb * 1048576.0);
  config.fusion.max_memory_bytes = bound - bound / 4;
  config.max_scan_bytes = bound / 4;
  source.get("reanchoring/max_odometry_gap", &config.trajectory.max_odometry_gap);
  config.validate();
  return config;
}

MapReanchoring::MapReanchoring(VoxelMap* map, GridLayer2D* layer, const ReanchoringConfig& config)
    : config_(config),
      fusion_(map, layer, fusionConfig(config, *map)),
      // tf's map -> odom wanders by millimetres with every localisation update (AMCL): a jump is
      // a voxel unless set, so that those are not each taken as a correction.
      jump_shift_(config.fusion.min_shift > 0.0 ? config.fusion.min_shift : map->resolution()),
      serial_(nextSerial()) {
  config_.validate();
  if (layer != nullptr) fusion_.setLayerDrawer(this);
}

MapReanchoring::~MapReanchoring() {
  stopCorrecting();
  fusion_.setLayerDrawer(nullptr);
}

void MapReanchoring::keepScan(int submap, const std::string& sensor,
                              const PolarLaserIntegrator& integrator, double stamp,
                              const Eigen::Isometry3d& T_odom_sensor, const LaserScan& scan,
                              double max_tilt) {
  std::lock_guard<std::mutex> lock(scans_mutex_);
  std::size_t index = 0;
  while (index < integrators_.size() && integrators_[index].first != &integrator) ++index;
  if (index == integrators_.size()) {
    integrators_.emplace_back(&integrator,
                              std::make_unique<PolarLaserIntegrator>(integrator.config()));
  }
  if (KeptScan* last = lastKeptLocked(sensor, submap)) {
    // Taken about where the last one kept was: it counts once more there instead.
    const Eigen::Isometry3d step = last->T_odom_sensor.inverse() * T_odom_sensor;
    if (std::abs(stamp - last->stamp) < config_.keep_scan_seconds &&
        step.translation().norm() < config_.keep_scan_distance &&
        Eigen::AngleAxisd(step.linear()).angle() < config_.keep_scan_angle) {
      last->weight += 1.0f;
      return;
    }
  }
  std::vector<KeptScan>& kept = kept_scans_[submap];
  last_kept_[sensor] = {submap, kept.size()};
  kept.push_back({index, stamp, T_odom_sensor, scan, max_tilt});
  kept_scan_bytes_ += kept.back().bytes();
  if (config_.max_scan_bytes > 0 && kept_scan_bytes_ > config_.max_scan_bytes) {
    spillOldScansLocked(submap);
  }
}

MapReanchoring::KeptScan* MapReanchoring::lastKeptLocked(const std::string& sensor, int submap) {
  // Only one of the same submap still in memory (a spilled record is not written again).
  const auto found = last_kept_.find(sensor);
  if (found == last_kept_.end()) return nullptr;
  const LastKept& last = found->second;
  if (last.submap != submap) return nullptr;
  const auto kept = kept_scans_.find(submap);
  if (kept == kept_scans_.end() || last.index >= kept->second.size()) return nullptr;
  return &kept->second[last.index];
}

void MapReanchoring::spillOldScansLocked(int active_submap) {
  // The oldest first; the submap being written stays (its scans still grow).
  for (auto it = kept_scans_.begin();
       it != kept_scans_.end() && kept_scan_bytes_ > config_.max_scan_bytes;) {
    if (it->first == active_submap) {
      ++it;
      continue;
    }
    // With what an earlier spill of this submap holds (a frame leased before the submap closed
    // may add a scan after).
    const std::vector<KeptScan> scans = scansOfLocked(it->first);
    std::string bytes;
    appendValue(&bytes, static_cast<std::uint64_t>(scans.size()));
    for (const KeptScan& kept : scans) {
      appendValue(&bytes, static_cast<std::uint64_t>(kept.integrator));
      appendValue(&bytes, kept.stamp);
      for (int i = 0; i < 16; ++i) appendValue(&bytes, kept.T_odom_sensor.matrix().data()[i]);
      for (double value : {kept.scan.angle_min, kept.scan.angle_increment, kept.scan.range_min,
                           kept.scan.range_max, kept.max_tilt}) {
        appendValue(&bytes, value);
      }
      appendValue(&bytes, kept.weight);
      appendValue(&bytes, static_cast<std::uint64_t>(kept.scan.ranges.size()));
      bytes.append(reinterpret_cast<const char*>(kept.scan.ranges.data()),
                   kept.scan.ranges.size() * sizeof(float));
    }
    if (!scan_spill_) scan_spill_ = std::make_unique<SubmapSpillFile>(config_.fusion.spill_folder);
    spilled_scans_[it->first] = {scan_spill_->append(bytes),
                                 static_cast<std::uint32_t>(bytes.size())};
    for (const KeptScan& kept : it->second) kept_scan_bytes_ -= kept.bytes();
    for (auto& [sensor, last] : last_kept_) {
      if (last.submap == it->first) last = LastKept();  // a late scan starts a record anew
    }
    it = kept_scans_.erase(it);
  }
}

std::vector<MapReanchoring::KeptScan> MapReanchoring::scansOfLocked(int submap) const {
  std::vector<KeptScan> scans = spilledScansLocked(submap);
  const auto kept = kept_scans_.find(submap);
  if (kept != kept_scans_.end())
    scans.insert(scans.end(), kept->second.begin(), kept->second.end());
  return scans;
}

std::vector<MapReanchoring::KeptScan> MapReanchoring::spilledScansLocked(int submap) const {
  const auto spilled = spilled_scans_.find(submap);
  if (spilled == spilled_scans_.end()) return {};
  std::string bytes;
  scan_spill_->read(spilled->second.first, spilled->second.second, &bytes);
  std::size_t at = 0;
  std::vector<KeptScan> scans(takeValue<std::uint64_t>(bytes, &at));
  for (KeptScan& kept : scans) {
    kept.integrator = takeValue<std::uint64_t>(bytes, &at);
    kept.stamp = takeValue<double>(bytes, &at);
    for (int i = 0; i < 16; ++i)
      kept.T_odom_sensor.matrix().data()[i] = takeValue<double>(bytes, &at);
    kept.scan.angle_min = takeValue<double>(bytes, &at);
    kept.scan.angle_increment = takeValue<double>(bytes, &at);
    kept.scan.range_min = takeValue<double>(bytes, &at);
    kept.scan.range_max = takeValue<double>(bytes, &at);
    kept.max_tilt = takeValue<double>(bytes, &at);
    kept.weight = takeValue<float>(bytes, &at);
    kept.scan.ranges.resize(takeValue<std::uint64_t>(bytes, &at));
    const std::size_t size = kept.scan.ranges.size() * sizeof(float);
    if (at + size > bytes.size()) throw std::runtime_error("kept scans: record ends early");
    std::copy_n(bytes.data() + at, size, reinterpret_cast<char*>(kept.scan.ranges.data()));
    at += size;
  }
  return scans;
}

std::size_t MapReanchoring::keptScanBytes() const {
  std::lock_guard<std::mutex> lock(scans_mutex_);
  return kept_scan_bytes_;
}

std::size_t MapReanchoring::spilledScanBytes() const {
  std::lock_guard<std::mutex> lock(scans_mutex_);
  return scan_spill_ ? scan_spill_->bytes() : 0;
}

namespace {

// An integrator keeps caches of its sensors' geometry: one per thread, laser and reanchoring
// (`serial`), made once. (A function of its own: a thread_local named inside an OpenMP region is
// not each thread's own with every compiler.)
PolarLaserIntegrator* integratorOfThisThread(std::uint64_t serial, std::size_t laser,
                                             const PolarLaserIntegratorConfig& config) {
  thread_local std::map<std::pair<std::uint64_t, std::size_t>,
                        std::unique_ptr<PolarLaserIntegrator>>
      integrators;
  std::unique_ptr<PolarLaserIntegrator>& integrator = integrators[{serial, laser}];
  if (!integrator) integrator = std::make_unique<PolarLaserIntegrator>(config);
  return integrator.get();
}

}  // namespace

bool MapReanchoring::draw(int id, const Eigen::Isometry3d& T_map_odom, GridLayer2D* layer) {
  std::vector<StampedPose> corrections;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    corrections = corrections_;
  }
  std::vector<KeptScan> scans;
  std::vector<PolarLaserIntegratorConfig> configs;
  {
    std::lock_guard<std::mutex> lock(scans_mutex_);
    scans = scansOfLocked(id);  // from memory or read back from the spill file
    if (scans.empty()) return false;
    for (const auto& integrator : integrators_) configs.push_back(integrator.second->config());
  }
  // The scans' rasters are made side by side, each thread with integrators of its own; they are
  // added in the order the scans were taken, a few at a time (a raster of a 20 m scan at 0.05 m
  // takes about a megabyte).
  constexpr long kRastersAtOnce = 16;
  std::vector<std::optional<LogOddsRaster>> rasters(kRastersAtOnce);
  const long count = static_cast<long>(scans.size());
  for (long first = 0; first < count; first += kRastersAtOnce) {
    const long last = std::min(count, first + kRastersAtOnce);
#pragma omp parallel for schedule(dynamic, 1)
    for (long i = first; i < last; ++i) {
      const KeptScan& scan = scans[static_cast<std::size_t>(i)];
      PolarLaserIntegrator* integrator =
          integratorOfThisThread(serial_, scan.integrator, configs[scan.integrator]);
      // Each scan at the correction of its own time, the submap's placement without one.
      const Eigen::Isometry3d T_map_sensor =
          correctionAt(corrections, scan.stamp).value_or(T_map_odom) * scan.T_odom_sensor;
      std::optional<LogOddsRaster>& raster = rasters[static_cast<std::size_t>(i - first)];
      raster.reset();
      try {
        const PlacedScan placed = placeScan(scan.scan, T_map_sensor, scan.max_tilt);
        raster = integrator->rasterOf(placed.scan, placed.sensor, layer->resolution(), scan.weight);
      } catch (const std::invalid_argument&) {
        // Tilted beyond max_tilt at the corrected pose: left out, as a frame would be.
      }
    }
    for (long i = first; i < last; ++i) {
      const std::optional<LogOddsRaster>& raster = rasters[static_cast<std::size_t>(i - first)];
      if (raster) {
        layer->addRaster(raster->origin_cell, raster->width, raster->height, raster->data.data());
      }
    }
  }
  return true;
}

std::optional<MapReanchoring::PlacedFrame> MapReanchoring::placeFrame(
    const PoseSource& poses, const std::string& map_frame, const std::string& sensor_frame,
    double stamp, std::string* why) {
  const std::optional<Eigen::Isometry3d> T_odom_sensor =
      poses.lookup(config_.odom_frame, sensor_frame, stamp, why);
  if (!T_odom_sensor) return std::nullopt;
  std::string base_why;
  const std::optional<Eigen::Isometry3d> T_odom_base =
      poses.lookup(config_.odom_frame, config_.base_frame, stamp, &base_why);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (T_odom_base) odometry_.add(stamp, *T_odom_base);
  }
  startSubmapIfDue((T_odom_base ? *T_odom_base : *T_odom_sensor).translation(), stamp);
  if (config_.source == ReanchoringConfig::Source::kTf) {
    const std::optional<Eigen::Isometry3d> T_map_odom =
        poses.lookup(map_frame, config_.odom_frame, stamp, why);
    if (!T_map_odom) return std::nullopt;
    followMapToOdom(*T_map_odom, stamp);
  }
  PlacedFrame placed{fusion_.beginFrame(stamp), Eigen::Isometry3d::Identity(), *T_odom_sensor};
  placed.T_map_sensor = placed.lease.T_map_odom() * *T_odom_sensor;
  return placed;
}

void MapReanchoring::startSubmapIfDue(const Eigen::Vector3d& position, double stamp) {
  bool may_defer = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!started_) {
      started_ = true;
      submap_start_position_ = position;
      submap_start_stamp_ = stamp;
      return;
    }
    const double travelled = (position - submap_start_position_).norm();
    const bool due =
        travelled > config_.submap_distance ||
        (config_.submap_seconds > 0.0 && stamp - submap_start_stamp_ > config_.submap_seconds) ||
        stamp < submap_start_stamp_;  // time went back: a new recording or a reset clock
    if (!due) return;
    may_defer = travelled <= kDeferredDistance * config_.submap_distance;
  }
  // While a correction rebuilds the map, a later frame cuts the submap: waiting here held every
  // mapper's frames for the rebuild (0.4-1.2 s on a building floor). It runs on by at most a
  // quarter of submap_distance more (a submap carries the drift within it: placed rigidly), then
  // the frame waits.
  if (may_defer) {
    if (!fusion_.tryStartSubmap()) return;
  } else {
    fusion_.startSubmap();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  submap_start_position_ = position;
  submap_start_stamp_ = stamp;
}

SubmapMoveResult MapReanchoring::applyPath(const std::vector<StampedPose>& path, double stamp) {
  std::vector<StampedPose> corrections;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    corrections = correctionsAlongPath(path, odometry_, config_.trajectory);
    if (!corrections.empty()) corrections_ = corrections;
    statistics_.path_keyframes = path.size();
    statistics_.path_corrections = corrections.size();
  }
  if (corrections.empty()) return {};
  const SubmapMoveResult result = fusion_.place(
      placementsFromCorrections(corrections, fusion_.submaps()), corrections.back().pose);
  countCorrection(result, stamp);
  return result;
}

std::optional<std::vector<StampedPose>> MapReanchoring::noteMapToOdom(
    const Eigen::Isometry3d& T_map_odom, double stamp) {
  // Every frame asks: measured over the newest blocks only, the submaps listed only on a jump.
  const Eigen::AlignedBox3d reach = fusion_.newestBounds();
  std::lock_guard<std::mutex> lock(mutex_);
  const bool jump = map_to_odom_.empty() ||
                    largestShift(reach, Eigen::Isometry3d::Identity(), map_to_odom_.back().pose,
                                 T_map_odom) > jump_shift_ ||
                    (reach.isEmpty() && !T_map_odom.isApprox(map_to_odom_.back().pose));
  if (!jump) return std::nullopt;
  if (!map_to_odom_.empty()) ++statistics_.map_to_odom_jumps;
  map_to_odom_.push_back({stamp, T_map_odom});
  std::stable_sort(map_to_odom_.begin(), map_to_odom_.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.stamp < b.stamp; });
  return map_to_odom_;
}

SubmapMoveResult MapReanchoring::applyMapToOdom(const Eigen::Isometry3d& T_map_odom, double stamp) {
  const std::optional<std::vector<StampedPose>> corrections = noteMapToOdom(T_map_odom, stamp);
  if (!corrections) return {};
  {
    std::lock_guard<std::mutex> lock(mutex_);
    corrections_ = *corrections;  // where the kept scans are drawn
  }
  const SubmapMoveResult result =
      fusion_.place(placementsFromCorrections(*corrections, fusion_.submaps()), T_map_odom);
  countCorrection(result, stamp);
  return result;
}

void MapReanchoring::followMapToOdom(const Eigen::Isometry3d& T_map_odom, double stamp) {
  std::optional<std::vector<StampedPose>> corrections = noteMapToOdom(T_map_odom, stamp);
  if (!corrections) return;
  // The frames from now on go into a new submap at the new correction; the submaps before are
  // moved on the correcting thread, while this sensor's frames go on. While a correction still
  // rebuilds the map, the active submap goes on at its old placement instead of waiting for it:
  // the correction queued here places it by the jump's own correction (odometry is smooth across
  // a jump, only its estimate jumps) and starts the next submap at T_map_odom.
  fusion_.tryStartSubmap(T_map_odom);
  std::lock_guard<std::mutex> lock(worker_mutex_);
  pending_ = PendingCorrection{std::move(*corrections), T_map_odom, stamp};
  if (!worker_.joinable()) worker_ = std::thread([this] { correctInTurn(); });
  worker_wake_.notify_all();
}

void MapReanchoring::correctInTurn() {
  std::unique_lock<std::mutex> lock(worker_mutex_);
  while (true) {
    worker_wake_.wait(lock, [&] { return stopping_ || pending_; });
    if (stopping_) return;
    // Only the newest: it holds every jump heard so far.
    const PendingCorrection correction = std::move(*pending_);
    pending_.reset();
    correcting_ = true;
    lock.unlock();
    {
      std::lock_guard<std::mutex> corrections(mutex_);
      corrections_ = correction.corrections;  // the scans drawn by this one, not a newer one
    }
    const SubmapMoveResult result = fusion_.place(
        placementsFromCorrections(correction.corrections, fusion_.submaps()), correction.next);
    countCorrection(result, correction.stamp);
    lock.lock();
    correcting_ = false;
    worker_idle_.notify_all();
  }
}

void MapReanchoring::waitForCorrections() {
  std::unique_lock<std::mutex> lock(worker_mutex_);
  worker_idle_.wait(lock, [&] { return !pending_ && !correcting_; });
}

void MapReanchoring::stopCorrecting() {
  {
    std::lock_guard<std::mutex> lock(worker_mutex_);
    stopping_ = true;
    pending_.reset();
  }
  worker_wake_.notify_all();
  if (worker_.joinable()) worker_.join();
  std::lock_guard<std::mutex> lock(worker_mutex_);
  stopping_ = false;
  worker_idle_.notify_all();
}

void MapReanchoring::countCorrection(const SubmapMoveResult& result, double stamp) {
  if (result.moved == 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  ++statistics_.corrections;
  statistics_.submaps_moved += result.moved;
  statistics_.blocks_rewritten += result.blocks_rewritten;
  statistics_.last_correction_seconds = result.seconds;
  statistics_.slowest_correction_seconds =
      std::max(statistics_.slowest_correction_seconds, result.seconds);
  statistics_.slowest_move_seconds =
      std::max(statistics_.slowest_move_seconds, result.moved_seconds);
  statistics_.last_correction_stamp = stamp;
}

ReanchoringStatistics MapReanchoring::statistics() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return statistics_;
}

std::size_t MapReanchoring::odometryPoses() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return odometry_.size();
}

namespace {

void writePoses(std::ostream& out, const std::vector<StampedPose>& poses) {
  const std::uint64_t count = poses.size();
  out.write(reinterpret_cast<const char*>(&count), sizeof(count));
  for (const StampedPose& pose : poses) {
    out.write(reinterpret_cast<const char*>(&pose.stamp), sizeof(pose.stamp));
    out.write(reinterpret_cast<const char*>(pose.pose.matrix().data()), 16 * sizeof(double));
  }
}

std::vector<StampedPose> readPoses(std::istream& in) {
  std::uint64_t count = 0;
  in.read(reinterpret_cast<char*>(&count), sizeof(count));
  std::vector<StampedPose> poses;
  for (std::uint64_t i = 0; in && i < count; ++i) {
    StampedPose pose;
    in.read(reinterpret_cast<char*>(&pose.stamp), sizeof(pose.stamp));
    in.read(reinterpret_cast<char*>(pose.pose.matrix().data()), 16 * sizeof(double));
    poses.push_back(pose);
  }
  if (!in) throw std::runtime_error("submaps: the odometry ends early");
  return poses;
}

}  // namespace

void MapReanchoring::saveThen(std::ostream& out, const std::function<void()>& then) {
  fusion_.saveThen(out, [&] {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      writePoses(out, odometry_.poses());
      writePoses(out, map_to_odom_);
    }
    if (then) then();
  });
}

void MapReanchoring::restore(std::istream& in) {
  stopCorrecting();  // a correction of the submaps before is moot
  {
    // Kept scans belong to the submaps before: the restored ones are re-sampled when they move.
    std::lock_guard<std::mutex> scans(scans_mutex_);
    kept_scans_.clear();
    kept_scan_bytes_ = 0;
    spilled_scans_.clear();
  }
  fusion_.restore(in);
  std::vector<StampedPose> odometry = readPoses(in), map_to_odom = readPoses(in);
  std::lock_guard<std::mutex> lock(mutex_);
  odometry_.clear();
  for (const StampedPose& pose : odometry) odometry_.add(pose.stamp, pose.pose);
  map_to_odom_ = std::move(map_to_odom);
  started_ = false;  // the next frame starts a submap where it is
}

void MapReanchoring::reset() {
  stopCorrecting();
  fusion_.reset();
  std::lock_guard<std::mutex> lock(mutex_);
  odometry_.clear();
  map_to_odom_.clear();
  corrections_.clear();
  started_ = false;
  std::lock_guard<std::mutex> scans(scans_mutex_);
  kept_scans_.clear();
  kept_scan_bytes_ = 0;
  spilled_scans_.clear();
  scan_spill_.reset();
  last_kept_.clear();
  statistics_ = ReanchoringStatistics();
}

}  // namespace occupancy_fusion
