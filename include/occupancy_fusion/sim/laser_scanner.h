// Simulated 2D laser scanner with sensor_msgs/LaserScan (REP-117) semantics.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "occupancy_fusion/sim/scene.h"

namespace occupancy_fusion {
namespace sim {

// Beam i points at angle angle_min + i * angle_increment (rad), measured in the sensor's x-y
// plane from +x towards +y; there are round((angle_max - angle_min) / angle_increment) + 1 beams.
// Defaults: a SICK LMS-like scanner, 361 beams over 180 degrees.
struct LaserScanner {
  double angle_min = -1.5707963267948966;         // rad
  double angle_max = 1.5707963267948966;          // rad
  double angle_increment = 0.008726646259971648;  // rad (0.5 deg)
  double range_min = 0.05;                        // m
  double range_max = 30.0;                        // m
  double noise_sigma = 0.0;  // m, white Gaussian range noise per beam and frame
  std::uint64_t seed = 1;

  void validate() const;  // throws std::invalid_argument naming the bad field
  int beamCount() const;
};

// The fields of sensor_msgs/LaserScan that carry data. Per beam (REP-117):
//  - a surface at true range r with range_min <= r <= range_max: r plus noise, the noisy value
//    clamped into [range_min, range_max] (a driver never reports a reading outside its limits);
//  - a surface closer than range_min: -inf (detection too close to measure);
//  - nothing within range_max: +inf (no return).
struct LaserScan {
  double angle_min = 0.0;
  double angle_max = 0.0;  // angle of the last beam
  double angle_increment = 0.0;
  double range_min = 0.0;
  double range_max = 0.0;
  std::vector<float> ranges;  // m

  double angle(int beam) const { return angle_min + beam * angle_increment; }
};

// Scans the scene from T_world_sensor. Noise is a hash of (seed, frame_index, beam), so a scan
// is reproducible.
LaserScan renderScan(const Scene& scene, const LaserScanner& scanner,
                     const Eigen::Isometry3d& T_world_sensor, int frame_index = 0);

}  // namespace sim
}  // namespace occupancy_fusion
