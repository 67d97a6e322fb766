// Wheel odometry that drifts: the true path's step-by-step motion, read with a scale error, a
// heading bias and random errors that grow with the distance travelled, integrated into the
// odometry frame. Deterministic per seed (counter-based noise, sim/deterministic_random.h).
#pragma once

#include <Eigen/Geometry>
#include <vector>

namespace occupancy_fusion {
namespace sim {

// Error magnitudes per metre travelled. The defaults give, over the building loop's 88 m, a few
// degrees of heading error and a few tenths of a metre to about 1 m of position error.
struct OdometryDriftConfig {
  unsigned seed = 1;
  double translation_noise = 0.01;  // m per sqrt(m): random walk along and across each step
  double scale_error = 0.005;       // fraction of the distance, systematic (odometry reads long)
  double heading_drift = 0.0008;    // rad per m, systematic (a turn bias, counter-clockwise)
  double heading_noise = 0.001;     // rad per sqrt(m): random walk of the heading

  // Every magnitude multiplied by `factor` (>= 0): 0 is exact odometry.
  OdometryDriftConfig scaled(double factor) const;
  void validate() const;  // throws std::invalid_argument naming the bad field
};

// T_odom_base per frame for the true poses T_map_base_truth: frame 0 equals the truth (odom starts
// where the robot does), then each frame adds the true step's planar motion in the body frame
// (x, y, yaw) with the configured errors; z, roll and pitch stay the truth's. Steps with no
// translation (turns in place) add no error.
std::vector<Eigen::Isometry3d> driftedOdometry(
    const std::vector<Eigen::Isometry3d>& T_map_base_truth, const OdometryDriftConfig& config);

// The yaw (rad, about z) of a pose whose z axis is near vertical.
double yawOf(const Eigen::Isometry3d& pose);

}  // namespace sim
}  // namespace occupancy_fusion
