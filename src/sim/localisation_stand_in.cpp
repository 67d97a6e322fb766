#include "occupancy_fusion/sim/localisation_stand_in.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "occupancy_fusion/sim/deterministic_random.h"

namespace occupancy_fusion {
namespace sim {
namespace {

void requirePositive(const char* name, double value) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string("localisation ") + name + " must be > 0");
  }
}

void requireNonNegative(const char* name, double value) {
  if (!(value >= 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string("localisation ") + name + " must be >= 0");
  }
}

// Keyframe `keyframe`'s pose as correction number `correction` sets it: the truth, moved by the
// residual error drawn for that pair.
Eigen::Isometry3d correctedPose(const Eigen::Isometry3d& truth, int correction, int keyframe,
                                const LocalisationConfig& config) {
  if (config.residual_translation_noise == 0.0 && config.residual_heading_noise == 0.0) {
    return truth;
  }
  auto normal = [&](std::uint64_t component) {
    return standardNormal(hashKey({config.seed, static_cast<std::uint64_t>(correction),
                                   static_cast<std::uint64_t>(keyframe), component}));
  };
  Eigen::Isometry3d pose = truth;
  pose.translation() +=
      config.residual_translation_noise * Eigen::Vector3d(normal(1), normal(2), 0);
  pose.linear() =
      Eigen::AngleAxisd(config.residual_heading_noise * normal(3), Eigen::Vector3d::UnitZ()) *
      truth.linear();
  return pose;
}

// Whether the odometry moved far enough from the last keyframe for a new one.
bool movedEnough(const Eigen::Isometry3d& T_odom_last, const Eigen::Isometry3d& T_odom_now,
                 const LocalisationConfig& config) {
  const Eigen::Isometry3d motion = T_odom_last.inverse() * T_odom_now;
  return motion.translation().norm() >= config.keyframe_distance ||
         Eigen::AngleAxisd(motion.linear()).angle() >= config.keyframe_angle;
}

}  // namespace

void LocalisationConfig::validate() const {
  requirePositive("keyframe_distance", keyframe_distance);
  requirePositive("keyframe_angle", keyframe_angle);
  requirePositive("closure_radius", closure_radius);
  requireNonNegative("min_loop_length", min_loop_length);
  if (min_frames_between_closures < 1) {
    throw std::invalid_argument("localisation min_frames_between_closures must be >= 1");
  }
  if (correct_every_frames < 0) {
    throw std::invalid_argument("localisation correct_every_frames must be >= 0 (0: never)");
  }
  requireNonNegative("residual_translation_noise", residual_translation_noise);
  requireNonNegative("residual_heading_noise", residual_heading_noise);
}

int LocalisationTrack::keyframeCountAt(int frame) const {
  return static_cast<int>(std::upper_bound(keyframe_frames.begin(), keyframe_frames.end(), frame) -
                          keyframe_frames.begin());
}

int LocalisationTrack::lastCorrectionAt(int frame) const {
  const auto after = std::upper_bound(corrections.begin(), corrections.end(), frame);
  return after == corrections.begin() ? -1 : *(after - 1);
}

std::vector<Eigen::Isometry3d> LocalisationTrack::pathAt(int frame) const {
  const auto after = std::upper_bound(corrections.begin(), corrections.end(), frame);
  const int correction = static_cast<int>(after - corrections.begin()) - 1;  // -1: none yet
  const int count = keyframeCountAt(frame);
  std::vector<Eigen::Isometry3d> path;
  path.reserve(count);
  for (int i = 0; i < count; ++i) {
    const bool corrected = correction >= 0 && corrections[correction] >= keyframe_frames[i];
    path.push_back(corrected ? correctedPose(keyframe_truth[i], correction, i, config)
                             : keyframe_estimates[i]);
  }
  return path;
}

bool LocalisationTrack::pathChangedAt(int frame) const {
  return std::binary_search(keyframe_frames.begin(), keyframe_frames.end(), frame) ||
         std::binary_search(corrections.begin(), corrections.end(), frame);
}

LocalisationTrack runLocalisation(const std::vector<Eigen::Isometry3d>& T_map_base_truth,
                                  const std::vector<Eigen::Isometry3d>& T_odom_base,
                                  const LocalisationConfig& config) {
  config.validate();
  if (T_map_base_truth.size() != T_odom_base.size()) {
    throw std::invalid_argument("runLocalisation needs as many odometry poses as true poses");
  }
  LocalisationTrack track;
  track.config = config;
  const int frames = static_cast<int>(T_map_base_truth.size());
  std::vector<double> travel(frames, 0.0);  // m, along the true path
  for (int k = 1; k < frames; ++k) {
    travel[k] = travel[k - 1] +
                (T_map_base_truth[k].translation() - T_map_base_truth[k - 1].translation()).norm();
  }
  auto loopClosesAt = [&](int k) {
    if (!config.detect_loop_closures) return false;
    if (!track.corrections.empty() &&
        k - track.corrections.back() < config.min_frames_between_closures) {
      return false;
    }
    for (std::size_t i = 0; i < track.keyframe_frames.size(); ++i) {
      if (travel[k] - travel[track.keyframe_frames[i]] <= config.min_loop_length) break;
      const double distance =
          (T_map_base_truth[k].translation() - track.keyframe_truth[i].translation()).norm();
      if (distance <= config.closure_radius) return true;
    }
    return false;
  };
  Eigen::Isometry3d T_map_odom = Eigen::Isometry3d::Identity();
  for (int k = 0; k < frames; ++k) {
    const bool scheduled =
        config.correct_every_frames > 0 && k > 0 && k % config.correct_every_frames == 0;
    const bool correct = k > 0 && (scheduled || loopClosesAt(k));
    const int next_keyframe = static_cast<int>(track.keyframe_frames.size());
    if (k == 0 || correct) {
      // The keyframe this frame adds is corrected with the rest: the estimate of it, and of the
      // robot until the next correction, starts from the corrected pose.
      if (correct) track.corrections.push_back(k);
      const int correction = static_cast<int>(track.corrections.size()) - 1;
      const Eigen::Isometry3d corrected =
          correct ? correctedPose(T_map_base_truth[k], correction, next_keyframe, config)
                  : T_map_base_truth[k];
      T_map_odom = corrected * T_odom_base[k].inverse();
    }
    track.T_map_odom.push_back(T_map_odom);
    if (k == 0 || correct ||
        movedEnough(T_odom_base[track.keyframe_frames.back()], T_odom_base[k], config)) {
      track.keyframe_frames.push_back(k);
      track.keyframe_estimates.push_back(T_map_odom * T_odom_base[k]);
      track.keyframe_truth.push_back(T_map_base_truth[k]);
    }
  }
  return track;
}

}  // namespace sim
}  // namespace occupancy_fusion
