#include "occupancy_fusion/eval/stereo_motion_matrix.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {

namespace {

// The motions whose speed is a parameter: the name's kind and the step's unit ("" for metres).
struct MotionKind {
  const char* kind;
  StereoMotion motion;
  const char* unit;
};
constexpr MotionKind kMotionKinds[] = {{"forward", StereoMotion::kForward, ""},
                                       {"turn", StereoMotion::kTurn, "deg"},
                                       {"sideways", StereoMotion::kSideways, ""},
                                       {"aisle_curve", StereoMotion::kAisleCurve, ""},
                                       {"aisle_diagonal", StereoMotion::kAisleDiagonal, ""},
                                       {"aisle_fast", StereoMotion::kAisleFast, ""},
                                       {"aisle_backward", StereoMotion::kAisleBackward, ""},
                                       {"office_loop", StereoMotion::kOfficeLoop, ""},
                                       {"office_zigzag", StereoMotion::kOfficeZigzag, ""},
                                       {"office_backward", StereoMotion::kOfficeBackward, ""}};

const MotionKind& kindOf(StereoMotion motion) {
  for (const MotionKind& kind : kMotionKinds) {
    if (kind.motion == motion) return kind;
  }
  throw std::invalid_argument("stereo motion without a step per frame");
}

// The motion at `step` per frame, named kind_step[unit]: forward_0.10, turn_5deg.
StereoMotionCase motionAt(StereoMotion motion, double step) {
  const MotionKind& kind = kindOf(motion);
  char text[64];
  if (kind.unit[0] == '\0') {
    std::snprintf(text, sizeof(text), "%s_%.2f", kind.kind, step);
  } else {
    std::snprintf(text, sizeof(text), "%s_%g%s", kind.kind, step, kind.unit);
  }
  return {text, motion, step};
}

// The step of `name` = kind + "_" + step + unit, where the step is a positive number; false where
// the name is not of that form.
bool parseStep(const std::string& name, const std::string& kind, const std::string& unit,
               double* step) {
  const std::string prefix = kind + "_";
  if (name.size() <= prefix.size() + unit.size() || name.compare(0, prefix.size(), prefix) != 0 ||
      name.compare(name.size() - unit.size(), unit.size(), unit) != 0) {
    return false;
  }
  const std::string number = name.substr(prefix.size(), name.size() - prefix.size() - unit.size());
  std::size_t used = 0;
  try {
    *step = std::stod(number, &used);
  } catch (const std::exception&) {
    return false;
  }
  return used == number.size() && std::isfinite(*step) && *step > 0;
}

}  // namespace

std::vector<StereoMotionCase> stereoMatrixMotions() {
  return {motionAt(StereoMotion::kForward, 0.03),  motionAt(StereoMotion::kForward, 0.10),
          motionAt(StereoMotion::kForward, 0.20),  motionAt(StereoMotion::kTurn, 5.0),
          motionAt(StereoMotion::kSideways, 0.10), {"standing", StereoMotion::kStanding, 0.0}};
}

std::vector<StereoMotionCase> stereoAisleMotions() {
  return {motionAt(StereoMotion::kAisleCurve, 0.15), motionAt(StereoMotion::kAisleDiagonal, 0.09),
          motionAt(StereoMotion::kAisleFast, 0.30), motionAt(StereoMotion::kAisleBackward, 0.10)};
}

std::vector<StereoMotionCase> stereoOfficeMotions() {
  return {motionAt(StereoMotion::kOfficeLoop, 0.10), motionAt(StereoMotion::kOfficeLoop, 0.25),
          motionAt(StereoMotion::kOfficeZigzag, 0.10), motionAt(StereoMotion::kOfficeZigzag, 0.20),
          motionAt(StereoMotion::kOfficeBackward, 0.10)};
}

StereoMotionCase stereoMotionCaseFromName(const std::string& name) {
  std::string known;
  std::vector<StereoMotionCase> motions = stereoMatrixMotions();
  for (const StereoMotionCase& aisle : stereoAisleMotions()) motions.push_back(aisle);
  for (const StereoMotionCase& office : stereoOfficeMotions()) motions.push_back(office);
  for (const StereoMotionCase& motion : motions) {
    if (motion.name == name) return motion;
    known += (known.empty() ? "" : ", ") + motion.name;
  }
  // The same motions at other speeds: the kind's name and its step per frame.
  double step = 0.0;
  std::string forms;
  for (const MotionKind& kind : kMotionKinds) {
    if (parseStep(name, kind.kind, kind.unit, &step)) return {name, kind.motion, step};
    forms += std::string(forms.empty() ? "" : ", ") + kind.kind + "_<step>" + kind.unit;
  }
  throw std::invalid_argument("unknown motion '" + name + "' (known: " + known +
                              "; other steps per frame, metres or degrees: " + forms + ")");
}

bool StereoMotionSetup::isAisle() const {
  return motion.motion == StereoMotion::kAisleCurve ||
         motion.motion == StereoMotion::kAisleDiagonal ||
         motion.motion == StereoMotion::kAisleFast || motion.motion == StereoMotion::kAisleBackward;
}

bool StereoMotionSetup::isOffice() const {
  return motion.motion == StereoMotion::kOfficeLoop ||
         motion.motion == StereoMotion::kOfficeZigzag ||
         motion.motion == StereoMotion::kOfficeBackward;
}

namespace {

// The camera and matcher errors of a check outside the matrix (the matrix keeps
// StereoMotionSetup's defaults); the errors' other fields stay the matrix's.
struct CheckCamera {
  int width, height;
  double focal_px, baseline, max_range;  // px, m, m
  double sigma_px, patch_probability;
  int patch_size_px;
  double patch_offset_px;
  int patch_persistence_frames;
  std::uint64_t seed;
};
constexpr CheckCamera kAisleCamera{640, 480, 420.0, 0.09, 10.0, 0.4, 0.25, 16, 2.0, 6, 11};
constexpr CheckCamera kOfficeCamera{848, 480, 425.0, 0.095, 8.0, 0.5, 0.2, 20, 2.5, 4, 23};

void useCamera(const CheckCamera& camera, StereoMotionSetup* setup) {
  setup->width = camera.width;
  setup->height = camera.height;
  setup->focal_px = camera.focal_px;
  setup->baseline = camera.baseline;
  setup->max_range = camera.max_range;
  sim::DisparityNoise& noise = setup->noise;
  noise.sigma_px = camera.sigma_px;
  noise.patch_probability = camera.patch_probability;
  noise.patch_size_px = camera.patch_size_px;
  noise.patch_offset_px = camera.patch_offset_px;
  noise.patch_persistence_frames = camera.patch_persistence_frames;
  noise.seed = camera.seed;
}

}  // namespace

StereoMotionSetup stereoSetupFor(const StereoMotionCase& motion) {
  StereoMotionSetup setup;
  setup.motion = motion;
  if (setup.isOffice()) useCamera(kOfficeCamera, &setup);
  if (setup.isAisle()) useCamera(kAisleCamera, &setup);
  return setup;
}

sim::PinholeCamera StereoMotionSetup::camera() const {
  sim::PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = focal_px;
  camera.cx = 0.5 * (width - 1);
  camera.cy = 0.5 * (height - 1);
  return camera;
}

StereoCamera StereoMotionSetup::stereo() const {
  const sim::PinholeCamera c = camera();
  return {c.fx, c.fy, c.cx, c.cy, baseline};
}

sim::Scene StereoMotionSetup::scene() const {
  if (isAisle()) return sim::makeAisleScene();
  if (isOffice()) return sim::makeOfficeScene();
  return motion.motion == StereoMotion::kTurn ? sim::makeRoomScene() : sim::makeCorridorScene();
}

namespace {

// The aisle motions' body poses at 1 m height, pitched 0.1 rad down.
Eigen::Isometry3d aislePose(const StereoMotionCase& motion, int k) {
  double x = 0.3, y = 0.0, yaw_deg = 0.0;
  switch (motion.motion) {
    case StereoMotion::kAisleCurve:
      x += motion.step * k;
      y = 0.3 * std::sin(0.1 * k);
      yaw_deg = 2.0 * k - 20.0;
      break;
    case StereoMotion::kAisleDiagonal:
      x += motion.step * k * 2.0 / std::sqrt(5.0);
      y = -0.8 + motion.step * k / std::sqrt(5.0);
      yaw_deg = 15.0;
      break;
    case StereoMotion::kAisleFast:
      x += motion.step * k;
      break;
    default:  // kAisleBackward
      x = 6.0 - motion.step * k;
      y = 0.2;
      yaw_deg = -10.0;
      break;
  }
  return Eigen::Translation3d(x, y, 1.0) *
         Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY());
}

// The office motions' body poses at 1.1 m height, pitched 0.15 rad down.
Eigen::Isometry3d officePose(const StereoMotionCase& motion, int k) {
  double x = 0.0, y = 0.0, yaw = 0.0;
  if (motion.motion == StereoMotion::kOfficeLoop) {
    // Counter-clockwise from the ellipse's lowest point, the step along its mean radius.
    constexpr double kA = 3.2, kB = 2.2;
    const double theta = -0.5 * M_PI + motion.step * k / (0.5 * (kA + kB));
    x = 0.3 + kA * std::cos(theta);
    y = 0.1 + kB * std::sin(theta);
    yaw = std::atan2(kB * std::cos(theta), -kA * std::sin(theta));
  } else {  // kOfficeZigzag, kOfficeBackward: the same line and heading, either way along it
    x = motion.motion == StereoMotion::kOfficeZigzag ? -4.0 + motion.step * k
                                                     : 3.8 - motion.step * k;
    y = 0.15;
    yaw = 30.0 * M_PI / 180.0 * std::sin(2.0 * M_PI * k / 16.0);
  }
  return Eigen::Translation3d(x, y, 1.1) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(0.15, Eigen::Vector3d::UnitY());
}

}  // namespace

std::vector<Eigen::Isometry3d> StereoMotionSetup::poses() const {
  constexpr double kHeight = 1.2;  // m
  const Eigen::Isometry3d optical = sim::opticalFrameInBody();
  std::vector<Eigen::Isometry3d> poses;
  for (int k = 0; k < frames; ++k) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    switch (motion.motion) {
      case StereoMotion::kForward:
      case StereoMotion::kStanding: {
        const double x = 0.5 + (motion.motion == StereoMotion::kForward ? motion.step * k : 0.0);
        pose = Eigen::Translation3d(x, 0.0, kHeight) * optical;
        break;
      }
      case StereoMotion::kTurn: {
        // About the room's free centre, slightly off it so that no wall is seen square on.
        const double yaw = motion.step * k * M_PI / 180.0;
        pose = Eigen::Translation3d(0.2, -0.3, kHeight) *
               Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * optical;
        break;
      }
      case StereoMotion::kSideways: {
        // 1.6 m from the left wall, pitched 15 deg down, passing the pillar at x = 4 towards the
        // doorway at x = 7.
        const double x = 2.0 + motion.step * k;
        const Eigen::Vector3d eye(x, -0.4, kHeight);
        pose = sim::lookAt(eye, eye + Eigen::Vector3d(0.0, 1.0, -std::tan(15.0 * M_PI / 180.0)));
        break;
      }
      case StereoMotion::kAisleCurve:
      case StereoMotion::kAisleDiagonal:
      case StereoMotion::kAisleFast:
      case StereoMotion::kAisleBackward:
        pose = aislePose(motion, k) * optical;
        break;
      case StereoMotion::kOfficeLoop:
      case StereoMotion::kOfficeZigzag:
      case StereoMotion::kOfficeBackward:
        pose = officePose(motion, k) * optical;
        break;
    }
    poses.push_back(pose);
  }
  return poses;
}

StereoRecording renderStereoRecording(const sim::Scene& scene, const StereoMotionSetup& setup) {
  StereoRecording recording{setup, {}, setup.poses()};
  const sim::PinholeCamera camera = setup.camera();
  recording.images.resize(recording.poses.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < static_cast<int>(recording.poses.size()); ++k) {
    recording.images[k] = sim::renderDisparity(scene, camera, setup.baseline, recording.poses[k],
                                               setup.max_range, setup.noise, k);
  }
  return recording;
}

StereoGroundTruth::StereoGroundTruth(const sim::Scene& scene, const StereoRecording& recording,
                                     double resolution)
    : scene_(scene), resolution_(resolution) {
  const std::vector<Eigen::Vector3d> samples = scene.sampleSurface(resolution);
  const sim::PinholeCamera camera = recording.setup.camera();
  const double max_range = recording.setup.max_range;
  first_seen_.assign(samples.size(), -1);
  sample_voxels_.resize(samples.size());
  const long count = static_cast<long>(samples.size());
#pragma omp parallel for schedule(dynamic, 1024)
  for (long i = 0; i < count; ++i) {
    const Eigen::Vector3d& sample = samples[i];
    sample_voxels_[i] = voxelIndexOf(sample, resolution);
    for (std::size_t k = 0; k < recording.poses.size(); ++k) {
      const Eigen::Isometry3d& pose = recording.poses[k];
      const Eigen::Vector3d p = pose.inverse() * sample;
      if (p.z() <= 0.1 || p.z() > max_range) continue;
      const double u = camera.fx * p.x() / p.z() + camera.cx;
      const double v = camera.fy * p.y() / p.z() + camera.cy;
      if (u < 0 || v < 0 || u > camera.width - 1 || v > camera.height - 1) continue;
      const Eigen::Vector3d offset = sample - pose.translation();
      const double distance = offset.norm();
      const auto t = scene.castRay(pose.translation(), offset / distance, distance + 0.01);
      if (t && *t >= distance - 0.02) {
        first_seen_[i] = static_cast<int>(k);
        break;
      }
    }
  }
}

bool StereoGroundTruth::isFalse(const VoxelIndex& voxel) {
  const std::uint64_t key = packKey(voxel);
  const auto it = is_false_.find(key);
  if (it != is_false_.end()) return it->second;
  const Eigen::Vector3d center = (voxel.cast<double>().array() + 0.5) * resolution_;
  const double tolerance = std::sqrt(3.0) * resolution_;  // one voxel diagonal
  const bool wrong = !scene_.isOccupied(center) && scene_.distanceToSurface(center) > tolerance;
  is_false_.emplace(key, wrong);
  return wrong;
}

StereoGroundTruth::FrameQuality StereoGroundTruth::evaluate(const OccupiedVoxelSet& occupied,
                                                            int frame) {
  FrameQuality quality;
  quality.occupied = occupied.voxels.size();
  for (const VoxelIndex& voxel : occupied.voxels) quality.false_occupied += isFalse(voxel) ? 1 : 0;
  quality.surface_occupied = quality.occupied - quality.false_occupied;
  std::size_t seen = 0, covered = 0;
  const long count = static_cast<long>(first_seen_.size());
#pragma omp parallel for schedule(static) reduction(+ : seen, covered)
  for (long i = 0; i < count; ++i) {
    if (first_seen_[i] < 0 || first_seen_[i] > frame) continue;
    ++seen;
    bool found = false;
    for (int dz = -1; dz <= 1 && !found; ++dz) {
      for (int dy = -1; dy <= 1 && !found; ++dy) {
        for (int dx = -1; dx <= 1 && !found; ++dx) {
          found = occupied.contains(sample_voxels_[i] + VoxelIndex(dx, dy, dz));
        }
      }
    }
    covered += found ? 1 : 0;
  }
  quality.seen_samples = seen;
  quality.coverage = seen == 0 ? 0.0 : static_cast<double>(covered) / seen;
  return quality;
}

StereoRunCurve mapStereoRecording(const VisibilityStereoConfig& config,
                                  const StereoRecording& recording, double resolution,
                                  StereoGroundTruth* truth) {
  const VisibilityStereoIntegrator integrator(config);
  VoxelMapConfig map_config;
  map_config.resolution = resolution;
  VoxelMap map(map_config);
  const StereoCamera stereo = recording.setup.stereo();
  StereoRunCurve curve;
  for (std::size_t k = 0; k < recording.images.size(); ++k) {
    const sim::DisparityImage& image = recording.images[k];
    const DisparityImageView view{image.width, image.height, image.disparity.data(), 0};
    curve.seconds += integrator.integrate(view, stereo, recording.poses[k], &map).seconds;
    curve.frames.push_back(truth->evaluate(occupiedVoxelsOf(map), static_cast<int>(k)));
  }
  curve.final_occupied = occupiedVoxelsOf(map);
  return curve;
}

}  // namespace occupancy_fusion
