// A map that follows its localisation's corrections (REP-105: map -> odom -> base_link): frames
// are placed by odometry into submaps (submap_fusion.h), and the submaps are placed in the map by
// the corrections, from one of
//  - `tf`: map -> odom as tf gives it at each frame's stamp. A localisation publishes the
//    correction that is right now; when it jumps (by more than min_shift, else a voxel), it is
//    taken as right at its stamp, and the odometry's drift as grown evenly since the previous jump:
//    each submap of that stretch is placed by the correction interpolated at its time (the same
//    rule as a path of two keyframes, trajectory_corrections.h), older submaps stay. What AMCL,
//    slam_toolbox and cartographer publish.
//  - `path`: the SLAM system's optimised keyframes, T_map_base at their stamps (a nav_msgs/Path
//    republished whenever the graph changes: LIO-SAM's mapping/path, RTAB-Map's mapPath), given
//    to applyPath(); every submap is placed by the keyframes of its own time span
//    (trajectory_corrections.h).
// With map -> odom the identity and never changing, the map is the one mapped without submaps,
// voxel for voxel. Thread safety: every public member function may be called from any thread
// (several mappers share one map and its reanchoring).
#pragma once

#include <Eigen/Geometry>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <istream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <thread>
#include <vector>

#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"
#include "occupancy_fusion/mapping/frames.h"
#include "occupancy_fusion/mapping/submap_fusion.h"
#include "occupancy_fusion/mapping/trajectory_corrections.h"
#include "occupancy_fusion/params/parameter_source.h"

namespace occupancy_fusion {

class SubmapSpillFile;  // mapping/submap_spill_file.h

struct ReanchoringConfig {
  enum class Source { kNone, kTf, kPath };
  // reanchoring/source: "none" (frames placed by map -> sensor; the map never moves), "tf" or
  // "path" (above).
  Source source = Source::kNone;
  std::string odom_frame = "odom";       // reanchoring/odom_frame
  std::string base_frame = "base_link";  // reanchoring/base_frame: the body the path's poses are of
  // A new submap after the robot travelled this far (m) or this long (s, 0: no limit) since the
  // active one began (reanchoring/submap_distance, reanchoring/submap_seconds).
  double submap_distance = 3.0;
  double submap_seconds = 60.0;
  // reanchoring/min_shift, reanchoring/max_memory_mb (the submaps' changes in memory; beyond, the
  // oldest go to a temporary file beside the map's spill_folder, or the system's temporary folder)
  SubmapFusionConfig fusion;
  TrajectoryCorrectionConfig trajectory;  // reanchoring/max_odometry_gap
  // The laser scans kept to draw moved submaps again, in memory at most (0: unbounded); the
  // oldest submaps' go to a temporary file beyond it. reanchoring/max_memory_mb splits between
  // the submaps' changes (fusion.max_memory_bytes, three quarters) and these (a quarter).
  std::size_t max_scan_bytes = 0;
  // A laser scan taken within these (m, rad, s) of the last one kept of its laser in the same
  // submap is not kept: that one is drawn with a weight one greater. A standing robot keeps a
  // scan a second. Farther apart, scans differ where a weighted one would not stand for them
  // (thinned to one kept scan every 0.3 m, the 60 x 40 m floor's laser IoU fell 0.94 -> 0.90).
  double keep_scan_distance = 0.05;
  double keep_scan_angle = 0.05;
  double keep_scan_seconds = 1.0;

  bool enabled() const { return source != Source::kNone; }
  void validate() const;  // throws std::invalid_argument naming the bad field
};

// The reanchoring/... keys above; throws std::invalid_argument for a bad value.
ReanchoringConfig readReanchoringConfig(const ParameterSource& source);
const char* sourceName(ReanchoringConfig::Source source);

// What the corrections did so far.
struct ReanchoringStatistics {
  std::size_t corrections = 0;       // paths and map -> odom jumps that moved a submap
  std::size_t submaps_moved = 0;     // in all
  std::size_t blocks_rewritten = 0;  // blocks and tiles of the fused map, in all
  double last_correction_seconds = 0.0;
  double slowest_correction_seconds = 0.0;  // until the laser layer was drawn again as well
  double slowest_move_seconds = 0.0;        // until the map was re-sampled at the new places
  double last_correction_stamp = 0.0;       // s, the frame or path that brought it
  std::size_t path_keyframes = 0;           // of the last path, and those matched with the odometry
  std::size_t path_corrections = 0;
  std::size_t map_to_odom_jumps = 0;  // tf's map -> odom changes beyond min_shift (a voxel)
};

class MapReanchoring : private LayerDrawer {
 public:
  // Watches `map` and `layer` (layer may be null; both must outlive this).
  MapReanchoring(VoxelMap* map, GridLayer2D* layer, const ReanchoringConfig& config);
  ~MapReanchoring() override;
  MapReanchoring(const MapReanchoring&) = delete;
  MapReanchoring& operator=(const MapReanchoring&) = delete;

  // A frame placed in the map: hold `lease` until its write is done.
  struct PlacedFrame {
    SubmapFusion::FrameLease lease;
    Eigen::Isometry3d T_map_sensor;
    Eigen::Isometry3d T_odom_sensor;
  };
  // Places a frame of `sensor_frame` at `stamp` by the odometry (odom -> sensor_frame) and the
  // active submap's placement; starts a new submap when the robot went far enough; with `tf`
  // first follows map -> odom (map_frame -> odom_frame) at the stamp. nullopt, with the reason
  // in *why, when a transform is missing.
  std::optional<PlacedFrame> placeFrame(const PoseSource& poses, const std::string& map_frame,
                                        const std::string& sensor_frame, double stamp,
                                        std::string* why);
  // A laser scan integrated into submap `submap`'s part of the layer, kept so that the submap's
  // cells can be drawn anew, each scan at its own correction, when the submap moves (instead of
  // re-sampled: thin walls then land where a map made with the corrected poses has them).
  // `integrator`: the session's, whose settings a copy of its own uses. A scan of `sensor` taken
  // about where its last kept one of the same submap was (config's keep_scan_*) is not kept: that
  // one is drawn with a weight one greater.
  void keepScan(int submap, const std::string& sensor, const PolarLaserIntegrator& integrator,
                double stamp, const Eigen::Isometry3d& T_odom_sensor, const LaserScan& scan,
                double max_tilt);
  std::size_t keptScanBytes() const;     // in memory
  std::size_t spilledScanBytes() const;  // in the temporary file

  // The SLAM system's keyframes (T_map_base of base_frame), the whole optimised path.
  SubmapMoveResult applyPath(const std::vector<StampedPose>& path, double stamp = 0.0);
  // map -> odom at `stamp`, the submaps moved before it returns (placeFrame does the same with
  // tf's, but moves them on a thread of its own: waitForCorrections()). For callers that have
  // map -> odom otherwise.
  SubmapMoveResult applyMapToOdom(const Eigen::Isometry3d& T_map_odom, double stamp = 0.0);
  // Returns once the corrections placeFrame heard so far have moved the map.
  void waitForCorrections();

  const ReanchoringConfig& config() const { return config_; }
  SubmapFusion& fusion() { return fusion_; }
  const SubmapFusion& fusion() const { return fusion_; }
  ReanchoringStatistics statistics() const;
  std::size_t odometryPoses() const;
  // The submaps, the odometry and the corrections heard, as bytes (submap_files.h), and back once
  // the map holds what was saved with them. restore throws std::runtime_error for bytes that are
  // not such a save (the map's contents then stay where they are, as one fixed submap).
  void save(std::ostream& out) { saveThen(out, {}); }
  void restore(std::istream& in);
  // save, then `then` before any frame is written into the next submap: a checkpoint of the map
  // that holds what the bytes add up to.
  void saveThen(std::ostream& out, const std::function<void()>& then);

  // Forgets the submaps, the odometry and empties the map (the map server's reset).
  void reset();

 private:
  void countCorrection(const SubmapMoveResult& result, double stamp);
  // tf's map -> odom taken in: the corrections so far when it jumped.
  std::optional<std::vector<StampedPose>> noteMapToOdom(const Eigen::Isometry3d& T_map_odom,
                                                        double stamp);
  // placeFrame's: the next frames go into a new submap at T_map_odom; the submaps are moved by
  // correctInTurn(), one correction after another on worker_.
  void followMapToOdom(const Eigen::Isometry3d& T_map_odom, double stamp);
  void correctInTurn();
  void stopCorrecting();  // drops a pending correction, waits for a running one
  void startSubmapIfDue(const Eigen::Vector3d& position, double stamp);
  // A submap due while a correction rebuilds the map runs on up to this many submap_distance.
  static constexpr double kDeferredDistance = 1.25;

  bool draw(int id, const Eigen::Isometry3d& T_map_odom, GridLayer2D* layer) override;

  struct KeptScan {
    std::size_t integrator = 0;  // in integrators_
    double stamp = 0.0;
    Eigen::Isometry3d T_odom_sensor;
    LaserScan scan;
    double max_tilt = 0.0;
    float weight = 1.0f;  // the scans it stands for: itself and those taken about where it was
    std::size_t bytes() const { return sizeof(KeptScan) + scan.ranges.size() * sizeof(float); }
  };

  ReanchoringConfig config_;
  SubmapFusion fusion_;
  double jump_shift_;     // m: a change of tf's map -> odom that counts as a jump
  std::uint64_t serial_;  // this reanchoring among all made in the process
  // Guards the kept scans and their integrators (draw runs on the correcting thread).
  mutable std::mutex scans_mutex_;
  std::map<int, std::vector<KeptScan>> kept_scans_;  // by submap
  std::size_t kept_scan_bytes_ = 0;
  // Under max_scan_bytes the oldest submaps' scans, by submap: offset and size in scan_spill_.
  std::map<int, std::pair<std::uint64_t, std::uint32_t>> spilled_scans_;
  std::unique_ptr<SubmapSpillFile> scan_spill_;
  void spillOldScansLocked(int active_submap);
  KeptScan* lastKeptLocked(const std::string& sensor, int submap);
  std::vector<KeptScan> scansOfLocked(int submap) const;  // spilled, then in memory
  std::vector<KeptScan> spilledScansLocked(int submap) const;
  // Copies of the sessions' integrators, by the session's one they copy.
  std::vector<std::pair<const PolarLaserIntegrator*, std::unique_ptr<PolarLaserIntegrator>>>
      integrators_;
  // By sensor frame, the last scan kept: its submap and its index there.
  struct LastKept {
    int submap = -1;
    std::size_t index = 0;
  };
  std::map<std::string, LastKept> last_kept_;
  // The corrections of the last path or tf's jumps: where each kept scan is drawn.
  std::vector<StampedPose> corrections_;
  mutable std::mutex mutex_;  // the odometry, the submap's start and the statistics
  OdometryTrack odometry_;
  std::vector<StampedPose> map_to_odom_;  // tf's map -> odom: the first, then at each jump
  bool started_ = false;
  // The correcting thread (tf): the newest correction not applied yet, and whether one runs.
  struct PendingCorrection {
    std::vector<StampedPose> corrections;
    Eigen::Isometry3d next;  // where the frames are written from then on
    double stamp = 0.0;
  };
  std::mutex worker_mutex_;
  std::condition_variable worker_wake_, worker_idle_;
  std::optional<PendingCorrection> pending_;
  bool correcting_ = false, stopping_ = false;
  std::thread worker_;
  Eigen::Vector3d submap_start_position_ = Eigen::Vector3d::Zero();
  double submap_start_stamp_ = 0.0;
  ReanchoringStatistics statistics_;
};

}  // namespace occupancy_fusion
