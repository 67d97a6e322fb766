#include "occupancy_fusion/tools/recording_mapper.h"

#include <chrono>
#include <cmath>
#include <ostream>
#include <stdexcept>

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

GridLayer2DConfig laserLayerConfig(const VoxelMapConfig& map) {
  GridLayer2DConfig layer;
  layer.resolution = map.resolution;
  layer.model = map.model;
  return layer;
}

}  // namespace

void RecordingMapperConfig::validate() const {
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
}

RecordingMapperConfig readRecordingMapperConfig(const ParameterSource& source) {
  RecordingMapperConfig config;
  source.get("frame_id", &config.frame_id);
  config.map = readVoxelMapConfig(source);
  config.point_cloud = readPointCloudIntegratorConfig(source);
  config.depth = readPyramidDepthConfig(source);
  config.stereo = readVisibilityStereoConfig(source);
  config.laser = readPolarLaserIntegratorConfig(source, "laser/");
  source.get("laser/max_tilt", &config.laser_max_tilt);
  if (hasKey(source, "observation_sources")) config.laser_sources = readLaserSourceConfigs(source);
  config.fused_grid = readFusedGridConfig(source);
  config.validate();
  return config;
}

std::size_t RecordingStatistics::framesIntegrated() const {
  std::size_t total = 0;
  for (const auto& entry : frames_by_kind) total += entry.second;
  return total;
}

std::size_t RecordingStatistics::framesSkipped() const {
  std::size_t total = 0;
  for (const auto& entry : skipped_by_reason) total += entry.second;
  return total;
}

RecordingMapper::RecordingMapper(const RecordingMapperConfig& config, const PoseSource* poses,
                                 std::ostream* warnings)
    : config_(config),
      poses_(poses),
      warnings_(warnings),
      map_(config.map),
      laser_layer_(laserLayerConfig(config.map)),
      point_cloud_integrator_(config.point_cloud),
      depth_integrator_(config.depth),
      stereo_integrator_(config.stereo),
      laser_integrator_(config.laser) {
  config_.validate();
  for (const LaserSourceConfig& laser_source : config_.laser_sources) {
    source_integrators_.push_back(std::make_unique<PolarLaserIntegrator>(laser_source.integrator));
  }
}

void RecordingMapper::onPointCloud(const PointCloudFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  const std::optional<Eigen::Isometry3d> map_T_sensor = poseOf(frame.header);
  if (!map_T_sensor) return;
  point_cloud_integrator_.integrate(transformed(frame.points, *map_T_sensor),
                                    map_T_sensor->translation(), &map_);
  statistics_.points += frame.points.size();
  countIntegrated("point_cloud", frame.points.size(), start);
}

void RecordingMapper::onDepthImage(const DepthImageFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  try {
    frame.camera.validate();
    frame.view().validateAgainst(frame.camera);
  } catch (const std::invalid_argument& error) {
    skip(frame.header, "bad depth image on " + frame.header.source, error.what());
    return;
  }
  const std::optional<Eigen::Isometry3d> map_T_camera = poseOf(frame.header);
  if (!map_T_camera) return;
  depth_integrator_.integrate(frame.view(), frame.camera, *map_T_camera, &map_);
  countIntegrated("depth", frame.depth.size(), start);
}

void RecordingMapper::onDisparityImage(const DisparityFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  try {
    frame.camera.validate();
    frame.view().validate();
    if (frame.disparity.size() != static_cast<std::size_t>(frame.width) * frame.height) {
      throw std::invalid_argument("disparity data does not match its size");
    }
  } catch (const std::invalid_argument& error) {
    skip(frame.header, "bad disparity image on " + frame.header.source, error.what());
    return;
  }
  const std::optional<Eigen::Isometry3d> map_T_camera = poseOf(frame.header);
  if (!map_T_camera) return;
  stereo_integrator_.integrate(frame.view(), frame.camera, *map_T_camera, &map_);
  countIntegrated("disparity", frame.disparity.size(), start);
}

void RecordingMapper::onLaserScan(const LaserScanFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  try {
    frame.scan.validate();
  } catch (const std::invalid_argument& error) {
    skip(frame.header, "bad laser scan on " + frame.header.source, error.what());
    return;
  }
  PolarLaserIntegrator* integrator = &laser_integrator_;
  double max_tilt = config_.laser_max_tilt;
  FrameHeader header = frame.header;
  for (std::size_t i = 0; i < config_.laser_sources.size(); ++i) {
    const LaserSourceConfig& laser_source = config_.laser_sources[i];
    if (withoutLeadingSlash(laser_source.topic) != withoutLeadingSlash(header.source)) continue;
    integrator = source_integrators_[i].get();
    max_tilt = laser_source.max_tilt;
    if (!laser_source.sensor_frame.empty()) header.frame_id = laser_source.sensor_frame;
    break;
  }
  const std::optional<Eigen::Isometry3d> map_T_sensor = poseOf(header);
  if (!map_T_sensor) return;
  bool upside_down = false;
  Pose2D sensor;
  try {
    sensor = planarPose(*map_T_sensor, max_tilt, &upside_down);
  } catch (const std::invalid_argument& error) {
    skip(header, "scan plane of '" + header.frame_id + "' tilted", error.what());
    return;
  }
  integrator->integrateIntoLayer(upside_down ? mirrorScan(frame.scan) : frame.scan, sensor,
                                 &laser_layer_);
  countIntegrated("laser", frame.scan.ranges.size(), start);
}

void RecordingMapper::onUnreadable(const FrameHeader& header, const std::string& why) {
  skip(header, "unreadable message on " + header.source, why);
}

void RecordingMapper::countIntegrated(const std::string& kind, std::size_t measurements,
                                      std::chrono::steady_clock::time_point start) {
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ++statistics_.frames_by_kind[kind];
  SensorKindStatistics& stats = statistics_.by_kind[kind];
  ++stats.frames;
  stats.measurements += measurements;
  stats.integration_seconds += seconds;
  statistics_.integration_seconds += seconds;
}

OccupancyRaster RecordingMapper::fusedGrid() const {
  return projectToRaster(map_, &laser_layer_, config_.fused_grid);
}

std::optional<Eigen::Isometry3d> RecordingMapper::poseOf(const FrameHeader& header) {
  if (header.stamp != 0.0) {  // 0: unstamped (files without times), never a duplicate
    const auto [last, first] =
        last_stamp_.try_emplace(header.source + '|' + header.frame_id, header.stamp);
    if (!first && last->second == header.stamp) {
      skip(header, "duplicate stamp on " + header.source,
           "frame of '" + header.frame_id + "' at t = " + std::to_string(header.stamp) +
               " s has the stamp of the one before it");
      return std::nullopt;
    }
    last->second = header.stamp;
  }
  if (header.T_map_sensor) return header.T_map_sensor;
  std::string why;
  std::optional<Eigen::Isometry3d> pose =
      poses_ == nullptr ? std::nullopt
                        : poses_->lookup(config_.frame_id, header.frame_id, header.stamp, &why);
  if (!pose) {
    skip(header, "no transform from '" + header.frame_id + "' to '" + config_.frame_id + "'",
         "at t = " + std::to_string(header.stamp) + " s: " + why);
    return std::nullopt;
  }
  if (!pose->matrix().allFinite()) {  // NaN in a pose file or a recorded transform
    skip(header, "pose of '" + header.frame_id + "' in '" + config_.frame_id + "' not finite",
         "at t = " + std::to_string(header.stamp) + " s");
    return std::nullopt;
  }
  return pose;
}

void RecordingMapper::skip(const FrameHeader& header, const std::string& reason,
                           const std::string& detail) {
  ++statistics_.by_kind[header.kind.empty() ? "unknown" : header.kind].skipped;
  if (statistics_.skipped_by_reason[reason]++ == 0) {
    statistics_.first_skip_detail[reason] = detail;
    if (warnings_ != nullptr) {
      *warnings_ << "warning: skipping frame: " << reason << " (" << detail
                 << "); further frames skipped for this reason are only counted\n";
    }
  }
}

}  // namespace occupancy_fusion
