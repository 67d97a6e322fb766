// Random segments for the ray-walk tests: both ends uniform in a cube around the origin (so the
// walks cross voxel and block boundaries in both directions and at negative indices), and every
// 7th segment with no step along one axis.
#pragma once

#include <Eigen/Core>
#include <random>
#include <utility>

namespace occupancy_fusion {

// Segment i of a test's sequence, ends in [-extent, extent)^3; for i % 7 == 0 the end keeps the
// start's coordinate i % 3.
inline std::pair<Eigen::Vector3d, Eigen::Vector3d> randomSegment(std::mt19937& rng, int i,
                                                                 double extent) {
  std::uniform_real_distribution<double> coordinate(-extent, extent);
  const Eigen::Vector3d start(coordinate(rng), coordinate(rng), coordinate(rng));
  Eigen::Vector3d end(coordinate(rng), coordinate(rng), coordinate(rng));
  if (i % 7 == 0) end[i % 3] = start[i % 3];
  return {start, end};
}

}  // namespace occupancy_fusion
