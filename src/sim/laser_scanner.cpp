#include "occupancy_fusion/sim/laser_scanner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "occupancy_fusion/sim/deterministic_random.h"

namespace occupancy_fusion {
namespace sim {

void LaserScanner::validate() const {
  if (!std::isfinite(angle_min))
    throw std::invalid_argument("LaserScanner.angle_min must be finite");
  if (!(std::isfinite(angle_max) && angle_max >= angle_min)) {
    throw std::invalid_argument("LaserScanner.angle_max must be finite and >= angle_min");
  }
  if (!(std::isfinite(angle_increment) && angle_increment > 0)) {
    throw std::invalid_argument("LaserScanner.angle_increment must be positive and finite");
  }
  if (!(std::isfinite(range_min) && range_min >= 0)) {
    throw std::invalid_argument("LaserScanner.range_min must be finite and >= 0");
  }
  if (!(std::isfinite(range_max) && range_max > range_min)) {
    throw std::invalid_argument("LaserScanner.range_max must be finite and > range_min");
  }
  if (!(std::isfinite(noise_sigma) && noise_sigma >= 0)) {
    throw std::invalid_argument("LaserScanner.noise_sigma must be finite and >= 0");
  }
}

int LaserScanner::beamCount() const {
  return static_cast<int>(std::lround((angle_max - angle_min) / angle_increment)) + 1;
}

LaserScan renderScan(const Scene& scene, const LaserScanner& scanner,
                     const Eigen::Isometry3d& T_world_sensor, int frame_index) {
  scanner.validate();
  if (frame_index < 0) throw std::invalid_argument("frame_index must be >= 0");
  LaserScan scan;
  scan.angle_min = scanner.angle_min;
  scan.angle_increment = scanner.angle_increment;
  scan.range_min = scanner.range_min;
  scan.range_max = scanner.range_max;
  const int beams = scanner.beamCount();
  scan.angle_max = scan.angle(beams - 1);
  scan.ranges.resize(beams);
  const Eigen::Vector3d origin = T_world_sensor.translation();
#pragma omp parallel for schedule(static)
  for (int beam = 0; beam < beams; ++beam) {
    const double angle = scan.angle(beam);
    const Eigen::Vector3d direction =
        T_world_sensor.linear() * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
    const std::optional<double> range = scene.castRay(origin, direction, scanner.range_max);
    float value = std::numeric_limits<float>::infinity();
    if (range && *range < scanner.range_min) {
      value = -std::numeric_limits<float>::infinity();
    } else if (range) {
      double noisy = *range;
      if (scanner.noise_sigma > 0) {
        noisy += scanner.noise_sigma *
                 standardNormal(hashKey({scanner.seed, static_cast<std::uint64_t>(frame_index),
                                         static_cast<std::uint64_t>(beam)}));
      }
      value = static_cast<float>(std::clamp(noisy, scanner.range_min, scanner.range_max));
    }
    scan.ranges[beam] = value;
  }
  return scan;
}

}  // namespace sim
}  // namespace occupancy_fusion
