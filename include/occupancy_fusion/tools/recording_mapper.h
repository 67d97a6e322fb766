// Maps a recording offline: the FrameConsumer that places each frame with the recording's poses
// and integrates it into one VoxelMap (and, for laser scans, a GridLayer2D), as the mapper
// nodelets do online.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <map>
#include <string>

#include "occupancy_fusion/integrators/point_cloud_integrator.h"
#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/params/parameter_source.h"
#include "occupancy_fusion/tools/recording.h"

namespace occupancy_fusion {

struct RecordingMapperConfig {
  std::string frame_id = "map";  // fixed frame the map is built in (REP-105)
  VoxelMapConfig map;
  PointCloudIntegratorConfig point_cloud;
  FusedGridConfig fused_grid;  // height band of the 2D view

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// frame_id, then the parameters of readVoxelMapConfig, readPointCloudIntegratorConfig and
// readFusedGridConfig: the same keys the point-cloud mapper nodelet and map server read.
RecordingMapperConfig readRecordingMapperConfig(const ParameterSource& source);

struct RecordingStatistics {
  std::map<std::string, std::size_t> frames_by_kind;     // integrated, e.g. "point_cloud"
  std::map<std::string, std::size_t> skipped_by_reason;  // not integrated, by short reason
  std::map<std::string, std::string> first_skip_detail;  // reason -> first full message
  std::size_t points = 0;                                // points integrated
  double integration_seconds = 0.0;                      // transform + integrate, all frames

  std::size_t framesIntegrated() const;
  std::size_t framesSkipped() const;
};

class RecordingMapper : public FrameConsumer {
 public:
  // poses must outlive the mapper. The first skip of each reason is reported on `warnings`.
  RecordingMapper(const RecordingMapperConfig& config, const PoseSource* poses,
                  std::ostream* warnings);

  void onPointCloud(const PointCloudFrame& frame) override;
  void onUnreadable(const FrameHeader& header, const std::string& why) override;

  const RecordingMapperConfig& config() const { return config_; }
  const VoxelMap& map() const { return map_; }
  // The 2D layer laser scans write (empty until a recording has scans); part of the fused view.
  const GridLayer2D& laserLayer() const { return laser_layer_; }
  // The fused 2D view over config().fused_grid's height band.
  OccupancyRaster fusedGrid() const;
  const RecordingStatistics& statistics() const { return statistics_; }

 private:
  // The sensor-to-map transform, or nullopt after counting the frame as skipped.
  std::optional<Eigen::Isometry3d> poseOf(const FrameHeader& header);
  void skip(const std::string& reason, const std::string& detail);

  RecordingMapperConfig config_;
  const PoseSource* poses_;
  std::ostream* warnings_;
  VoxelMap map_;
  GridLayer2D laser_layer_;
  PointCloudIntegrator point_cloud_integrator_;
  RecordingStatistics statistics_;
};

}  // namespace occupancy_fusion
