#include "occupancy_fusion/map/occupancy_model.h"

#include <algorithm>
#include <stdexcept>

namespace occupancy_fusion {
namespace {

void requireOpenUnitInterval(double value, const char* name) {
  if (!(value > 0.0 && value < 1.0)) {
    throw std::invalid_argument(std::string(name) + " must be a probability in (0, 1), got " +
                                std::to_string(value));
  }
}

}  // namespace

void OccupancyModel::validate() const {
  requireOpenUnitInterval(prob_hit, "sensor_model/hit");
  requireOpenUnitInterval(prob_miss, "sensor_model/miss");
  requireOpenUnitInterval(clamp_min, "sensor_model/min");
  requireOpenUnitInterval(clamp_max, "sensor_model/max");
  requireOpenUnitInterval(occupancy_threshold, "occupancy_threshold");
  if (prob_hit <= 0.5) {
    throw std::invalid_argument(
        "sensor_model/hit must be above 0.5 (a hit raises occupancy), got " +
        std::to_string(prob_hit));
  }
  if (prob_miss >= 0.5) {
    throw std::invalid_argument(
        "sensor_model/miss must be below 0.5 (a miss lowers occupancy), got " +
        std::to_string(prob_miss));
  }
  if (clamp_min >= clamp_max) {
    throw std::invalid_argument("sensor_model/min (" + std::to_string(clamp_min) +
                                ") must be below sensor_model/max (" + std::to_string(clamp_max) +
                                ")");
  }
}

float OccupancyModel::clamp(float log_odds) const {
  return std::min(std::max(log_odds, minLogOdds()), maxLogOdds());
}

}  // namespace occupancy_fusion
