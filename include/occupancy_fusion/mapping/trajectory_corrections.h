// Where each submap belongs after a SLAM system corrected its trajectory (submap_fusion.h).
//
// A submap was written in the odometry frame and placed in the map by T_map_odom. A SLAM system
// that optimises its pose graph publishes its keyframes' poses in the map frame (T_map_base at
// each keyframe's stamp: LIO-SAM's mapping/path, RTAB-Map's mapPath); with the odometry's pose of
// the same body at the same stamp, each keyframe gives the correction
//   C(t) = T_map_base(t) * T_odom_base(t)^-1,
// the placement of the odometry frame that SLAM believes in at t. A submap takes the mean of the
// corrections of the keyframes within its time span (a stretch of odometry is smooth, so they
// differ little), or, with no keyframe in its span, the correction interpolated between the
// keyframes around it (the nearest one beyond either end of the path).
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <utility>
#include <vector>

#include "occupancy_fusion/mapping/frames.h"
#include "occupancy_fusion/mapping/submap_fusion.h"

namespace occupancy_fusion {

// Between two poses: translation linear, rotation by slerp; t in [0, 1].
Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double t);

// The mean of rigid transforms: mean translation, and the normalised sum of their quaternions
// (each turned to the first one's hemisphere), which is the rotation mean for nearby rotations.
Eigen::Isometry3d meanPose(const std::vector<Eigen::Isometry3d>& poses);

// The odometry's poses of the robot (T_odom_base) as frames came, in stamp order.
class OdometryTrack {
 public:
  // Stamps must not decrease (an earlier one is ignored: a clock jump is the caller's to handle
  // with clear()).
  void add(double stamp, const Eigen::Isometry3d& T_odom_base);
  // Interpolated between the recorded poses around stamp; nullopt outside their span, or where
  // the nearest two are more than max_gap seconds apart.
  std::optional<Eigen::Isometry3d> at(double stamp, double max_gap) const;
  bool empty() const { return poses_.empty(); }
  std::size_t size() const { return poses_.size(); }
  const std::vector<StampedPose>& poses() const { return poses_; }
  void clear() { poses_.clear(); }

 private:
  std::vector<StampedPose> poses_;
};

struct TrajectoryCorrectionConfig {
  // s: odometry poses farther apart than this are not interpolated between (the robot may have
  // moved anywhere in a gap).
  double max_odometry_gap = 1.0;

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// The corrections C(t) = T_map_base(t) * T_odom_base(t)^-1 at the path's keyframes where the
// odometry is known, in stamp order. `path`: T_map_base at the keyframes' stamps, in any order.
std::vector<StampedPose> correctionsAlongPath(const std::vector<StampedPose>& path,
                                              const OdometryTrack& odometry,
                                              const TrajectoryCorrectionConfig& config);

// The correction at `stamp`: interpolated between those around it, the nearest beyond their ends;
// nullopt without any.
std::optional<Eigen::Isometry3d> correctionAt(const std::vector<StampedPose>& corrections,
                                              double stamp);

// Each submap's placement (T_map_odom) by the corrections: the mean of those within its stamps,
// else the one interpolated at its middle. Submaps without stamps (fixed, or nothing written yet)
// and every submap when there is no correction are left out.
std::vector<std::pair<int, Eigen::Isometry3d>> placementsFromCorrections(
    const std::vector<StampedPose>& corrections, const std::vector<SubmapInfo>& submaps);

}  // namespace occupancy_fusion
