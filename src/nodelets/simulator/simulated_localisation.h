// The Simulator's robot on the building's corridor loop, with optional drifting odometry and a
// graph-SLAM stand-in (sim/odometry_drift.h, sim/localisation_stand_in.h): what its tf tree and
// its SLAM path say at each moment, and what the sensors see.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "occupancy_fusion/params/parameter_source.h"
#include "occupancy_fusion/sim/localisation_stand_in.h"
#include "occupancy_fusion/sim/odometry_drift.h"

namespace occupancy_fusion {

struct LoopMotionConfig {
  double speed = 1.0;  // m/s along the loop
  double laps = 1.25;  // then the robot stands at the end of its path
  bool drift = false;  // false: exact odometry and map -> odom the identity
  sim::OdometryDriftConfig odometry_drift;
  sim::LocalisationConfig localisation;

  void validate() const;  // throws std::invalid_argument naming the bad parameter
};

// trajectory/speed, trajectory/laps; drift/enabled, drift/seed, drift/scale (multiplies the four
// magnitudes drift/translation_noise, drift/scale_error, drift/heading_drift,
// drift/heading_noise); localisation/... (the fields of sim::LocalisationConfig). Validated.
LoopMotionConfig readLoopMotionConfig(const ParameterSource& source);

// The loop path sampled at frame_rate (one frame per tf tick), its odometry and the stand-in's
// track, computed once.
class LoopMotion {
 public:
  LoopMotion(const LoopMotionConfig& config, double frame_rate);

  // The frame the robot is at `seconds` after the start (the last one after the path's end).
  int frameAt(double seconds) const;
  int frames() const { return static_cast<int>(truth_.size()); }
  const Eigen::Isometry3d& truth(int frame) const { return truth_[frame]; }
  const Eigen::Isometry3d& odometry(int frame) const { return odometry_[frame]; }
  // map -> odom at `frame`: the identity without drift.
  Eigen::Isometry3d mapToOdom(int frame) const;
  // The SLAM stand-in's output; absent without drift.
  const std::optional<sim::LocalisationTrack>& track() const { return track_; }

 private:
  double frame_rate_;
  std::vector<Eigen::Isometry3d> truth_;
  std::vector<Eigen::Isometry3d> odometry_;
  std::optional<sim::LocalisationTrack> track_;
};

}  // namespace occupancy_fusion
