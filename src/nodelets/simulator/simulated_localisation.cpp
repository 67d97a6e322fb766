#include "simulated_localisation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "occupancy_fusion/sim/scenes.h"

#include "simulated_sensors.h"  // validateUnder

namespace occupancy_fusion {
namespace {

sim::OdometryDriftConfig readOdometryDrift(const ParameterSource& source) {
  sim::OdometryDriftConfig config;
  int seed = static_cast<int>(config.seed);
  source.get("drift/seed", &seed);
  if (seed < 0) throw std::invalid_argument("drift/seed must be >= 0");
  config.seed = static_cast<unsigned>(seed);
  source.get("drift/translation_noise", &config.translation_noise);
  source.get("drift/scale_error", &config.scale_error);
  source.get("drift/heading_drift", &config.heading_drift);
  source.get("drift/heading_noise", &config.heading_noise);
  double scale = 1.0;
  source.get("drift/scale", &scale);
  if (!(scale >= 0.0)) throw std::invalid_argument("drift/scale must be >= 0");
  return config.scaled(scale);
}

sim::LocalisationConfig readLocalisation(const ParameterSource& source) {
  sim::LocalisationConfig config;
  source.get("localisation/keyframe_distance", &config.keyframe_distance);
  source.get("localisation/keyframe_angle", &config.keyframe_angle);
  source.get("localisation/detect_loop_closures", &config.detect_loop_closures);
  source.get("localisation/closure_radius", &config.closure_radius);
  source.get("localisation/min_loop_length", &config.min_loop_length);
  source.get("localisation/min_frames_between_closures", &config.min_frames_between_closures);
  source.get("localisation/correct_every_frames", &config.correct_every_frames);
  source.get("localisation/residual_translation_noise", &config.residual_translation_noise);
  source.get("localisation/residual_heading_noise", &config.residual_heading_noise);
  int seed = static_cast<int>(config.seed);
  source.get("localisation/seed", &seed);
  if (seed < 0) throw std::invalid_argument("localisation/seed must be >= 0");
  config.seed = static_cast<unsigned>(seed);
  return config;
}

}  // namespace

void LoopMotionConfig::validate() const {
  if (!(speed > 0.0) || !std::isfinite(speed)) {
    throw std::invalid_argument("trajectory/speed must be a positive number of m/s");
  }
  if (!(laps > 0.0) || !(laps <= 100.0)) {
    throw std::invalid_argument("trajectory/laps must be > 0 and at most 100");
  }
  validateUnder("drift", odometry_drift);
  validateUnder("localisation", localisation);
}

LoopMotionConfig readLoopMotionConfig(const ParameterSource& source) {
  LoopMotionConfig config;
  source.get("trajectory/speed", &config.speed);
  source.get("trajectory/laps", &config.laps);
  source.get("drift/enabled", &config.drift);
  config.odometry_drift = readOdometryDrift(source);
  config.localisation = readLocalisation(source);
  config.validate();
  return config;
}

LoopMotion::LoopMotion(const LoopMotionConfig& config, double frame_rate)
    : frame_rate_(frame_rate) {
  config.validate();
  if (!(frame_rate > 0.0)) throw std::invalid_argument("the frame rate must be positive");
  truth_ = sim::buildingLoopPath(config.speed / frame_rate, config.laps);
  if (!config.drift) {
    odometry_ = truth_;
    return;
  }
  odometry_ = sim::driftedOdometry(truth_, config.odometry_drift);
  track_ = sim::runLocalisation(truth_, odometry_, config.localisation);
}

int LoopMotion::frameAt(double seconds) const {
  // A hair above the exact product, so a stamp computed from a frame maps back to that frame.
  const double frame = std::floor(std::max(0.0, seconds) * frame_rate_ + 1e-6);
  return static_cast<int>(std::min(frame, static_cast<double>(frames() - 1)));
}

Eigen::Isometry3d LoopMotion::mapToOdom(int frame) const {
  return track_ ? track_->T_map_odom[frame] : Eigen::Isometry3d::Identity();
}

}  // namespace occupancy_fusion
