// An independent reference for Eq. 10's pyramid layers, shared by the layer tests: the
// measurement a 2^level cell keeps, found by visiting its pixels of M in scan order (rows of the
// cell top to bottom, each left to right, the first best one kept).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"

namespace occupancy_fusion {
namespace test_support {

struct ScanResult {
  float kept = std::numeric_limits<float>::quiet_NaN();
  bool tie = false;  // another pixel with a different value had the same score
};

inline ScanResult scanCell(const DistancePyramid& pyramid, const CameraIntrinsics& camera,
                           int level, int cell_u, int cell_v,
                           PyramidSelection selection = PyramidSelection::kClosestToThreshold) {
  const int side = 1 << level;
  const float target = static_cast<float>(pyramid.threshold(level));
  ScanResult result;
  float best_score = std::numeric_limits<float>::infinity();
  for (int v = cell_v * side; v < std::min(camera.height, (cell_v + 1) * side); ++v) {
    for (int u = cell_u * side; u < std::min(camera.width, (cell_u + 1) * side); ++u) {
      const float value = pyramid.at(0, u, v);
      if (std::isnan(value)) continue;
      const float score =
          selection == PyramidSelection::kMinimum ? value : std::abs(value - target);
      if (score < best_score) {
        best_score = score;
        result.kept = value;
        result.tie = false;
      } else if (score == best_score && value != result.kept) {
        result.tie = true;
      }
    }
  }
  return result;
}

// Equal as bit patterns (NaN equals NaN): the layers must keep the very measurement of M.
inline bool sameBits(float a, float b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return std::memcmp(&a, &b, sizeof(float)) == 0;
}

}  // namespace test_support
}  // namespace occupancy_fusion
