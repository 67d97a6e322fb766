#include "occupancy_fusion/sensors/laser_scan.h"

#include <cmath>
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
