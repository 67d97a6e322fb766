#include "occupancy_fusion/tools/recording_mapper.h"

#include <chrono>
#include <ostream>
#include <stdexcept>

#include "occupancy_fusion/params/config_readers.h"

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
  fused_grid.validate();
}

RecordingMapperConfig readRecordingMapperConfig(const ParameterSource& source) {
  RecordingMapperConfig config;
  source.get("frame_id", &config.frame_id);
  config.map = readVoxelMapConfig(source);
  config.point_cloud = readPointCloudIntegratorConfig(source);
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
      point_cloud_integrator_(config.point_cloud) {
  config_.validate();
}

void RecordingMapper::onPointCloud(const PointCloudFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  const std::optional<Eigen::Isometry3d> map_T_sensor = poseOf(frame.header);
  if (!map_T_sensor) return;
  point_cloud_integrator_.integrate(transformed(frame.points, *map_T_sensor),
                                    map_T_sensor->translation(), &map_);
  ++statistics_.frames_by_kind["point_cloud"];
  statistics_.points += frame.points.size();
  statistics_.integration_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void RecordingMapper::onUnreadable(const FrameHeader& header, const std::string& why) {
  skip("unreadable message on " + header.source, why);
}

OccupancyRaster RecordingMapper::fusedGrid() const {
  return projectToRaster(map_, &laser_layer_, config_.fused_grid);
}

std::optional<Eigen::Isometry3d> RecordingMapper::poseOf(const FrameHeader& header) {
  std::string why;
  std::optional<Eigen::Isometry3d> pose =
      poses_->lookup(config_.frame_id, header.frame_id, header.stamp, &why);
  if (!pose) {
    skip("no transform from '" + header.frame_id + "' to '" + config_.frame_id + "'",
         "at t = " + std::to_string(header.stamp) + " s: " + why);
  }
  return pose;
}

void RecordingMapper::skip(const std::string& reason, const std::string& detail) {
  if (statistics_.skipped_by_reason[reason]++ == 0) {
    statistics_.first_skip_detail[reason] = detail;
    if (warnings_ != nullptr) {
      *warnings_ << "warning: skipping frame: " << reason << " (" << detail
                 << "); further frames skipped for this reason are only counted\n";
    }
  }
}

}  // namespace occupancy_fusion
