// The depth paper's Fig. 2 / Fig. 5 setup, shared by its unit test and `benchmark depth-fig5`:
// a 400 x 400 camera (f = 400) sees an obstacle at 6 m left of a vertical edge and one at 10 m
// right of it; map voxels of r = 0.1 m; k = sigma = 0.6 (PyramidDepthConfig's defaults).
#pragma once

#include <optional>
#include <vector>

#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"

namespace occupancy_fusion {

// Log-odds a method assigns to the map voxels on the optical axis (nullopt: left unchanged).
struct AxisProfile {
  std::vector<double> distance;  // voxel centres, 0.15 ... 12.35 m
  std::vector<std::optional<float>> log_odds;
};

// The edge lies `edge_offset` pixels right of the optical axis (a multiple of 0.5: the edge runs
// between pixel columns, so the principal point moves by half a pixel for half-integer offsets).
// finer_layers: PyramidDepthConfig's option of that name (0, the paper, by default).
AxisProfile fig5AxisProfile(DepthMethod method, double edge_offset = 0.0, int finer_layers = 0);

// Occupancy probability of a profile entry (Eq. 5); unknown reads as 0.5.
double profileProbability(const std::optional<float>& log_odds);

struct ProfileErrors {
  double mean = 0.0;
  double max = 0.0;
};

// Absolute occupancy-probability error against the ideal over the voxels the ideal observes.
ProfileErrors errorsAgainstIdeal(const AxisProfile& ideal, const AxisProfile& method);

}  // namespace occupancy_fusion
