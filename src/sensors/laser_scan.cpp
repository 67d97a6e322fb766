#include "occupancy_fusion/sensors/laser_scan.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <stdexcept>

namespace occupancy_fusion {

void LaserScan::validate() const {
  if (!std::isfinite(angle_min))
    throw std::invalid_argument("LaserScan.angle_min must be finite");
  if (!(std::isfinite(angle_increment) && angle_increment > 0.0)) {
    throw std::invalid_argument(
        "LaserScan.angle_increment must be finite and > 0");
  }
  if (!(std::isfinite(range_min) && range_min >= 0.0)) {
    throw std::invalid_argument("LaserScan.range_min must be finite and >= 0");
  }
  if (!(std::isfinite(range_max) && range_max > range_min)) {
    throw std::invalid_argument(
        "LaserScan.range_max must be finite and > range_min");
  }
  if (ranges.empty())
    throw std::invalid_argument("LaserScan.ranges must not be empty");
}

LaserScan checkedLaserScan(double angle_min, double angle_max,
                           double angle_increment, double range_min,
                           double range_max, std::vector<float> ranges) {
  if (!std::isfinite(angle_increment) || angle_increment == 0.0) {
    throw std::invalid_argument("angle_increment is " +
                                std::to_string(angle_increment) +
                                " (must be finite and non-zero)");
  }
  if (!std::isfinite(angle_min) || !std::isfinite(angle_max)) {
    throw std::invalid_argument("angle_min or angle_max is not finite");
  }
  const std::size_t count = ranges.size();
  if (count == 0)
    throw std::invalid_argument("no ranges");
  // The last beam must point at angle_max (float fields: within half an
  // increment).
  const double last_angle =
      angle_min + (static_cast<double>(count) - 1.0) * angle_increment;
  if (!(std::abs(last_angle - angle_max) <= 0.5 * std::abs(angle_increment))) {
    const double expected =
        std::round((angle_max - angle_min) / angle_increment) + 1.0;
    throw std::invalid_argument(
        std::to_string(count) + " ranges, but angle_min, angle_max and " +
        "angle_increment describe " + std::to_string(expected) + " beams");
  }
  LaserScan scan;
  scan.angle_min = angle_min;
  scan.angle_increment = angle_increment;
  scan.range_min = range_min;
  scan.range_max = range_max;
  scan.ranges = std::move(ranges);
  if (angle_increment < 0.0) {
    scan.angle_min = last_angle;
    scan.angle_increment = -angle_increment;
    std::reverse(scan.ranges.begin(), scan.ranges.end());
  }
  scan.validate();
  return scan;
}

BeamReading classifyBeam(float range, double range_min, double range_max,
                         const LaserRangeConfig &config) {
  if (std::isnan(range))
    return {BeamKind::kInvalid, 0.0};
  if (std::isinf(range))
    return {range > 0 ? BeamKind::kNoReturn : BeamKind::kTooClose, 0.0};
  if (range > range_max) {
    return {config.above_range_max_is_no_return ? BeamKind::kNoReturn
                                                : BeamKind::kInvalid,
            0.0};
  }
  if (range < range_min)
    return {BeamKind::kInvalid, 0.0};
  return {BeamKind::kHit, static_cast<double>(range)};
}

} // namespace occupancy_fusion
