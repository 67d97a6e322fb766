// Eq. 10's coarse layers (merged from per-cell distance buckets) against an independent
// cell-by-cell scan of M on images built to make the float score |d - t_i| tie between
// different distances: values on both sides of a threshold at equal distance, and distances a
// few ulps apart far below a threshold, whose differences round to the same float.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"
#include "pyramid_reference_scan.h"

namespace occupancy_fusion {
namespace {

using test_support::sameBits;
using test_support::scanCell;
using test_support::ScanResult;

TEST(DistancePyramid, CoarseLayersEqualAScanWhenFloatScoresTie) {
  CameraIntrinsics camera;
  camera.width = 203;  // odd: partial border cells at every level
  camera.height = 141;
  camera.fx = camera.fy = 1e7;  // rays all but parallel: M equals the depth
  camera.cx = 101.0;
  camera.cy = 70.0;
  // t_0 = 64: t_i = 64, 32, ..., 0.125, all exact. 3 * 2^j and 5 * 2^j tie about t = 4 * 2^j;
  // 1 + a few ulps lie far below t = 64 .. 8, where |d - t| rounds several of them together.
  std::vector<float> values;
  for (int j = -3; j <= 4; ++j) {
    values.push_back(std::ldexp(3.0f, j));
    values.push_back(std::ldexp(5.0f, j));
  }
  for (int ulps = 0; ulps < 6; ++ulps) {
    float value = 1.0f;
    for (int step = 0; step < ulps; ++step) value = std::nextafter(value, 2.0f);
    values.push_back(value);
    values.push_back(std::ldexp(value, 1));
  }
  std::mt19937 random(11);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(values.size()));
  std::uniform_int_distribution<int> patch(0, 3);
  std::vector<float> depth(static_cast<std::size_t>(camera.width) * camera.height);
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      // Patches of one value class as well as per-pixel noise: cells within one bucket and
      // cells spanning several.
      const int index = (u / 16 + v / 16) % 4 == 0 ? pick(random) % 12 : pick(random);
      depth[static_cast<std::size_t>(v) * camera.width + u] =
          index < static_cast<int>(values.size()) && patch(random) > 0 ? values[index] : 0.0f;
    }
  }
  const DepthImageView view{camera.width, camera.height, depth.data()};
  const DistancePyramid pyramid(view, camera, 64.0, 10, 1000.0,
                                PyramidSelection::kClosestToThreshold);
  ASSERT_EQ(pyramid.levels(), 10);
  int coarse_ties = 0;
  for (int level = 1; level < pyramid.levels(); ++level) {
    for (int cv = 0; cv < pyramid.height(level); ++cv) {
      for (int cu = 0; cu < pyramid.width(level); ++cu) {
        const ScanResult expected = scanCell(pyramid, camera, level, cu, cv);
        EXPECT_TRUE(sameBits(pyramid.at(level, cu, cv), expected.kept))
            << "level " << level << " cell " << cu << "," << cv;
        if (level >= 3) coarse_ties += expected.tie;
      }
    }
  }
  EXPECT_GT(coarse_ties, 20);  // the scan order really decides many coarse cells
}

}  // namespace
}  // namespace occupancy_fusion
