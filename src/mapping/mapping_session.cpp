#include "occupancy_fusion/mapping/mapping_session.h"

#include <cmath>
#include <ostream>
#include <stdexcept>

#include "occupancy_fusion/mapping/submap_files.h"
#include "occupancy_fusion/params/config_readers.h"
#include "occupancy_fusion/params/depth_config_reader.h"
#include "occupancy_fusion/params/laser_config_reader.h"
#include "occupancy_fusion/params/stereo_config_reader.h"

namespace occupancy_fusion {
namespace {

std::vector<Eigen::Vector3f> transformed(const std::vector<Eigen::Vector3f>& points,
                                         const Eigen::Isometry3d& map_T_sensor) {
  const Eigen::Isometry3f transform = map_T_sensor.cast<float>();
  std::vector<Eigen::Vector3f> result;
  result.reserve(points.size());
  for (const Eigen::Vector3f& point : points) result.push_back(transform * point);
  return result;
}

bool hasKey(const ParameterSource& source, const std::string& key) {
  for (const std::string& present : source.keys()) {
    if (present == key || present.rfind(key + "/", 0) == 0) return true;
  }
  return false;
}

// Topics as configured ("front/scan") and as recorded ("/front/scan") name the same topic.
std::string withoutLeadingSlash(const std::string& topic) {
  return topic.rfind('/', 0) == 0 ? topic.substr(1) : topic;
}

template <class Integrator, class Config>
Integrator& made(std::unique_ptr<Integrator>* integrator, const Config& config) {
  if (!*integrator) *integrator = std::make_unique<Integrator>(config);
  return **integrator;
}

}  // namespace

void MappingSessionConfig::validate() const {
  if (frame_id.empty()) throw std::invalid_argument("frame_id must not be empty");
  map.validate();
  point_cloud.validate();
  depth.validate();
  stereo.validate();
  laser.validate();
  for (const LaserSourceConfig& laser_source : laser_sources) laser_source.validate();
  if (!(laser_max_tilt >= 0.0 && laser_max_tilt < M_PI / 2)) {
    throw std::invalid_argument("laser/max_tilt must be in [0, pi/2) rad");
  }
  fused_grid.validate();
  reanchoring.validate();
}

MappingSessionConfig readMappingSessionConfig(const ParameterSource& source) {
  MappingSessionConfig config;
  source.get("frame_id", &config.frame_id);
  config.map = readVoxelMapConfig(source);
  config.point_cloud = readPointCloudIntegratorConfig(source);
  config.depth = readPyramidDepthConfig(source);
  config.stereo = readVisibilityStereoConfig(source);
  config.laser = readPolarLaserIntegratorConfig(source, "laser/");
  source.get("laser/max_tilt", &config.laser_max_tilt);
  if (hasKey(source, "observation_sources")) config.laser_sources = readLaserSourceConfigs(source);
  config.fused_grid = readFusedGridConfig(source);
  config.reanchoring = readReanchoringConfig(source);
  config.validate();
  return config;
}

PlacedScan placeScan(const LaserScan& scan, const Eigen::Isometry3d& T_frame_sensor,
                     double max_tilt) {
  if (!T_frame_sensor.matrix().allFinite()) {
    throw std::invalid_argument("the scanner's pose is not finite");
  }
  bool upside_down = false;
  PlacedScan placed;
  placed.sensor = planarPose(T_frame_sensor, max_tilt, &upside_down);
  placed.scan = upside_down ? mirrorScan(scan) : scan;
  return placed;
}

std::size_t MappingStatistics::framesIntegrated() const {
  std::size_t total = 0;
  for (const auto& entry : frames_by_kind) total += entry.second;
  return total;
}

std::size_t MappingStatistics::framesSkipped() const {
  std::size_t total = 0;
  for (const auto& entry : skipped_by_reason) total += entry.second;
  return total;
}

MappingSession::MappingSession(const MappingSessionConfig& config, const PoseSource* poses,
                               std::ostream* warnings)
    : MappingSession(config, nullptr, nullptr, poses, warnings) {}

MappingSession::MappingSession(const MappingSessionConfig& config, VoxelMap* voxels,
                               GridLayer2D* layer, const PoseSource* poses, std::ostream* warnings)
    : config_(config), poses_(poses), warnings_(warnings), voxels_(voxels), layer_(layer) {
  config_.validate();
  if (voxels_ == nullptr) {
    own_voxels_ = std::make_unique<VoxelMap>(config_.map);
    voxels_ = own_voxels_.get();
  }
  if (layer_ == nullptr) {
    own_layer_ = std::make_unique<GridLayer2D>(laserLayerConfig(config_.map));
    layer_ = own_layer_.get();
  }
  if (own_voxels_ && own_layer_) {
    checkpoints_ = std::make_unique<MapCheckpoints>(voxels_, layer_);
    if (config_.reanchoring.enabled()) {
      own_reanchoring_ = std::make_unique<MapReanchoring>(voxels_, layer_, config_.reanchoring);
      reanchoring_ = own_reanchoring_.get();
      resumeSubmaps();
    }
  }
  for (const LaserSourceConfig& laser_source : config_.laser_sources) {
    source_integrators_.push_back(std::make_unique<PolarLaserIntegrator>(laser_source.integrator));
  }
}

FrameOutcome MappingSession::integrate(const PointCloudFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  Eigen::Isometry3d map_T_sensor;
  std::optional<MapReanchoring::PlacedFrame> lease;
  FrameOutcome outcome = place(frame.header, frame.header.frame_id, &map_T_sensor, &lease);
  if (outcome.drop != nullptr) return outcome;
  // The sensor sits at the origin of the cloud's frame.
  last_point_cloud_ =
      made(&point_cloud_integrator_, config_.point_cloud)
          .integrate(transformed(frame.points, map_T_sensor), map_T_sensor.translation(), voxels_);
  statistics_.points += frame.points.size();
  return integrated(frame.header, frame.points.size(), start);
}

FrameOutcome MappingSession::integrate(const DepthImageFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  try {
    frame.camera.validate();
    frame.view().validateAgainst(frame.camera);
  } catch (const std::invalid_argument& error) {
    return drop(frame.header, kDropBadFrame, "bad depth image on " + frame.header.source,
                error.what());
  }
  Eigen::Isometry3d map_T_camera;
  std::optional<MapReanchoring::PlacedFrame> lease;
  FrameOutcome outcome = place(frame.header, frame.header.frame_id, &map_T_camera, &lease);
  if (outcome.drop != nullptr) return outcome;
  last_depth_ = made(&depth_integrator_, config_.depth)
                    .integrate(frame.view(), frame.camera, map_T_camera, voxels_);
  return integrated(frame.header,
                    static_cast<std::size_t>(frame.camera.width) * frame.camera.height, start);
}

FrameOutcome MappingSession::integrate(const DisparityFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  try {
    frame.camera.validate();
    frame.view().validate();
    if (frame.disparity.size() != static_cast<std::size_t>(frame.width) * frame.height) {
      throw std::invalid_argument("disparity data does not match its size");
    }
  } catch (const std::invalid_argument& error) {
    return drop(frame.header, kDropBadFrame, "bad disparity image on " + frame.header.source,
                error.what());
  }
  Eigen::Isometry3d map_T_camera;
  std::optional<MapReanchoring::PlacedFrame> lease;
  FrameOutcome outcome = place(frame.header, frame.header.frame_id, &map_T_camera, &lease);
  if (outcome.drop != nullptr) return outcome;
  last_stereo_ = made(&stereo_integrator_, config_.stereo)
                     .integrate(frame.view(), frame.camera, map_T_camera, voxels_);
  return integrated(frame.header, frame.disparity.size(), start);
}

FrameOutcome MappingSession::integrate(const LaserScanFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  try {
    frame.scan.validate();
  } catch (const std::invalid_argument& error) {
    return drop(frame.header, kDropBadFrame, "bad laser scan on " + frame.header.source,
                error.what());
  }
  const std::string sensor_frame = sensorFrameOf(frame.header);
  Eigen::Isometry3d map_T_sensor;
  std::optional<MapReanchoring::PlacedFrame> lease;
  FrameOutcome outcome = place(frame.header, sensor_frame, &map_T_sensor, &lease);
  if (outcome.drop != nullptr) return outcome;
  PlacedScan placed;
  try {
    placed = placeScan(frame.scan, map_T_sensor, maxTiltOf(frame.header));
  } catch (const std::invalid_argument& error) {
    return drop(frame.header, kDropTiltedScanPlane, "scan plane of '" + sensor_frame + "' tilted",
                error.what());
  }
  const LaserSourceConfig* laser_source = laserSourceOf(frame.header);
  PolarLaserIntegrator& integrator = laser_source == nullptr
                                         ? made(&laser_integrator_, config_.laser)
                                         : *source_integrators_[static_cast<std::size_t>(
                                               laser_source - &config_.laser_sources[0])];
  integrator.integrateIntoLayer(placed.scan, placed.sensor, layer_);
  if (lease) {  // kept to draw its cells anew when its submap moves
    reanchoring_->keepScan(lease->lease.submap(), sensor_frame, integrator, frame.header.stamp,
                           lease->T_odom_sensor, frame.scan, maxTiltOf(frame.header));
  }
  return integrated(frame.header, frame.scan.ranges.size(), start);
}

void MappingSession::resumeSubmaps() {
  try {
    resumeCheckpointedSubmaps(*checkpoints_, reanchoring_);
  } catch (const std::runtime_error& error) {
    if (warnings_ != nullptr) {
      *warnings_ << "warning: " << error.what() << "; the resumed map stays where it is\n";
    }
  }
}

CheckpointResult MappingSession::checkpoint(const std::string& stamp) {
  if (!checkpoints_) return CheckpointResult();
  if (reanchoring_ != nullptr)
    return checkpointWithSubmaps(checkpoints_.get(), reanchoring_, stamp);
  return checkpoints_->checkpoint(stamp);
}

ResumedMap MappingSession::resumeFrom(const std::string& path) {
  ResumedMap resumed = resumeSavedMap(path, voxels_, layer_);
  if (reanchoring_ != nullptr && !readSubmapFile(reanchoring_, submapFilePath(path))) {
    reanchoring_->fusion().fixWrittenSoFar();
  }
  return resumed;
}

void MappingSession::onUnreadable(const FrameHeader& header, const std::string& why) {
  drop(header, kDropUnreadable, "unreadable message on " + header.source, why);
}

const LaserSourceConfig* MappingSession::laserSourceOf(const FrameHeader& header) const {
  for (const LaserSourceConfig& laser_source : config_.laser_sources) {
    if (withoutLeadingSlash(laser_source.topic) == withoutLeadingSlash(header.source)) {
      return &laser_source;
    }
  }
  return nullptr;
}

std::string MappingSession::sensorFrameOf(const FrameHeader& header) const {
  const LaserSourceConfig* laser_source = header.kind == "laser" ? laserSourceOf(header) : nullptr;
  return laser_source != nullptr && !laser_source->sensor_frame.empty() ? laser_source->sensor_frame
                                                                        : header.frame_id;
}

double MappingSession::maxTiltOf(const FrameHeader& header) const {
  const LaserSourceConfig* laser_source = laserSourceOf(header);
  return laser_source != nullptr ? laser_source->max_tilt : config_.laser_max_tilt;
}

OccupancyRaster MappingSession::fusedGrid() const {
  return projectToRaster(*voxels_, layer_, config_.fused_grid);
}

SubmapMoveResult MappingSession::onPath(const std::vector<StampedPose>& path, double stamp) {
  if (reanchoring_ == nullptr ||
      reanchoring_->config().source != ReanchoringConfig::Source::kPath) {
    return {};
  }
  return reanchoring_->applyPath(path, stamp);
}

FrameOutcome MappingSession::place(const FrameHeader& header, const std::string& sensor_frame,
                                   Eigen::Isometry3d* map_T_sensor,
                                   std::optional<MapReanchoring::PlacedFrame>* lease) {
  if (header.stamp != 0.0) {  // 0: unstamped (files without times), never a duplicate
    const auto last = last_stamp_.find(header.kind + '|' + header.frame_id);
    if (last != last_stamp_.end() && last->second == header.stamp) {
      return drop(header, kDropDuplicateStamp, "duplicate stamp on " + header.source,
                  "frame of '" + header.frame_id + "' at t = " + std::to_string(header.stamp) +
                      " s has the stamp of the last one integrated");
    }
  }
  std::string why;
  std::optional<Eigen::Isometry3d> pose;
  if (poses_ != nullptr && reanchoring_ != nullptr) {  // by odometry, whatever the frame carries
    *lease = reanchoring_->placeFrame(*poses_, config_.frame_id, sensor_frame, header.stamp, &why);
    if (*lease) pose = (*lease)->T_map_sensor;
  } else if (header.T_map_sensor) {
    pose = header.T_map_sensor;
  } else if (poses_ != nullptr) {
    pose = poses_->lookup(config_.frame_id, sensor_frame, header.stamp, &why);
  }
  if (!pose) {
    return drop(header, kDropNoPose,
                "no transform from '" + sensor_frame + "' to '" + config_.frame_id + "'",
                "at t = " + std::to_string(header.stamp) +
                    " s: " + (why.empty() ? "the input has no poses" : why));
  }
  if (!pose->matrix().allFinite()) {  // NaN in a pose file, a recorded or a live transform
    return drop(header, kDropPoseNotFinite,
                "pose of '" + sensor_frame + "' in '" + config_.frame_id + "' not finite",
                "at t = " + std::to_string(header.stamp) + " s");
  }
  *map_T_sensor = *pose;
  return {};
}

FrameOutcome MappingSession::drop(const FrameHeader& header, const char* why,
                                  const std::string& reason, const std::string& detail) {
  ++statistics_.by_kind[header.kind.empty() ? "unknown" : header.kind].skipped;
  if (statistics_.skipped_by_reason[reason]++ == 0) {
    statistics_.first_skip_detail[reason] = detail;
    if (warnings_ != nullptr) {
      *warnings_ << "warning: skipping frame: " << reason << " (" << detail
                 << "); further frames skipped for this reason are only counted\n";
    }
  }
  FrameOutcome outcome;
  outcome.drop = why;
  outcome.detail = reason + ": " + detail;
  return outcome;
}

FrameOutcome MappingSession::integrated(const FrameHeader& header, std::size_t measurements,
                                        std::chrono::steady_clock::time_point start) {
  if (header.stamp != 0.0) last_stamp_[header.kind + '|' + header.frame_id] = header.stamp;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ++statistics_.frames_by_kind[header.kind];
  SensorKindStatistics& stats = statistics_.by_kind[header.kind];
  ++stats.frames;
  stats.measurements += measurements;
  stats.integration_seconds += seconds;
  statistics_.integration_seconds += seconds;
  FrameOutcome outcome;
  outcome.integrated = true;
  return outcome;
}

}  // namespace occupancy_fusion
