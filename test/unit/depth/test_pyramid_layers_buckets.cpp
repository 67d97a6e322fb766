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

// Every layer of `pyramid` against the scan, and M against Eq. 6 with the depth itself (the
// camera's rays are all but parallel). Returns the number of cells compared.
int expectLayersEqualAScan(const DistancePyramid& pyramid, const CameraIntrinsics& camera,
                           const std::vector<float>& depth) {
  int cells = 0;
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const float z = depth[static_cast<std::size_t>(v) * camera.width + u];
      const float expected = z > 0.0f ? z : std::numeric_limits<float>::quiet_NaN();
      EXPECT_TRUE(sameBits(pyramid.at(0, u, v), expected)) << "M at " << u << "," << v;
    }
  }
  for (int level = 1; level < pyramid.levels(); ++level) {
    for (int cv = 0; cv < pyramid.height(level); ++cv) {
      for (int cu = 0; cu < pyramid.width(level); ++cu, ++cells) {
        EXPECT_TRUE(
            sameBits(pyramid.at(level, cu, cv), scanCell(pyramid, camera, level, cu, cv).kept))
            << "level " << level << " cell " << cu << "," << cv;
      }
    }
  }
  return cells;
}

// The layers' storage and the bucket tables pass from one pyramid to the next on a thread: a
// pyramid after a larger one, with invalid pixels where the earlier one had values, and then a
// larger one again must not see anything of the earlier ones.
TEST(DistancePyramid, StorageTakenOverFromEarlierPyramidsHoldsNothingOfThem) {
  const std::vector<float> values{0.75f, 1.5f, 2.5f, 3.0f, 5.0f, 6.0f, 10.0f, 12.0f, 20.0f, 40.0f};
  std::mt19937 random(5);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(values.size()) - 1);
  const int sizes[3][2] = {{203, 141}, {150, 100}, {260, 170}};
  for (int image = 0; image < 3; ++image) {
    CameraIntrinsics camera;
    camera.width = sizes[image][0];
    camera.height = sizes[image][1];
    camera.fx = camera.fy = 1e7;
    camera.cx = camera.width / 2.0;
    camera.cy = camera.height / 2.0;
    std::vector<float> depth(static_cast<std::size_t>(camera.width) * camera.height);
    for (int v = 0; v < camera.height; ++v) {
      for (int u = 0; u < camera.width; ++u) {
        // The second image: its left half invalid, its right half within one bucket per cell.
        const bool invalid = image == 1 && u < camera.width / 2;
        const float value =
            image == 1 ? values[(u / 16 + v / 16) % values.size()] : values[pick(random)];
        depth[static_cast<std::size_t>(v) * camera.width + u] = invalid ? 0.0f : value;
      }
    }
    const DepthImageView view{camera.width, camera.height, depth.data()};
    const DistancePyramid pyramid(view, camera, 64.0, 10, 1000.0,
                                  PyramidSelection::kClosestToThreshold);
    ASSERT_EQ(pyramid.levels(), 10);
    EXPECT_GT(expectLayersEqualAScan(pyramid, camera, depth), 1000) << "image " << image;
  }
}

}  // namespace
}  // namespace occupancy_fusion
