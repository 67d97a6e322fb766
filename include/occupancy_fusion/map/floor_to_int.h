// floor() of a double known to fit an int, as an int: the same value as
// static_cast<int>(std::floor(x)) without the rounding call (the build targets x86-64's baseline,
// which has no SSE4.1 round instruction, and GCC calls or expands floor() into a longer
// sequence). Precondition: x finite and -2^31 < x < 2^31.
#pragma once

namespace occupancy_fusion {

inline int floorToInt(double x) {
  const int truncated = static_cast<int>(x);  // towards zero
  return truncated - (x < truncated);
}

}  // namespace occupancy_fusion
