// One mapping session: the frames of every sensor kind (frames.h) placed in the map frame and
// integrated into one VoxelMap (point clouds, depth images, disparity images) and one GridLayer2D
// (laser scans) by the rules the nodelets and offline_mapper share, so that a recording mapped
// offline gives the map the nodelets build from it live:
//  - pose: with reanchoring (map_reanchoring.h) and a PoseSource, the odometry's pose of the
//    sensor placed by the active submap; else the frame's own T_map_sensor (a recording's poses,
//    or what a nodelet looked up in tf at the frame's exact stamp), else the PoseSource's pose of
//    frame_id at the stamp; a pose that is not finite is dropped;
//  - duplicate stamps: a frame stamped exactly like the last one integrated of the same sensor
//    kind and header frame_id (a republished or duplicated message) is dropped, since integrating
//    it would count the same evidence twice. The key is the sensor's frame, not the topic: a
//    frame_id names one sensor, the kind keeps a depth image and a disparity image of one optical
//    frame apart. Unstamped frames (stamp 0: files without times) are never duplicates;
//  - laser sources (costmap_2d's observation sources): a scan whose source is a source's topic
//    takes that source's integrator, max_tilt and sensor_frame; the scan plane must lie within
//    max_tilt of the map's x-y plane and a scanner mounted upside down has its scan mirrored
//    (placeScan);
//  - drops: every frame not integrated gets one reason (the kDrop* names), counted in the
//    statistics and returned as the frame's outcome.
// The session either owns its map (offline_mapper) or writes into one it is given (a nodelet's
// shared map). Not thread-safe: one caller at a time.
#pragma once

#include <chrono>
#include <cstddef>
#include <iosfwd>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"
#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"
#include "occupancy_fusion/integrators/point_cloud_integrator.h"
#include "occupancy_fusion/integrators/stereo/visibility_stereo_integrator.h"
#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/map_checkpoints.h"
#include "occupancy_fusion/map/saved_map.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/mapping/frames.h"
#include "occupancy_fusion/mapping/map_reanchoring.h"
#include "occupancy_fusion/params/laser_config_reader.h"
#include "occupancy_fusion/params/parameter_source.h"

namespace occupancy_fusion {

struct MappingSessionConfig {
  std::string frame_id = "map";  // fixed frame the map is built in (REP-105)
  VoxelMapConfig map;            // of the map the session owns (a given map keeps its own)
  PointCloudIntegratorConfig point_cloud;
  PyramidDepthConfig depth;          // depth images (Pirker et al.)
  VisibilityStereoConfig stereo;     // disparity images (Schauwecker & Zell)
  PolarLaserIntegratorConfig laser;  // laser scans into the 2D layer (Yguel et al.)
  double laser_max_tilt = 0.1;       // rad, largest tilt of a scan plane from the map's x-y plane
  // Per-scanner settings (the laser mapper's observation sources): a scan whose source is a
  // source's topic uses that source's integrator, max_tilt and sensor_frame; other scans use
  // `laser` and laser_max_tilt.
  std::vector<LaserSourceConfig> laser_sources;
  FusedGridConfig fused_grid;  // height band of the 2D view
  // Submaps placed by the localisation's corrections (map_reanchoring.h); off by default.
  ReanchoringConfig reanchoring;

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// frame_id, then the parameters of readVoxelMapConfig, readPointCloudIntegratorConfig,
// readPyramidDepthConfig (depth/...), readVisibilityStereoConfig (stereo/...),
// readPolarLaserIntegratorConfig under laser/ (and laser/max_tilt), readLaserSourceConfigs where
// observation_sources is given, readFusedGridConfig and readReanchoringConfig: the same keys the
// mapper nodelets and map server read, so their YAML files can be merged.
MappingSessionConfig readMappingSessionConfig(const ParameterSource& source);

// A scan placed in the x-y plane of a frame in which the scanner's pose is T_frame_sensor: the
// scanner's planar pose, and the scan as seen in that frame (mirrored when the scanner is mounted
// upside down, so that it sweeps clockwise there; REP-103). Throws std::invalid_argument when the
// pose is not finite or the scan plane tilts more than max_tilt (rad) from the frame's x-y plane.
// The one rule for the map's layer (MappingSession) and a vehicle-frame grid (LaserMapper).
struct PlacedScan {
  Pose2D sensor;
  LaserScan scan;
};
PlacedScan placeScan(const LaserScan& scan, const Eigen::Isometry3d& T_frame_sensor,
                     double max_tilt);

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

struct MappingStatistics {
  std::map<std::string, std::size_t> frames_by_kind;     // integrated, e.g. "point_cloud"
  std::map<std::string, std::size_t> skipped_by_reason;  // not integrated, by short reason
  std::map<std::string, std::string> first_skip_detail;  // reason -> first full message
  std::map<std::string, SensorKindStatistics> by_kind;   // "point_cloud", "depth", ...
  std::size_t points = 0;                                // point-cloud points integrated
  double integration_seconds = 0.0;                      // transform + integrate, all frames

  std::size_t framesIntegrated() const;
  std::size_t framesSkipped() const;
};

// The outcome of one frame: integrated, or dropped for one of MappingSession's kDrop* reasons
// (`detail` says which frame and why, for a log line).
struct FrameOutcome {
  bool integrated = false;
  const char* drop = nullptr;
  std::string detail;
};

class MappingSession : public FrameConsumer {
 public:
  // Why a frame was not integrated (the statistics' reasons add the source and frame).
  static constexpr const char* kDropDuplicateStamp = "duplicate stamp";
  static constexpr const char* kDropNoPose = "no pose";
  static constexpr const char* kDropPoseNotFinite = "pose not finite";
  static constexpr const char* kDropTiltedScanPlane = "scan plane tilted";
  static constexpr const char* kDropBadFrame = "bad frame";     // fails its own checks
  static constexpr const char* kDropUnreadable = "unreadable";  // its message could not be read

  // A session with a map of its own, made from config.map (offline_mapper). `poses` (may be null:
  // then only frames with T_map_sensor are placed) must outlive the session. The first drop of
  // each reason is reported on `warnings` (may be null).
  MappingSession(const MappingSessionConfig& config, const PoseSource* poses,
                 std::ostream* warnings);
  // A session writing into `voxels` and `layer` (a nodelet's shared map), which must outlive it;
  // config.map is not used.
  MappingSession(const MappingSessionConfig& config, VoxelMap* voxels, GridLayer2D* layer,
                 const PoseSource* poses, std::ostream* warnings);

  // Later frames take their poses from `poses` (when a run moves on to the next recording).
  void setPoseSource(const PoseSource* poses) { poses_ = poses; }
  // With config.reanchoring enabled: a session with its own map reanchors it itself; one given
  // its map is given the map's reanchoring here (shared by every session writing that map; must
  // outlive the session). With a PoseSource every frame is placed by odometry through it (what a
  // frame's T_map_sensor says is not used); without one, frames keep the pose they carry.
  void setReanchoring(MapReanchoring* reanchoring) { reanchoring_ = reanchoring; }
  MapReanchoring* reanchoring() { return reanchoring_; }
  const MapReanchoring* reanchoring() const { return reanchoring_; }
  // The SLAM system's optimised keyframes (reanchoring/source: path): every submap re-placed.
  // Nothing without reanchoring by path.
  SubmapMoveResult onPath(const std::vector<StampedPose>& path, double stamp);

  FrameOutcome integrate(const PointCloudFrame& frame);
  FrameOutcome integrate(const DepthImageFrame& frame);
  FrameOutcome integrate(const DisparityFrame& frame);
  FrameOutcome integrate(const LaserScanFrame& frame);

  // FrameConsumer: the same, for readers.
  void onPointCloud(const PointCloudFrame& frame) override { integrate(frame); }
  void onDepthImage(const DepthImageFrame& frame) override { integrate(frame); }
  void onDisparityImage(const DisparityFrame& frame) override { integrate(frame); }
  void onLaserScan(const LaserScanFrame& frame) override { integrate(frame); }
  void onUnreadable(const FrameHeader& header, const std::string& why) override;
  void onTrajectory(const std::vector<StampedPose>& keyframes, double stamp) override {
    onPath(keyframes, stamp);
  }

  // The laser source a scan's header belongs to (nullptr: the default `laser` settings), the
  // sensor frame its pose is looked up for (the source's sensor_frame, else the header's) and its
  // largest tilt: for callers that place the scan in other frames too.
  const LaserSourceConfig* laserSourceOf(const FrameHeader& header) const;
  std::string sensorFrameOf(const FrameHeader& header) const;
  double maxTiltOf(const FrameHeader& header) const;

  // Forgets the stamps of the frames integrated so far (time jumped back: a looped recording
  // starts over, and its frames are no duplicates).
  void forgetStamps() { last_stamp_.clear(); }

  const MappingSessionConfig& config() const { return config_; }
  const VoxelMap& map() const { return *voxels_; }
  // A checkpoint of the map and its laser layer to the map's store
  // (VoxelMapConfig::checkpoint_period), stamped `stamp`; a session given its map and layer
  // leaves checkpoints to their owner (written: false).
  // With reanchoring the submaps go into the same checkpoint (submap_files.h).
  CheckpointResult checkpoint(const std::string& stamp);
  // Laser layer tiles resumed from the store's checkpoint with the map.
  std::size_t resumedLayerTiles() const { return checkpoints_ ? checkpoints_->resumedTiles() : 0; }
  // The 2D layer laser scans write (empty until a recording has scans); part of the fused view.
  const GridLayer2D& laserLayer() const { return *layer_; }
  // The fused 2D view over config().fused_grid's height band.
  OccupancyRaster fusedGrid() const;
  const MappingStatistics& statistics() const { return statistics_; }
  // What the integrator of the last integrated frame of each kind reported.
  const IntegrationStats& lastPointCloudStats() const { return last_point_cloud_; }
  const DepthIntegrationStats& lastDepthStats() const { return last_depth_; }
  const StereoIntegrationStats& lastStereoStats() const { return last_stereo_; }

  // Starts from a saved map (a .ot or .bt and the laser layer files beside it; see saved_map.h),
  // before the first frame. Throws std::runtime_error naming the file and what is wrong.
  // With reanchoring, the submaps saved beside it (<prefix>.submaps, submap_files.h) come back
  // too; without that file the resumed map is fixed where it is.
  ResumedMap resumeFrom(const std::string& path);

 private:
  // The frame's pose in the map frame (looked up for `sensor_frame`), or a drop: a duplicate
  // stamp, no pose, a pose that is not finite.
  // With reanchoring, *lease holds the frame's submap until the caller's write is done.
  FrameOutcome place(const FrameHeader& header, const std::string& sensor_frame,
                     Eigen::Isometry3d* map_T_sensor,
                     std::optional<MapReanchoring::PlacedFrame>* lease);
  FrameOutcome drop(const FrameHeader& header, const char* why, const std::string& reason,
                    const std::string& detail);
  void resumeSubmaps();  // those of the checkpoint the owned map resumed
  // Counts an integrated frame of `kind` that started at `start` and remembers its stamp.
  FrameOutcome integrated(const FrameHeader& header, std::size_t measurements,
                          std::chrono::steady_clock::time_point start);

  MappingSessionConfig config_;
  const PoseSource* poses_;
  std::ostream* warnings_;
  std::unique_ptr<VoxelMap> own_voxels_;
  std::unique_ptr<GridLayer2D> own_layer_;
  std::unique_ptr<MapCheckpoints> checkpoints_;      // when the session owns the map and layer
  std::unique_ptr<MapReanchoring> own_reanchoring_;  // the same, with reanchoring
  MapReanchoring* reanchoring_ = nullptr;
  VoxelMap* voxels_;
  GridLayer2D* layer_;
  // Made on the first frame of their kind: a nodelet's session maps one kind only.
  std::unique_ptr<PointCloudIntegrator> point_cloud_integrator_;
  std::unique_ptr<PyramidDepthIntegrator> depth_integrator_;
  std::unique_ptr<VisibilityStereoIntegrator> stereo_integrator_;
  std::unique_ptr<PolarLaserIntegrator> laser_integrator_;
  // One integrator per configured laser source (each keeps its own exact-overlay cache).
  std::vector<std::unique_ptr<PolarLaserIntegrator>> source_integrators_;
  MappingStatistics statistics_;
  IntegrationStats last_point_cloud_;
  DepthIntegrationStats last_depth_;
  StereoIntegrationStats last_stereo_;
  std::map<std::string, double> last_stamp_;  // by sensor kind and header frame_id
};

}  // namespace occupancy_fusion
