// A stand-in for graph SLAM: what a SLAM system publishes, per frame, for a robot whose true
// poses and drifted odometry are known. Between loop closures its estimate of the robot is the
// odometry placed by the last correction, so it drifts; at a loop closure it corrects the whole
// past (every keyframe to the truth) and map -> odom so that the estimate is right again.
#pragma once

#include <Eigen/Geometry>
#include <vector>

namespace occupancy_fusion {
namespace sim {

struct LocalisationConfig {
  // A keyframe is added when the odometry has moved this far from the last one (either test).
  double keyframe_distance = 1.0;  // m
  double keyframe_angle = 0.35;    // rad
  // A loop closes at a frame whose true position lies within closure_radius of the true position
  // of a keyframe added more than min_loop_length of travel earlier, at least
  // min_frames_between_closures frames after the previous correction.
  bool detect_loop_closures = true;
  double closure_radius = 1.5;           // m
  double min_loop_length = 20.0;         // m of true travel
  int min_frames_between_closures = 50;  // frames
  // Corrections also at frames N, 2N, ... (0: none): a regular schedule for tests.
  int correct_every_frames = 0;
  // What a correction leaves of the error: each corrected keyframe is the truth moved by a
  // Gaussian error of these standard deviations (planar position, yaw). 0: exactly the truth.
  double residual_translation_noise = 0.0;  // m
  double residual_heading_noise = 0.0;      // rad
  unsigned seed = 1;                        // of the residual errors

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// The stand-in's output for frames 0 .. n-1.
struct LocalisationTrack {
  // map -> odom as published at each frame; changes only at corrections.
  std::vector<Eigen::Isometry3d> T_map_odom;
  // Frames at which the past was corrected, ascending (a loop closure or the fixed schedule).
  std::vector<int> corrections;
  // The keyframes in order of addition: the frame each was added at (its stamp), its pose (base
  // in map) as estimated then, and its true pose. Frame 0 and every correction add a keyframe.
  std::vector<int> keyframe_frames;
  std::vector<Eigen::Isometry3d> keyframe_estimates;
  std::vector<Eigen::Isometry3d> keyframe_truth;
  // Corrected keyframe poses differ from the truth by seeded residual errors (config's).
  LocalisationConfig config;

  int frames() const { return static_cast<int>(T_map_odom.size()); }
  // How many keyframes exist at `frame` (those added at or before it).
  int keyframeCountAt(int frame) const;
  // The keyframe path (poses of base in map, in keyframe order, stamped keyframe_frames[i]) as
  // published at `frame`: each keyframe as estimated when added, or as corrected by the last
  // correction at or before `frame` that came at or after it.
  std::vector<Eigen::Isometry3d> pathAt(int frame) const;
  // True when the path published at `frame` differs from the one before: a keyframe was added or
  // a correction happened.
  bool pathChangedAt(int frame) const;
  // The last correction at or before `frame`, or -1 before the first.
  int lastCorrectionAt(int frame) const;
};

// Runs the stand-in over the true poses and the odometry (T_odom_base, e.g. driftedOdometry's) of
// the same frames. Frame 0 places odom so that the estimate starts at the truth. Throws
// std::invalid_argument when the two differ in length or the config is invalid.
LocalisationTrack runLocalisation(const std::vector<Eigen::Isometry3d>& T_map_base_truth,
                                  const std::vector<Eigen::Isometry3d>& T_odom_base,
                                  const LocalisationConfig& config = {});

}  // namespace sim
}  // namespace occupancy_fusion
