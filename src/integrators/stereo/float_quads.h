// Four floats as one value of GCC's and Clang's vector extension, whose
// operators act lane by lane: one SSE2 instruction each on plain x86-64. The measured surface
// works on many grid points at once with selections after comparisons, which GCC does not
// vectorise from loops over lanes (a comparison might trap); wider vector types are split into
// these anyway without AVX, and through memory. Internal to the stereo integrator.
#pragma once

#include <cstring>

// An AVX2 path (target attribute, run-time check) where the compiler can build it beside the
// baseline one.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define OCCUPANCY_FUSION_HAS_AVX2_PATH 1
#endif

namespace occupancy_fusion {

// Whether the processor runs the AVX2 paths (asked once).
inline bool processorHasAvx2() {
#ifdef OCCUPANCY_FUSION_HAS_AVX2_PATH
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
#else
  return false;
#endif
}

using FloatQuad = float __attribute__((vector_size(4 * sizeof(float))));
// Eight floats: one AVX register, for the functions built for AVX2 beside the baseline ones.
using FloatOctet = float __attribute__((vector_size(8 * sizeof(float))));

inline FloatQuad loadQuad(const float* values) {
  FloatQuad quad;
  std::memcpy(&quad, values, sizeof(quad));
  return quad;
}

inline void storeQuad(const FloatQuad& quad, float* values) {
  std::memcpy(values, &quad, sizeof(quad));
}

}  // namespace occupancy_fusion
