#include "occupancy_fusion/eval/loop_closure.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <ostream>
#include <stdexcept>
#include <string>
#include <thread>

#include "occupancy_fusion/eval/simulated_frames.h"
#include "occupancy_fusion/mapping/mapping_session.h"
#include "occupancy_fusion/sensors/carmen_log.h"
#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/laser_scanner.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/stereo_camera.h"
#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {
namespace {

constexpr double kStamp0 = 1000.0;  // s, frame 0
constexpr double kSensorMaxRange = 6.0;

// The robot's sensors: frame name and mount on base_link.
struct Mount {
  std::string frame;
  Eigen::Isometry3d T_base_sensor;
};

// A depth camera 1 m up looking ahead and 0.3 rad down; a stereo camera 1.1 m up looking
// 0.5 rad to the right and 0.2 rad down; lasers 0.25 m ahead facing forward and 0.25 m behind
// facing backward, mounted upside down.
const Mount& depthMount() {
  static const Mount mount{"depth_optical", Eigen::Translation3d(0.1, 0.0, 1.0) *
                                                Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()) *
                                                Eigen::Isometry3d(sim::opticalFrameInBody())};
  return mount;
}
const Mount& stereoMount() {
  static const Mount mount{"stereo_optical", Eigen::Translation3d(0.05, -0.1, 1.1) *
                                                 Eigen::AngleAxisd(-0.5, Eigen::Vector3d::UnitZ()) *
                                                 Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()) *
                                                 Eigen::Isometry3d(sim::opticalFrameInBody())};
  return mount;
}
const std::vector<Mount>& laserMounts() {
  static const std::vector<Mount> mounts = {
      {"laser_front", Eigen::Isometry3d(Eigen::Translation3d(0.25, 0.0, 0.3))},
      {"laser_rear", Eigen::Translation3d(-0.25, 0.0, 0.35) *
                         Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX())}};
  return mounts;
}
const Mount* mountOf(const std::string& frame) {
  if (frame == depthMount().frame) return &depthMount();
  if (frame == stereoMount().frame) return &stereoMount();
  for (const Mount& mount : laserMounts()) {
    if (frame == mount.frame) return &mount;
  }
  return nullptr;
}

const sim::PinholeCamera kCamera{160, 120, 138.6, 138.6, 79.5, 59.5};  // 60 deg wide
constexpr double kBaseline = 0.12;

// The drive: true poses, the drifted odometry and what the stand-in published.
struct Drive {
  std::vector<Eigen::Isometry3d> truth, odometry;
  sim::LocalisationTrack track;
  double rate_hz = 5.0;
  double stamp(int k) const { return kStamp0 + k / rate_hz; }
  int frameAt(double stamp) const {
    return static_cast<int>(std::lround((stamp - kStamp0) * rate_hz));
  }
};

// tf as the robot publishes it: map -> odom (the stand-in's), odom -> base_link (the odometry),
// base_link -> sensors.
class DrivePoses : public PoseSource {
 public:
  explicit DrivePoses(const Drive& drive) : drive_(drive) {}
  std::optional<Eigen::Isometry3d> lookup(const std::string& target, const std::string& frame,
                                          double stamp, std::string* why) const override {
    const int k = drive_.frameAt(stamp);
    if (k < 0 || k >= static_cast<int>(drive_.truth.size())) {
      if (why != nullptr) *why = "no pose at that stamp";
      return std::nullopt;
    }
    if (frame == "odom") return drive_.track.T_map_odom[k];  // target: map
    const Mount* mount = mountOf(frame);
    const Eigen::Isometry3d T_odom_frame =
        drive_.odometry[k] *
        (mount != nullptr ? mount->T_base_sensor : Eigen::Isometry3d::Identity());
    if (target == "odom") return T_odom_frame;
    return drive_.track.T_map_odom[k] * T_odom_frame;
  }

 private:
  const Drive& drive_;
};

// One step's frames, rendered from the true poses.
struct StepFrames {
  std::optional<DepthImageFrame> depth;
  std::vector<LaserScanFrame> scans;
  std::optional<DisparityFrame> disparity;
};

FrameHeader headerFor(const char* kind, const Mount& mount, double stamp) {
  FrameHeader header;
  header.kind = kind;
  header.source = std::string("/") + mount.frame;
  header.frame_id = mount.frame;
  header.stamp = stamp;
  return header;
}

std::vector<StepFrames> renderFrames(const sim::Scene& scene, const Drive& drive,
                                     const LoopClosureCase& setup) {
  const int frames = static_cast<int>(drive.truth.size());
  std::vector<StepFrames> result(static_cast<std::size_t>(frames));
  sim::DisparityNoise noise;
  noise.sigma_px = 0.2;
#pragma omp parallel for schedule(dynamic, 4)
  for (int k = 0; k < frames; ++k) {
    StepFrames& step = result[static_cast<std::size_t>(k)];
    const Eigen::Isometry3d& T_map_base = drive.truth[static_cast<std::size_t>(k)];
    if (setup.depth) {
      DepthImageFrame frame;
      frame.header = headerFor("depth", depthMount(), drive.stamp(k));
      frame.camera = kCamera;
      frame.depth =
          sim::renderDepth(scene, kCamera, T_map_base * depthMount().T_base_sensor, kSensorMaxRange)
              .depth;
      step.depth = std::move(frame);
    }
    if (setup.lasers) {
      for (const Mount& mount : laserMounts()) {
        LaserScanFrame frame;
        frame.header = headerFor("laser", mount, drive.stamp(k));
        sim::LaserScanner scanner;
        scanner.range_max = 20.0;
        frame.scan =
            toLaserScan(sim::renderScan(scene, scanner, T_map_base * mount.T_base_sensor, k));
        step.scans.push_back(std::move(frame));
      }
    }
    if (setup.stereo) {
      const sim::DisparityImage image =
          sim::renderDisparity(scene, kCamera, kBaseline, T_map_base * stereoMount().T_base_sensor,
                               kSensorMaxRange, noise, k);
      step.disparity = disparityFrameOf(image, kCamera, kBaseline,
                                        headerFor("disparity", stereoMount(), drive.stamp(k)));
    }
  }
  return result;
}

// The scene's ground truth at one voxel size: surface samples in the sensors' height band, and
// free-space classes of voxels (cached).
class GroundTruth {
 public:
  GroundTruth(const sim::Scene& scene, double resolution) : scene_(scene), resolution_(resolution) {
    for (const Eigen::Vector3d& sample : scene.sampleSurface(resolution)) {
      if (sample.z() < 0.1 || sample.z() > 2.0) continue;  // the floor is seen by all alike
      samples_.push_back((sample / resolution).array().floor().cast<int>());
    }
  }

  // Occupied voxels whose centre is in free space farther than a voxel diagonal from a surface.
  std::size_t falseOccupied(const std::vector<VoxelIndex>& occupied) {
    std::size_t count = 0;
    for (const VoxelIndex& voxel : occupied) {
      auto cached = is_false_.find(packKey(voxel));
      if (cached == is_false_.end()) {
        const Eigen::Vector3d centre = (voxel.cast<double>().array() + 0.5) * resolution_;
        const bool is_false = !scene_.isOccupied(centre) &&
                              scene_.distanceToSurface(centre) > std::sqrt(3.0) * resolution_;
        cached = is_false_.emplace(packKey(voxel), is_false).first;
      }
      count += cached->second ? 1 : 0;
    }
    return count;
  }

  // Of the surface samples, those with an occupied voxel within one voxel.
  double coverage(const SpatialKeySet& occupied) const {
    std::size_t covered = 0;
    for (const VoxelIndex& sample : samples_) {
      for (int d = 0; d < 27; ++d) {
        if (occupied.count(packKey(Eigen::Vector3i(
                sample + Eigen::Vector3i(d % 3 - 1, (d / 3) % 3 - 1, d / 9 - 1))))) {
          ++covered;
          break;
        }
      }
    }
    return samples_.empty() ? 0.0 : static_cast<double>(covered) / samples_.size();
  }

 private:
  const sim::Scene& scene_;
  double resolution_;
  std::vector<VoxelIndex> samples_;
  SpatialKeyMap<bool> is_false_;
};

// The occupied cells of a grid by their map-frame cell index.
SpatialKeySet occupiedCells(const OccupancyRaster& grid) {
  SpatialKeySet cells;
  const int x0 = static_cast<int>(std::lround(grid.origin_x / grid.resolution));
  const int y0 = static_cast<int>(std::lround(grid.origin_y / grid.resolution));
  for (int y = 0; y < grid.height; ++y) {
    for (int x = 0; x < grid.width; ++x) {
      if (grid.at(x, y) == OccupancyRaster::kOccupied)
        cells.insert(packKey(CellIndex(x0 + x, y0 + y)));
    }
  }
  return cells;
}

// Of a's and b's cells, those with a cell of the other within one cell.
double agreementWithinOneCell(const SpatialKeySet& a, const SpatialKeySet& b) {
  const auto matched = [](const SpatialKeySet& from, const SpatialKeySet& to) {
    std::size_t count = 0;
    for (std::uint64_t key : from) {
      const CellIndex cell = unpackKey2(key);
      for (int d = 0; d < 9; ++d) {
        if (to.count(packKey(CellIndex(cell + CellIndex(d % 3 - 1, d / 3 - 1))))) {
          ++count;
          break;
        }
      }
    }
    return count;
  };
  const std::size_t total = a.size() + b.size();
  return total == 0 ? 1.0 : static_cast<double>(matched(a, b) + matched(b, a)) / total;
}

double intersectionOverUnion(const SpatialKeySet& a, const SpatialKeySet& b) {
  std::size_t both = 0;
  for (std::uint64_t key : a) both += b.count(key);
  const std::size_t either = a.size() + b.size() - both;
  return either == 0 ? 1.0 : static_cast<double>(both) / either;
}

MappingSessionConfig sessionConfig(const LoopClosureCase& setup, LoopClosureMapping mapping) {
  MappingSessionConfig config = setup.mapping;
  config.map.resolution = setup.resolution;
  config.reanchoring.source =
      mapping == LoopClosureMapping::kPath ? ReanchoringConfig::Source::kPath
      : mapping == LoopClosureMapping::kTf ? ReanchoringConfig::Source::kTf
                                           : ReanchoringConfig::Source::kNone;
  config.reanchoring.submap_distance = setup.submap_distance;
  return config;
}

// The keyframe path as the stand-in published it at frame k.
std::vector<StampedPose> publishedPath(const Drive& drive, int k) {
  const std::vector<Eigen::Isometry3d> poses = drive.track.pathAt(k);
  std::vector<StampedPose> path;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    path.push_back({drive.stamp(drive.track.keyframe_frames[i]), poses[i]});
  }
  return path;
}

class RunEvaluator {
 public:
  RunEvaluator(const sim::Scene& scene, const LoopClosureCase& setup)
      : truth_(scene, setup.resolution) {}

  LoopClosureQuality measure(const MappingSession& session, int frame,
                             const std::map<int, SpatialKeySet>* true_grids,
                             SpatialKeySet* grid_cells) {
    LoopClosureQuality quality;
    quality.frame = frame;
    std::vector<VoxelIndex> occupied;
    SpatialKeySet occupied_keys;
    session.map().forEachOccupiedVoxel([&](const VoxelIndex& index, float) {
      occupied.push_back(index);
      occupied_keys.insert(packKey(index));
    });
    quality.occupied = occupied.size();
    quality.false_occupied = truth_.falseOccupied(occupied);
    quality.coverage = truth_.coverage(occupied_keys);
    *grid_cells = occupiedCells(session.fusedGrid());
    quality.grid_occupied = grid_cells->size();
    if (true_grids != nullptr) {
      quality.grid_iou = intersectionOverUnion(*grid_cells, true_grids->at(frame));
      quality.grid_agreement = agreementWithinOneCell(*grid_cells, true_grids->at(frame));
    } else {
      quality.grid_iou = quality.grid_agreement = 1.0;
    }
    return quality;
  }

 private:
  GroundTruth truth_;
};

bool evaluatedAt(const LoopClosureCase& setup, int k, int frames) {
  return k == frames - 1 || (k + 1) % setup.evaluate_every == 0;
}

LoopClosureRun mapOnce(const sim::Scene& scene, const LoopClosureCase& setup, const Drive& drive,
                       const std::vector<StepFrames>& frames, LoopClosureMapping mapping,
                       std::map<int, SpatialKeySet>* true_grids) {
  const bool true_poses = mapping == LoopClosureMapping::kTruePoses;
  const DrivePoses poses(drive);
  MappingSession session(sessionConfig(setup, mapping), true_poses ? nullptr : &poses, nullptr);
  RunEvaluator evaluator(scene, setup);
  LoopClosureRun run;
  run.mapping = mapping;
  const int count = static_cast<int>(frames.size());
  const auto started = std::chrono::steady_clock::now();
  const auto place = [&](FrameHeader header, int k) {
    if (true_poses) header.T_map_sensor = drive.truth[k] * mountOf(header.frame_id)->T_base_sensor;
    return header;
  };
  for (int k = 0; k < count; ++k) {
    const StepFrames& step = frames[static_cast<std::size_t>(k)];
    if (setup.real_time) {
      std::this_thread::sleep_until(started +
                                    std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::duration<double>(k / setup.rate_hz)));
    }
    if (step.depth) {
      DepthImageFrame frame = *step.depth;
      frame.header = place(frame.header, k);
      session.integrate(frame);
    }
    for (const LaserScanFrame& scan : step.scans) {
      LaserScanFrame frame = scan;
      frame.header = place(frame.header, k);
      session.integrate(frame);
    }
    if (step.disparity) {
      DisparityFrame frame = *step.disparity;
      frame.header = place(frame.header, k);
      session.integrate(frame);
    }
    if (mapping == LoopClosureMapping::kPath && drive.track.pathChangedAt(k)) {
      session.onPath(publishedPath(drive, k), drive.stamp(k));
    }
    if (!evaluatedAt(setup, k, count)) continue;
    // tf's corrections move the map on a thread of their own: measured once they have.
    if (MapReanchoring* reanchoring = session.reanchoring()) reanchoring->waitForCorrections();
    SpatialKeySet grid;
    run.curve.push_back(evaluator.measure(session, k, true_poses ? nullptr : true_grids, &grid));
    if (true_poses) (*true_grids)[k] = std::move(grid);
  }
  run.last = run.curve.back();
  run.final_grid = session.fusedGrid();
  const auto ms = [&](const char* kind) {
    const auto it = session.statistics().by_kind.find(kind);
    return it == session.statistics().by_kind.end() ? 0.0 : it->second.millisecondsPerFrame();
  };
  run.depth_ms = ms("depth");
  run.laser_ms = ms("laser");
  run.stereo_ms = ms("disparity");
  run.map_bytes = session.map().memoryBytes() + session.laserLayer().memoryBytes();
  if (const MapReanchoring* reanchoring = session.reanchoring()) {
    run.submap_bytes = reanchoring->fusion().memoryBytes() + reanchoring->keptScanBytes();
    run.submaps = reanchoring->fusion().submaps().size();
    const ReanchoringStatistics statistics = reanchoring->statistics();
    run.corrections = statistics.corrections;
    run.slowest_correction_seconds = statistics.slowest_correction_seconds;
    run.slowest_move_seconds = statistics.slowest_move_seconds;
  }
  return run;
}

}  // namespace

namespace {

// The occupied cells of a laser layer.
SpatialKeySet occupiedLayerCells(const GridLayer2D& layer) {
  SpatialKeySet cells;
  layer.forEachKnownCell([&](const CellIndex& index, float value) {
    if (layer.classify(value) == Occupancy::kOccupied) cells.insert(packKey(index));
  });
  return cells;
}

// Poses of a log's laser as the frames of its scans (the laser is the robot's body here).
class LogPoses : public PoseSource {
 public:
  LogPoses(const std::vector<Eigen::Isometry3d>& odometry,
           const std::vector<Eigen::Isometry3d>& map_to_odom, double rate_hz)
      : odometry_(odometry), map_to_odom_(map_to_odom), rate_hz_(rate_hz) {}
  std::optional<Eigen::Isometry3d> lookup(const std::string& target, const std::string& frame,
                                          double stamp, std::string* why) const override {
    const long k = std::lround((stamp - kStamp0) * rate_hz_);
    if (k < 0 || k >= static_cast<long>(odometry_.size())) {
      if (why != nullptr) *why = "no pose at that stamp";
      return std::nullopt;
    }
    if (frame == "odom") return map_to_odom_[k];
    if (target == "odom") return odometry_[k];
    return map_to_odom_[k] * odometry_[k];
  }

 private:
  const std::vector<Eigen::Isometry3d>& odometry_;
  const std::vector<Eigen::Isometry3d>& map_to_odom_;
  double rate_hz_;
};

}  // namespace

CarmenReanchoringResult evaluateCarmenReanchoring(const std::string& log_path,
                                                  const LoopClosureCase& setup, int path_every,
                                                  std::size_t max_scans) {
  setup.validate();
  if (path_every < 1) throw std::invalid_argument("path_every must be >= 1");
  CarmenReadConfig read;
  read.max_scans = max_scans;
  const std::vector<CarmenLaserScan> log = readCarmenLog(log_path, read);
  CarmenReanchoringResult result;
  result.scans = log.size();
  std::vector<Eigen::Isometry3d> truth;
  for (const CarmenLaserScan& scan : log) {
    truth.push_back(Eigen::Isometry3d(Eigen::Translation3d(scan.x, scan.y, 0.0) *
                                      Eigen::AngleAxisd(scan.theta, Eigen::Vector3d::UnitZ())));
  }
  const std::vector<Eigen::Isometry3d> odometry = sim::driftedOdometry(truth, setup.drift);
  // Keyframes a metre apart; the path (the corrected poses of those so far) every path_every
  // scans, and tf's map -> odom the correction of its newest keyframe.
  std::vector<int> keyframes;
  std::vector<Eigen::Isometry3d> map_to_odom;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    if (k > 0) result.travel += (truth[k].translation() - truth[k - 1].translation()).norm();
    result.largest_drift =
        std::max(result.largest_drift, (odometry[k].translation() - truth[k].translation()).norm());
    if (keyframes.empty() ||
        (truth[k].translation() - truth[keyframes.back()].translation()).norm() >= 1.0) {
      keyframes.push_back(static_cast<int>(k));
    }
    const bool publishes = k % static_cast<std::size_t>(path_every) == 0;
    map_to_odom.push_back(publishes || k == 0
                              ? truth[keyframes.back()] * odometry[keyframes.back()].inverse()
                              : map_to_odom.back());
  }
  const LogPoses poses(odometry, map_to_odom, setup.rate_hz);
  MappingSessionConfig config = sessionConfig(setup, LoopClosureMapping::kToday);
  MappingSession corrected(config, nullptr, nullptr), today(config, &poses, nullptr);
  config.reanchoring.source = ReanchoringConfig::Source::kPath;
  MappingSession reanchored(config, &poses, nullptr);
  std::size_t next_keyframe = 0;
  std::vector<StampedPose> path;
  for (std::size_t k = 0; k < log.size(); ++k) {
    LaserScanFrame frame;
    frame.header.kind = "laser";
    frame.header.source = "/scan";
    frame.header.frame_id = "laser";
    frame.header.stamp = kStamp0 + static_cast<double>(k) / setup.rate_hz;
    frame.scan = log[k].scan;
    today.integrate(frame);
    reanchored.integrate(frame);
    frame.header.T_map_sensor = truth[k];
    corrected.integrate(frame);
    while (next_keyframe < keyframes.size() && keyframes[next_keyframe] <= static_cast<int>(k)) {
      const int f = keyframes[next_keyframe++];
      path.push_back({kStamp0 + f / setup.rate_hz, truth[static_cast<std::size_t>(f)]});
    }
    if (k % static_cast<std::size_t>(path_every) == 0 || k + 1 == log.size()) {
      const SubmapMoveResult moved = reanchored.onPath(path, frame.header.stamp);
      result.slowest_correction_seconds =
          std::max(result.slowest_correction_seconds, moved.seconds);
    }
  }
  const SpatialKeySet truth_cells = occupiedLayerCells(corrected.laserLayer());
  const SpatialKeySet today_cells = occupiedLayerCells(today.laserLayer());
  const SpatialKeySet path_cells = occupiedLayerCells(reanchored.laserLayer());
  result.corrected_cells = truth_cells.size();
  result.iou_without_submaps = intersectionOverUnion(today_cells, truth_cells);
  result.iou_path = intersectionOverUnion(path_cells, truth_cells);
  result.within_one_cell_without_submaps = agreementWithinOneCell(today_cells, truth_cells);
  result.within_one_cell_path = agreementWithinOneCell(path_cells, truth_cells);
  return result;
}

void LoopClosureCase::validate() const {
  if (!(resolution > 0.0) || !(step > 0.0) || !(laps > 0.0) || !(rate_hz > 0.0)) {
    throw std::invalid_argument("loop closure case: resolution, step, laps and rate must be > 0");
  }
  if (evaluate_every < 1) throw std::invalid_argument("evaluate_every must be >= 1");
  if (!depth && !lasers && !stereo) throw std::invalid_argument("no sensor");
  // Narrower, the corridor would pass closer than its 1 m clearance; wider, not a floor.
  if (!(stretch.minCoeff() >= 1.0 && stretch.maxCoeff() <= 10.0)) {
    throw std::invalid_argument("loop closure case: the stretch must be within [1, 10]");
  }
  drift.validate();
  localisation.validate();
}

const char* loopClosureMappingName(LoopClosureMapping mapping) {
  switch (mapping) {
    case LoopClosureMapping::kToday:
      return "without_submaps";
    case LoopClosureMapping::kPath:
      return "reanchored_path";
    case LoopClosureMapping::kTf:
      return "reanchored_tf";
    case LoopClosureMapping::kTruePoses:
      break;
  }
  return "true_poses";
}

LoopClosureResult evaluateLoopClosure(const LoopClosureCase& setup,
                                      const std::vector<LoopClosureMapping>& mappings,
                                      std::ostream* progress) {
  setup.validate();
  LoopClosureResult result;
  result.setup = setup;
  const sim::Scene scene = sim::stretchedInPlane(sim::makeBuildingFloorScene(), setup.stretch);
  Drive drive;
  drive.rate_hz = setup.rate_hz;
  drive.truth = sim::buildingLoopPath(setup.step, setup.laps, setup.stretch);
  drive.odometry = sim::driftedOdometry(drive.truth, setup.drift);
  const Eigen::Isometry3d slip =
      Eigen::Translation3d(setup.odometry_slip.x(), setup.odometry_slip.y(), 0.0) *
      Eigen::AngleAxisd(setup.odometry_slip.z(), Eigen::Vector3d::UnitZ());
  for (std::size_t k = 1; k < drive.odometry.size(); ++k) {
    drive.odometry[k] = slip * drive.odometry[k];
  }
  drive.track = sim::runLocalisation(drive.truth, drive.odometry, setup.localisation);
  result.frames = static_cast<int>(drive.truth.size());
  result.corrections = drive.track.corrections;
  result.loop_length = setup.step * (result.frames - 1);
  if (!result.corrections.empty()) {
    const int k = result.corrections.front();
    const Eigen::Isometry3d before = drive.track.T_map_odom[k - 1] * drive.odometry[k];
    result.drift_before_closure = (before.translation() - drive.truth[k].translation()).norm();
  }
  if (progress != nullptr) {
    *progress << "loop closure: rendering " << result.frames << " frames\n";
  }
  const std::vector<StepFrames> frames = renderFrames(scene, drive, setup);
  std::map<int, SpatialKeySet> true_grids;
  std::vector<LoopClosureMapping> order = {LoopClosureMapping::kTruePoses};
  for (LoopClosureMapping mapping : mappings) {
    if (mapping != LoopClosureMapping::kTruePoses) order.push_back(mapping);
  }
  for (LoopClosureMapping mapping : order) {
    const auto start = std::chrono::steady_clock::now();
    result.runs.push_back(mapOnce(scene, setup, drive, frames, mapping, &true_grids));
    if (progress != nullptr) {
      *progress << "loop closure: mapped " << loopClosureMappingName(mapping) << " in "
                << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
                << " s\n";
    }
  }
  return result;
}

}  // namespace occupancy_fusion
