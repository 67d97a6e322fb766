// Maps a recording offline: the FrameConsumer that places each frame with the recording's poses
// and integrates it into one VoxelMap (point clouds, depth images, disparity images) and one
// GridLayer2D (laser scans), as the mapper nodelets do online.
#pragma once

#include <chrono>
#include <cstddef>
#include <iosfwd>
#include <map>
#include <memory>
#include <string>

#include "occupancy_fusion/integrators/point_cloud_integrator.h"
#include "occupancy_fusion/integrators/polar_laser_integrator.h"
#include "occupancy_fusion/integrators/pyramid_depth_integrator.h"
#include "occupancy_fusion/integrators/visibility_stereo_integrator.h"
#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/saved_map.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/params/laser_config_reader.h"
#include "occupancy_fusion/params/parameter_source.h"
#include "occupancy_fusion/tools/recording.h"

namespace occupancy_fusion {

struct RecordingMapperConfig {
  std::string frame_id = "map";  // fixed frame the map is built in (REP-105)
  VoxelMapConfig map;
  PointCloudIntegratorConfig point_cloud;
  PyramidDepthConfig depth;          // depth images (Pirker et al.)
  VisibilityStereoConfig stereo;     // disparity images (Schauwecker & Zell)
  PolarLaserIntegratorConfig laser;  // laser scans into the 2D layer (Yguel et al.)
  double laser_max_tilt = 0.1;       // rad, largest tilt of a scan plane from the map's x-y plane
  // Per-scanner settings (costmap_2d-style observation sources of the laser mapper): a scan
  // whose topic is a source's topic uses that source's integrator, max_tilt and sensor_frame;
  // other scans use `laser` and laser_max_tilt.
  std::vector<LaserSourceConfig> laser_sources;
  FusedGridConfig fused_grid;  // height band of the 2D view

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// frame_id, then the parameters of readVoxelMapConfig, readPointCloudIntegratorConfig,
// readPyramidDepthConfig (depth/...), readVisibilityStereoConfig (stereo/...),
// readPolarLaserIntegratorConfig under laser/ (and laser/max_tilt), readLaserSourceConfigs where
// observation_sources is given, and readFusedGridConfig: the
// same keys the mapper nodelets and map server read, so their YAML files can be merged.
RecordingMapperConfig readRecordingMapperConfig(const ParameterSource& source);

// What happened to the frames of one sensor kind.
struct SensorKindStatistics {
  std::size_t frames = 0;            // integrated
  std::size_t skipped = 0;           // not integrated (no pose, unreadable, ...)
  std::size_t measurements = 0;      // points, pixels or beams of the integrated frames
  double integration_seconds = 0.0;  // pose lookup + integration of the integrated frames

  double millisecondsPerFrame() const {
    return frames > 0 ? 1e3 * integration_seconds / frames : 0;
  }
};

struct RecordingStatistics {
  std::map<std::string, std::size_t> frames_by_kind;     // integrated, e.g. "point_cloud"
  std::map<std::string, std::size_t> skipped_by_reason;  // not integrated, by short reason
  std::map<std::string, std::string> first_skip_detail;  // reason -> first full message
  std::map<std::string, SensorKindStatistics> by_kind;   // "point_cloud", "depth", ...
  std::size_t points = 0;                                // point-cloud points integrated
  double integration_seconds = 0.0;                      // transform + integrate, all frames

  std::size_t framesIntegrated() const;
  std::size_t framesSkipped() const;
};

class RecordingMapper : public FrameConsumer {
 public:
  // poses must outlive the mapper. The first skip of each reason is reported on `warnings`.
  RecordingMapper(const RecordingMapperConfig& config, const PoseSource* poses,
                  std::ostream* warnings);

  // Later frames take their poses from `poses` (when a run moves on to the next recording).
  void setPoseSource(const PoseSource* poses) { poses_ = poses; }

  void onPointCloud(const PointCloudFrame& frame) override;
  void onDepthImage(const DepthImageFrame& frame) override;
  void onDisparityImage(const DisparityFrame& frame) override;
  void onLaserScan(const LaserScanFrame& frame) override;
  void onUnreadable(const FrameHeader& header, const std::string& why) override;

  const RecordingMapperConfig& config() const { return config_; }
  const VoxelMap& map() const { return map_; }
  // The 2D layer laser scans write (empty until a recording has scans); part of the fused view.
  const GridLayer2D& laserLayer() const { return laser_layer_; }
  // The fused 2D view over config().fused_grid's height band.
  OccupancyRaster fusedGrid() const;
  const RecordingStatistics& statistics() const { return statistics_; }

  // Starts from a saved map (a .ot or .bt and the laser layer files beside it; see saved_map.h),
  // before the first frame. Throws std::runtime_error naming the file and what is wrong.
  ResumedMap resumeFrom(const std::string& path) {
    return resumeSavedMap(path, &map_, &laser_layer_);
  }

 private:
  // The sensor-to-map transform, or nullopt after counting the frame as skipped (also a frame
  // with the stamp of the last one taken from the same source and sensor frame: a duplicate,
  // whose evidence would be counted twice, as the nodelets drop it).
  std::optional<Eigen::Isometry3d> poseOf(const FrameHeader& header);
  void skip(const FrameHeader& header, const std::string& reason, const std::string& detail);
  // Counts an integrated frame of `kind` that started at `start`.
  void countIntegrated(const std::string& kind, std::size_t measurements,
                       std::chrono::steady_clock::time_point start);

  RecordingMapperConfig config_;
  const PoseSource* poses_;
  std::ostream* warnings_;
  VoxelMap map_;
  GridLayer2D laser_layer_;
  PointCloudIntegrator point_cloud_integrator_;
  PyramidDepthIntegrator depth_integrator_;
  VisibilityStereoIntegrator stereo_integrator_;
  PolarLaserIntegrator laser_integrator_;
  // One integrator per configured laser source (each keeps its own exact-overlay cache).
  std::vector<std::unique_ptr<PolarLaserIntegrator>> source_integrators_;
  RecordingStatistics statistics_;
  std::map<std::string, double> last_stamp_;  // by source and sensor frame
};

}  // namespace occupancy_fusion
