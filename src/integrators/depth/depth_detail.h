// Constants and checks shared by the stages of the depth integrator (this folder only).
#pragma once

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace occupancy_fusion {
namespace depth_detail {

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
inline constexpr float kInfinity = std::numeric_limits<float>::infinity();
// Per-frame passes over fewer pixels or cells than this run on one thread: an OpenMP region
// costs a barrier, and a descheduled thread on a shared machine holds it.
inline constexpr long kParallelPixels = 16384;

inline void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

inline bool isValidMeasurement(float value) { return !std::isnan(value); }

}  // namespace depth_detail
}  // namespace occupancy_fusion
