// A 2D laser scan as the core's laser integrator reads it, and the REP-117
// reading of its ranges.
#pragma once

#include <vector>

namespace occupancy_fusion {

// The data-carrying fields of sensor_msgs/LaserScan. Beam i points at angle_min
// + i * angle_increment (rad) in the sensor's x-y plane, counter-clockwise from
// +x; angle_increment > 0.
struct LaserScan {
  double angle_min = 0.0;
  double angle_increment = 0.0;
  double range_min = 0.0; // m
  double range_max = 0.0; // m
  std::vector<float> ranges;

  int beamCount() const { return static_cast<int>(ranges.size()); }
  double angle(int beam) const { return angle_min + beam * angle_increment; }
  void validate() const; // throws std::invalid_argument naming the bad field
};

// Copies the fields shared with sensor_msgs::LaserScan and sim::LaserScan (both
// have the same names), so the core needs neither ROS nor the simulator.
template <typename ScanLike> LaserScan toLaserScan(const ScanLike &in) {
  LaserScan out;
  out.angle_min = in.angle_min;
  out.angle_increment = in.angle_increment;
  out.range_min = in.range_min;
  out.range_max = in.range_max;
  out.ranges.assign(in.ranges.begin(), in.ranges.end());
  return out;
}

// The scan a sensor_msgs/LaserScan-like message describes, checked: a finite,
// non-zero angle_increment (a negative one is the same scan listed backwards:
// returned reversed, with angle_increment > 0), as many ranges as angle_min,
// angle_max and angle_increment describe beams (within half an increment), and
// then LaserScan::validate(). Throws std::invalid_argument naming the problem.
// Ranges are not touched: classifyBeam reads each one.
LaserScan checkedLaserScan(double angle_min, double angle_max,
                           double angle_increment, double range_min,
                           double range_max, std::vector<float> ranges);

template <typename ScanMessage>
LaserScan checkedLaserScan(const ScanMessage &in) {
  return checkedLaserScan(in.angle_min, in.angle_max, in.angle_increment,
                          in.range_min, in.range_max,
                          std::vector<float>(in.ranges.begin(), in.ranges.end()));
}

// What one range reading says (REP-117).
enum class BeamKind {
  kHit,      // a detection at `range`, range_min <= range <= range_max
  kNoReturn, // nothing within range_max (+inf): free space up to a configured
             // length
  kTooClose, // something closer than range_min (-inf): no usable information
             // along the beam
  kInvalid, // NaN, or a finite value outside [range_min, range_max] (see below)
};

struct BeamReading {
  BeamKind kind = BeamKind::kInvalid;
  double range = 0.0; // m; meaningful for kHit only
};

struct LaserRangeConfig {
  // REP-117 says finite readings outside [range_min, range_max] are invalid,
  // and that is the default. Some drivers and logs (CARMEN: 81.83 m) store "no
  // return" as a finite value above range_max: set this to read those as
  // kNoReturn. Finite values below range_min stay kInvalid.
  bool above_range_max_is_no_return = false;

  void validate() const {} // every value is valid
};

BeamReading classifyBeam(float range, double range_min, double range_max,
                         const LaserRangeConfig &config);

} // namespace occupancy_fusion
