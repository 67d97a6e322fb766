// A session that follows its localisation's corrections (map_reanchoring.h): a robot circles the
// simulator's room twice with a depth camera and a laser while its odometry drifts; the map
// placed by the corrections (tf's map -> odom, or a path of keyframes) is compared with the map
// of the true poses and with the map a session without submaps makes of the same frames.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "occupancy_fusion/mapping/map_saving.h"
#include "occupancy_fusion/mapping/mapping_session.h"
#include "occupancy_fusion/mapping/submap_files.h"
#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/laser_scanner.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/trajectory.h"

#include "../../common/test_folder.h"

namespace occupancy_fusion {
namespace {

constexpr int kFrames = 80;
constexpr int kCorrectionEvery = 20;
constexpr double kStamp0 = 100.0;

Eigen::Isometry3d planar(double x, double y, double yaw) {
  return Eigen::Isometry3d(Eigen::Translation3d(x, y, 0.0) *
                           Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
}

const Eigen::Isometry3d kBaseCamera = Eigen::Translation3d(0.1, 0.0, 1.0) *
                                      Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()) *
                                      Eigen::Isometry3d(sim::opticalFrameInBody());
const Eigen::Isometry3d kBaseLaser(Eigen::Translation3d(0.2, 0.0, 0.3));

// Two turns on a circle of 1 m about the room's free centre, facing outward, and an odometry
// that reads each step 3 % long and turns 0.012 rad more than the robot (0.75 rad a turn).
struct Drive {
  std::vector<Eigen::Isometry3d> truth, odometry, map_to_odom;
  Drive() {
    Eigen::Isometry3d odom = Eigen::Isometry3d::Identity();
    for (int k = 0; k < kFrames; ++k) {
      const double angle = 4.0 * M_PI * k / kFrames;
      truth.push_back(planar(std::cos(angle), std::sin(angle), angle));
      if (k == 0) odom = truth[0];
      if (k > 0) {
        Eigen::Isometry3d step = truth[k - 1].inverse() * truth[k];
        step.translation() *= 1.03;
        odom = odom * step * planar(0, 0, 0.012);
      }
      odometry.push_back(odom);
      // The localisation is right every kCorrectionEvery frames and at the last one, and holds its
      // correction between.
      const bool corrects = k % kCorrectionEvery == 0 || k == kFrames - 1;
      map_to_odom.push_back(corrects ? truth[k] * odom.inverse() : map_to_odom.back());
    }
  }
  double stamp(int k) const { return kStamp0 + k; }
};

// tf as a robot's: map -> odom -> base_link -> {camera, laser}, each at the frame's stamp.
class DrivePoses : public PoseSource {
 public:
  explicit DrivePoses(const Drive& drive) : drive_(drive) {}
  std::optional<Eigen::Isometry3d> lookup(const std::string& target, const std::string& frame,
                                          double stamp, std::string* why) const override {
    const int k = static_cast<int>(std::lround(stamp - kStamp0));
    if (k < 0 || k >= kFrames) {
      *why = "no pose at that stamp";
      return std::nullopt;
    }
    const Eigen::Isometry3d mount = frame == "camera"  ? kBaseCamera
                                    : frame == "laser" ? kBaseLaser
                                                       : Eigen::Isometry3d::Identity();
    const Eigen::Isometry3d T_odom_frame = drive_.odometry[k] * mount;
    if (target == "odom") return T_odom_frame;
    if (frame == "odom") return drive_.map_to_odom[k];
    return drive_.map_to_odom[k] * T_odom_frame;
  }

 private:
  const Drive& drive_;
};

MappingSessionConfig sessionConfig(ReanchoringConfig::Source source) {
  MappingSessionConfig config;
  config.map.resolution = 0.1;
  config.reanchoring.source = source;
  config.reanchoring.submap_distance = 1.0;
  return config;
}

// The frames of step k, rendered from the true poses (once: every session maps the same ones).
struct StepFrames {
  PointCloudFrame cloud;
  LaserScanFrame scan;
};
const StepFrames& stepFrames(const Drive& drive, int k) {
  static const std::vector<StepFrames> frames = [&drive] {
    const sim::Scene scene = sim::makeRoomScene();
    const sim::PinholeCamera camera{80, 60, 69.3, 69.3, 39.5, 29.5};
    std::vector<StepFrames> result(kFrames);
    for (int i = 0; i < kFrames; ++i) {
      StepFrames& step = result[static_cast<std::size_t>(i)];
      step.cloud.header = {"point_cloud", "/cloud", "camera", drive.stamp(i), std::nullopt};
      for (const Eigen::Vector3d& point :
           sim::renderPointCloud(scene, camera, drive.truth[i] * kBaseCamera, 5.0)) {
        step.cloud.points.push_back(point.cast<float>());
      }
      step.scan.header = {"laser", "/scan", "laser", drive.stamp(i), std::nullopt};
      step.scan.scan =
          toLaserScan(sim::renderScan(scene, sim::LaserScanner(), drive.truth[i] * kBaseLaser));
    }
    return result;
  }();
  return frames[static_cast<std::size_t>(k)];
}

// The frames of step k into `session`, placed by tf, or by the truth when `truth`.
void feed(const Drive& drive, int k, bool truth, MappingSession* session) {
  PointCloudFrame cloud = stepFrames(drive, k).cloud;
  LaserScanFrame scan = stepFrames(drive, k).scan;
  if (truth) {
    cloud.header.T_map_sensor = drive.truth[k] * kBaseCamera;
    scan.header.T_map_sensor = drive.truth[k] * kBaseLaser;
  }
  EXPECT_TRUE(session->integrate(cloud).integrated);
  EXPECT_TRUE(session->integrate(scan).integrated);
}

// Of the occupied cells of `from`, the share with an occupied cell of `to` within one cell.
double matchedVoxels(const VoxelMap& from, const VoxelMap& to) {
  std::size_t count = 0, matched = 0;
  from.forEachOccupiedVoxel([&](const VoxelIndex& index, float) {
    ++count;
    for (int d = 0; d < 27; ++d) {
      const Eigen::Vector3i offset(d % 3 - 1, (d / 3) % 3 - 1, d / 9 - 1);
      if (to.occupancy(index + offset) == Occupancy::kOccupied) {
        ++matched;
        break;
      }
    }
  });
  return count == 0 ? 0.0 : static_cast<double>(matched) / static_cast<double>(count);
}

double matchedCells(const GridLayer2D& from, const GridLayer2D& to) {
  std::size_t count = 0, matched = 0;
  from.forEachKnownCell([&](const CellIndex& index, float value) {
    if (from.classify(value) != Occupancy::kOccupied) return;
    ++count;
    for (int d = 0; d < 9; ++d) {
      if (to.occupancy(index + CellIndex(d % 3 - 1, d / 3 - 1)) == Occupancy::kOccupied) {
        ++matched;
        break;
      }
    }
  });
  return count == 0 ? 0.0 : static_cast<double>(matched) / static_cast<double>(count);
}

// Occupied laser cells of both layers: shared over either's.
double layerIoU(const GridLayer2D& a, const GridLayer2D& b) {
  std::size_t both = 0, either = 0;
  a.forEachKnownCell([&](const CellIndex& index, float value) {
    if (a.classify(value) != Occupancy::kOccupied) return;
    ++either;
    both += b.occupancy(index) == Occupancy::kOccupied ? 1 : 0;
  });
  b.forEachKnownCell([&](const CellIndex& index, float value) {
    if (b.classify(value) == Occupancy::kOccupied && a.occupancy(index) != Occupancy::kOccupied) {
      ++either;
    }
  });
  return either == 0 ? 0.0 : static_cast<double>(both) / either;
}

struct Agreement {
  double coverage = 0;  // of the true map's occupied voxels (cells), those mapped within one
  double genuine = 0;   // of the map's occupied voxels (cells), those within one of a true one
  double layer_coverage = 0, layer_genuine = 0;
};

Agreement agreement(const MappingSession& session, const MappingSession& truth) {
  return {matchedVoxels(truth.map(), session.map()), matchedVoxels(session.map(), truth.map()),
          matchedCells(truth.laserLayer(), session.laserLayer()),
          matchedCells(session.laserLayer(), truth.laserLayer())};
}

class MapReanchoringDrive : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    truth_ = new MappingSession(sessionConfig(ReanchoringConfig::Source::kNone), nullptr, nullptr);
    for (int k = 0; k < kFrames; ++k) feed(drive(), k, true, truth_);
    today_ = new MappingSession(sessionConfig(ReanchoringConfig::Source::kNone), &poses(), nullptr);
    for (int k = 0; k < kFrames; ++k) feed(drive(), k, false, today_);
  }
  static void TearDownTestSuite() {
    delete truth_;
    delete today_;
  }
  static const Drive& drive() {
    static const Drive drive;
    return drive;
  }
  static const DrivePoses& poses() {
    static const DrivePoses poses(drive());
    return poses;
  }
  static MappingSession* truth_;
  static MappingSession* today_;
};
MappingSession* MapReanchoringDrive::truth_ = nullptr;
MappingSession* MapReanchoringDrive::today_ = nullptr;

// Measured: today 0.78 / 0.79 of the voxels, 0.74 / 0.72 of the laser cells (coverage / genuine);
// by tf 1.00 / 0.99 and 1.00 / 0.99; by path 1.00 / 1.00 and 1.00 / 0.99.
TEST_F(MapReanchoringDrive, TodaysMapKeepsTheDriftedWalls) {
  const Agreement today = agreement(*today_, *truth_);
  EXPECT_LT(today.coverage, 0.85);
  EXPECT_LT(today.genuine, 0.85);
  EXPECT_LT(today.layer_coverage, 0.85);
  EXPECT_LT(today.layer_genuine, 0.85);
}

TEST_F(MapReanchoringDrive, MapToOdomJumpsSpreadOverTheirStretchCorrectTheMap) {
  MappingSession session(sessionConfig(ReanchoringConfig::Source::kTf), &poses(), nullptr);
  for (int k = 0; k < kFrames; ++k) feed(drive(), k, false, &session);
  session.reanchoring()->waitForCorrections();
  const Agreement ours = agreement(session, *truth_), today = agreement(*today_, *truth_);
  EXPECT_GT(ours.coverage, 0.97);
  EXPECT_GT(ours.genuine, 0.97);
  EXPECT_GT(ours.layer_coverage, 0.97);
  EXPECT_GT(ours.layer_genuine, 0.97);
  EXPECT_GT(ours.genuine, today.genuine + 0.1);
  EXPECT_EQ(session.reanchoring()->statistics().map_to_odom_jumps,
            static_cast<std::size_t>(kFrames / kCorrectionEvery));
}

TEST_F(MapReanchoringDrive, APathOfTrueKeyframesGivesTheTrueMap) {
  MappingSession session(sessionConfig(ReanchoringConfig::Source::kPath), &poses(), nullptr);
  std::vector<StampedPose> path;
  for (int k = 0; k < kFrames; ++k) {
    feed(drive(), k, false, &session);
    if (k % 4 == 0) path.push_back({drive().stamp(k), drive().truth[k]});
    if (k % kCorrectionEvery == kCorrectionEvery - 1) session.onPath(path, drive().stamp(k));
  }
  const Agreement ours = agreement(session, *truth_);
  EXPECT_GT(ours.genuine, 0.97);
  // Cell for cell, the laser layer's moved submaps drawn anew from their scans: 0.81 (re-sampled
  // from their cells instead: 0.67).
  EXPECT_GT(layerIoU(session.laserLayer(), truth_->laserLayer()), 0.78);
  EXPECT_GT(ours.coverage, 0.97);
  EXPECT_GT(ours.layer_genuine, 0.97);
  EXPECT_GT(ours.layer_coverage, 0.97);
  EXPECT_GE(session.reanchoring()->statistics().corrections, 3u);
}

// Every frame's true pose in the path, given once after the drive: each moved submap's scans are
// drawn again at their true poses, in the order written and on what the submaps before hold, so
// the laser layer is the true-pose layer's, each cell's updates clamped in the same order (up to
// the 1/1024 steps the submaps keep changes in, rounded away from the threshold: rounded to the
// nearest step, the wall cells whose evidence cancels to +1e-4 come back at 0, free: IoU 0.85).
TEST_F(MapReanchoringDrive, APathOfEveryTruePoseDrawsTheTrueLaserLayer) {
  MappingSessionConfig config = sessionConfig(ReanchoringConfig::Source::kPath);
  config.reanchoring.fusion.min_shift = 1e-4;  // every submap moves
  MappingSession session(config, &poses(), nullptr);
  std::vector<StampedPose> path;
  for (int k = 0; k < kFrames; ++k) {
    feed(drive(), k, false, &session);
    path.push_back({drive().stamp(k), drive().truth[k]});
  }
  session.onPath(path, drive().stamp(kFrames - 1));
  EXPECT_GT(layerIoU(session.laserLayer(), truth_->laserLayer()), 0.995);
  std::size_t cells = 0, close = 0;
  truth_->laserLayer().forEachKnownCell([&](const CellIndex& index, float value) {
    ++cells;
    const std::optional<float> drawn = session.laserLayer().logOdds(index);
    close += drawn && std::abs(*drawn - value) < 0.02f ? 1 : 0;
  });
  EXPECT_GT(static_cast<double>(close) / static_cast<double>(cells), 0.995);
}

// Submaps under a memory bound (reanchoring/max_memory_mb): all but the newest spilled to a
// file, read back when corrections move them. The map is the unbounded session's, bit for bit,
// through the same corrections, and so is a save of its submaps.
TEST_F(MapReanchoringDrive, SpilledSubmapsMoveAsThoseInMemory) {
  MappingSessionConfig bounded_config = sessionConfig(ReanchoringConfig::Source::kPath);
  bounded_config.reanchoring.fusion.max_memory_bytes = 1;
  bounded_config.reanchoring.max_scan_bytes = 1;  // the laser scans kept to draw submaps again
  MappingSession unbounded(sessionConfig(ReanchoringConfig::Source::kPath), &poses(), nullptr);
  MappingSession bounded(bounded_config, &poses(), nullptr);
  std::vector<StampedPose> path;
  for (int k = 0; k < kFrames; ++k) {
    feed(drive(), k, false, &unbounded);
    feed(drive(), k, false, &bounded);
    if (k % 4 == 0) path.push_back({drive().stamp(k), drive().truth[k]});
    if (k % kCorrectionEvery == kCorrectionEvery - 1) {
      EXPECT_EQ(bounded.onPath(path, drive().stamp(k)).moved,
                unbounded.onPath(path, drive().stamp(k)).moved);
    }
  }
  const auto cells = [](const MappingSession& session) {
    std::map<std::tuple<int, int, int>, float> known;
    session.map().forEachKnownVoxel([&](const VoxelIndex& i, float v) {
      known[{i.x(), i.y(), i.z()}] = v;
    });
    session.laserLayer().forEachKnownCell([&](const CellIndex& i, float v) {
      known[{i.x(), i.y(), 1 << 20}] = v;
    });
    return known;
  };
  EXPECT_TRUE(cells(bounded) == cells(unbounded));
  const SubmapFusion& spilled = bounded.reanchoring()->fusion();
  EXPECT_GT(spilled.spilledBytes(), 0u);
  // Measured: 64 KB against 165 KB (the newest submap, the active one and where each spilled
  // block lies stay in memory).
  EXPECT_LT(spilled.memoryBytes(), unbounded.reanchoring()->fusion().memoryBytes() / 2);
  // The kept scans too: all but the submap being written's in the file, read back to draw the
  // moved submaps' laser cells again (the same cells as above).
  EXPECT_GT(unbounded.reanchoring()->keptScanBytes(), 0u);
  EXPECT_GT(bounded.reanchoring()->spilledScanBytes(), 0u);
  EXPECT_LT(bounded.reanchoring()->keptScanBytes(), unbounded.reanchoring()->keptScanBytes() / 2);
  // Saved, the same submaps (in another order of blocks): restored, they move the same.
  std::ostringstream bounded_bytes, unbounded_bytes;
  bounded.reanchoring()->save(bounded_bytes);
  unbounded.reanchoring()->save(unbounded_bytes);
  EXPECT_EQ(bounded_bytes.str().size(), unbounded_bytes.str().size());
  // (Both restored: kept laser scans are not saved, so restored submaps' laser cells are
  // re-sampled when they move.)
  std::istringstream saved(bounded_bytes.str()), saved_unbounded(unbounded_bytes.str());
  EXPECT_NO_THROW(bounded.reanchoring()->restore(saved));
  EXPECT_NO_THROW(unbounded.reanchoring()->restore(saved_unbounded));
  EXPECT_EQ(bounded.reanchoring()->fusion().submaps().size(),
            unbounded.reanchoring()->fusion().submaps().size());
  const std::vector<StampedPose> shifted = [&] {
    std::vector<StampedPose> moved = path;
    for (StampedPose& keyframe : moved) {
      keyframe.pose = Eigen::Translation3d(0.3, -0.2, 0.0) * keyframe.pose;
    }
    return moved;
  }();
  EXPECT_GT(bounded.onPath(shifted, drive().stamp(kFrames - 1)).moved, 3u);
  unbounded.onPath(shifted, drive().stamp(kFrames - 1));
  EXPECT_TRUE(cells(bounded) == cells(unbounded));
}

// Mapped before a restart, saved with its submaps, resumed: the first correction after the
// restart moves what was mapped before it, as it does in a session that never stopped.
TEST_F(MapReanchoringDrive, ASavedAndResumedMapFollowsTheNextCorrection) {
  const TemporaryFolder folder("reanchoring_resume");
  const MappingSessionConfig config = sessionConfig(ReanchoringConfig::Source::kPath);
  MappingSession before(config, &poses(), nullptr);
  std::vector<StampedPose> path;
  for (int k = 0; k < kFrames / 2; ++k) {
    feed(drive(), k, false, &before);
    if (k % 4 == 0) path.push_back({drive().stamp(k), drive().truth[k]});
  }
  const std::string prefix = folder.path("map");
  std::vector<std::string> files;
  saveMap(before.map(), before.laserLayer(), prefix, MapSaveOptions(), &files);
  writeSubmapFile(before.reanchoring(), submapFilePath(prefix));

  MappingSession resumed(config, &poses(), nullptr);
  resumed.resumeFrom(prefix + ".ot");
  const std::size_t submaps = resumed.reanchoring()->fusion().submaps().size();
  EXPECT_EQ(submaps, before.reanchoring()->fusion().submaps().size());
  EXPECT_FALSE(resumed.reanchoring()->fusion().submaps()[0].fixed);
  EXPECT_EQ(resumed.reanchoring()->odometryPoses(), before.reanchoring()->odometryPoses());

  EXPECT_GE(before.onPath(path, drive().stamp(kFrames / 2)).moved, 1u);
  EXPECT_GE(resumed.onPath(path, drive().stamp(kFrames / 2)).moved, 1u);
  EXPECT_GT(matchedVoxels(resumed.map(), before.map()), 0.99);
  EXPECT_GT(matchedVoxels(before.map(), resumed.map()), 0.99);
  EXPECT_GT(matchedCells(resumed.laserLayer(), before.laserLayer()), 0.99);
  // Without the submaps file the resumed map stays where it was mapped.
  std::filesystem::remove(submapFilePath(prefix));
  MappingSession fixed(config, &poses(), nullptr);
  fixed.resumeFrom(prefix + ".ot");
  EXPECT_TRUE(fixed.reanchoring()->fusion().submaps()[0].fixed);
  EXPECT_EQ(fixed.onPath(path, drive().stamp(kFrames / 2)).moved, 0u);
}

// The same through the map's checkpoints: a process killed after a checkpoint and started on the
// same store resumes the map with its submaps.
TEST_F(MapReanchoringDrive, ACheckpointedMapResumesItsSubmaps) {
  const TemporaryFolder folder("reanchoring_checkpoint");
  MappingSessionConfig config = sessionConfig(ReanchoringConfig::Source::kPath);
  config.map.spill_folder = folder.path("store");
  config.map.checkpoint_period = 1.0;  // called by hand here
  MappingSession continuous(sessionConfig(ReanchoringConfig::Source::kPath), &poses(), nullptr);
  std::vector<StampedPose> path;
  std::size_t submaps = 0;
  {
    MappingSession killed(config, &poses(), nullptr);
    for (int k = 0; k < kFrames / 2; ++k) {
      feed(drive(), k, false, &killed);
      feed(drive(), k, false, &continuous);
      if (k % 4 == 0) path.push_back({drive().stamp(k), drive().truth[k]});
    }
    ASSERT_TRUE(killed.checkpoint("before the kill").written);
    submaps = killed.reanchoring()->fusion().submaps().size();
  }
  MappingSession resumed(config, &poses(), nullptr);
  EXPECT_GT(resumed.map().knownVoxelCount(), 0u);
  ASSERT_EQ(resumed.reanchoring()->fusion().submaps().size(), submaps);
  EXPECT_FALSE(resumed.reanchoring()->fusion().submaps()[0].fixed);
  EXPECT_GE(continuous.onPath(path, drive().stamp(kFrames / 2)).moved, 1u);
  EXPECT_GE(resumed.onPath(path, drive().stamp(kFrames / 2)).moved, 1u);
  EXPECT_GT(matchedVoxels(resumed.map(), continuous.map()), 0.99);
  EXPECT_GT(matchedVoxels(continuous.map(), resumed.map()), 0.99);
  EXPECT_GT(matchedCells(resumed.laserLayer(), continuous.laserLayer()), 0.99);
}

TEST_F(MapReanchoringDrive, WithoutCorrectionsTheMapIsTodaysVoxelForVoxel) {
  // map -> odom the identity throughout: reanchoring by tf gives today's map exactly.
  struct Unlocalised : PoseSource {
    explicit Unlocalised(const Drive& drive) : poses(drive) {}
    std::optional<Eigen::Isometry3d> lookup(const std::string& /*target*/, const std::string& frame,
                                            double stamp, std::string* why) const override {
      if (frame == "odom") return Eigen::Isometry3d::Identity();
      return poses.lookup("odom", frame, stamp, why);  // map == odom
    }
    DrivePoses poses;
  } unlocalised(drive());
  MappingSession plain(sessionConfig(ReanchoringConfig::Source::kNone), &unlocalised, nullptr);
  MappingSession reanchored(sessionConfig(ReanchoringConfig::Source::kTf), &unlocalised, nullptr);
  for (int k = 0; k < kFrames / 2; ++k) {
    feed(drive(), k, false, &plain);
    feed(drive(), k, false, &reanchored);
  }
  reanchored.reanchoring()->waitForCorrections();
  std::map<std::tuple<int, int, int>, float> a, b;
  plain.map().forEachKnownVoxel([&](const VoxelIndex& i, float v) {
    a[{i.x(), i.y(), i.z()}] = v;
  });
  reanchored.map().forEachKnownVoxel([&](const VoxelIndex& i, float v) {
    b[{i.x(), i.y(), i.z()}] = v;
  });
  EXPECT_EQ(a, b);
  const LogOddsRaster plain_layer = plain.laserLayer().toLogOddsRaster();
  const LogOddsRaster reanchored_layer = reanchored.laserLayer().toLogOddsRaster();
  ASSERT_EQ(plain_layer.data.size(), reanchored_layer.data.size());
  for (std::size_t i = 0; i < plain_layer.data.size(); ++i) {
    const float a = plain_layer.data[i], b = reanchored_layer.data[i];
    ASSERT_TRUE(a == b || (std::isnan(a) && std::isnan(b))) << "cell " << i;
  }
  EXPECT_GT(reanchored.reanchoring()->fusion().submaps().size(), 3u);
}

// A robot standing for 0.9 s with a front and a rear laser at 10 Hz: each laser's first scan is
// kept, standing for the nine taken there (one integrator draws both lasers: a scan is compared
// with the last one of its own laser). A correction then draws them again, each with weight 9:
// the laser layer is the one the 18 scans make at the corrected pose.
TEST(MapReanchoringScans, AStandingRobotKeepsOneScanPerLaserDrawnForAllItsScans) {
  const Eigen::Isometry3d rear_laser =
      Eigen::Translation3d(-0.2, 0.0, 0.3) * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ());
  struct Standing : PoseSource {
    Eigen::Isometry3d rear;
    std::optional<Eigen::Isometry3d> lookup(const std::string& /*target*/, const std::string& frame,
                                            double /*stamp*/, std::string* /*why*/) const override {
      if (frame == "laser") return kBaseLaser;
      if (frame == "laser_rear") return rear;
      return Eigen::Isometry3d::Identity();  // base_link in odom (and odom in map)
    }
  } standing;
  standing.rear = rear_laser;
  const sim::Scene scene = sim::makeRoomScene();
  const Eigen::Isometry3d T_map_base = planar(0.3, -0.2, 0.0);  // the correction
  MappingSession session(sessionConfig(ReanchoringConfig::Source::kPath), &standing, nullptr);
  MappingSession corrected(sessionConfig(ReanchoringConfig::Source::kNone), nullptr, nullptr);
  std::size_t beams = 0;
  for (int k = 0; k < 9; ++k) {
    for (const auto& [frame, mount] :
         {std::pair<std::string, Eigen::Isometry3d>{"laser", kBaseLaser},
          {"laser_rear", rear_laser}}) {
      LaserScanFrame scan;
      scan.header = {"laser", "/" + frame, frame, kStamp0 + 0.1 * k, std::nullopt};
      scan.scan = toLaserScan(sim::renderScan(scene, sim::LaserScanner(), T_map_base * mount));
      beams = scan.scan.ranges.size();
      ASSERT_TRUE(session.integrate(scan).integrated);
      scan.header.T_map_sensor = T_map_base * mount;
      ASSERT_TRUE(corrected.integrate(scan).integrated);
    }
  }
  // Two scans kept, not 18.
  EXPECT_LT(session.reanchoring()->keptScanBytes(), 2 * (beams * sizeof(float) + 1024));
  session.onPath({{kStamp0, T_map_base}, {kStamp0 + 0.8, T_map_base}}, kStamp0 + 0.8);
  ASSERT_EQ(session.reanchoring()->statistics().corrections, 1u);
  std::size_t cells = 0, close = 0;
  corrected.laserLayer().forEachKnownCell([&](const CellIndex& index, float value) {
    ++cells;
    const std::optional<float> drawn = session.laserLayer().logOdds(index);
    close += drawn && std::abs(*drawn - value) < 0.01f ? 1 : 0;
  });
  ASSERT_GT(cells, 1000u);
  EXPECT_GT(static_cast<double>(close) / static_cast<double>(cells), 0.99);
  EXPECT_GT(layerIoU(session.laserLayer(), corrected.laserLayer()), 0.99);
}

}  // namespace
}  // namespace occupancy_fusion
