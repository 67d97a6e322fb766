// Counter-based random numbers: each value is a hash of (seed, frame, pixel, ...), so noise is
// reproducible given the seed and does not depend on the order in which OpenMP threads run.
#pragma once

#include <cmath>
#include <cstdint>
#include <initializer_list>

namespace occupancy_fusion {
namespace sim {

// SplitMix64's finaliser: a bijective mix with good avalanche.
inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Hash of a sequence of integers (order matters).
inline std::uint64_t hashKey(std::initializer_list<std::uint64_t> parts) {
  std::uint64_t h = 0x6a09e667f3bcc909ULL;
  for (std::uint64_t part : parts) h = mix64(h ^ part);
  return h;
}

// Uniform in [0, 1) from the top 53 bits of a hash.
inline double uniform01(std::uint64_t hash) {
  return static_cast<double>(hash >> 11) * (1.0 / 9007199254740992.0);
}

// Standard normal from a key (Box-Muller on two derived uniforms).
inline double standardNormal(std::uint64_t key) {
  const double u1 = 1.0 - uniform01(mix64(key ^ 0x1ULL));  // (0, 1]: log is finite
  const double u2 = uniform01(mix64(key ^ 0x2ULL));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

}  // namespace sim
}  // namespace occupancy_fusion
