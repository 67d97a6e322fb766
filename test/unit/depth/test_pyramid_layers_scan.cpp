// Eq. 10's layers against an independent cell-by-cell scan of M: an odd-sized image (partial
// border cells), invalid pixels, and values placed symmetrically about the layers' distances
// so that different measurements tie and the scan order (rows of a cell top to bottom, each
// left to right, first one kept) decides. The large image's layers are built on two threads.
#include <gtest/gtest.h>
#include <omp.h>

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

void expectLayersEqualACellByCellScan(int width, int height) {
  CameraIntrinsics camera;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = 1e6;  // rays all but parallel: M equals the depth
  camera.cx = width / 2;
  camera.cy = height / 2;
  // t_0 = 16: t_i = 16, 8, 4, 2, 1, 0.5; 3 and 5 tie for t = 4, 6 and 10 for t = 8, ...
  const std::vector<float> values{0.75f, 1.5f, 2.5f, 3.0f, 5.0f, 6.0f, 10.0f, 12.0f, 20.0f};
  std::mt19937 random(7);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(values.size()) + 1);
  std::vector<float> depth(static_cast<std::size_t>(camera.width) * camera.height);
  for (float& z : depth) {
    const int index = pick(random);
    z = index < static_cast<int>(values.size()) ? values[index] : 0.0f;  // 0: invalid
  }
  const DepthImageView view{camera.width, camera.height, depth.data()};
  for (PyramidSelection selection :
       {PyramidSelection::kClosestToThreshold, PyramidSelection::kMinimum}) {
    const DistancePyramid pyramid(view, camera, 16.0, 6, 100.0, selection);
    ASSERT_EQ(pyramid.levels(), 6);
    int ties_decided = 0;
    for (int level = 1; level < pyramid.levels(); ++level) {
      ASSERT_EQ(pyramid.width(level), (camera.width + (1 << level) - 1) >> level);
      ASSERT_EQ(pyramid.height(level), (camera.height + (1 << level) - 1) >> level);
      for (int cv = 0; cv < pyramid.height(level); ++cv) {
        for (int cu = 0; cu < pyramid.width(level); ++cu) {
          const ScanResult expected = scanCell(pyramid, camera, level, cu, cv, selection);
          EXPECT_TRUE(sameBits(pyramid.at(level, cu, cv), expected.kept))
              << "level " << level << " cell " << cu << "," << cv;
          ties_decided += expected.tie;
        }
      }
    }
    if (selection == PyramidSelection::kClosestToThreshold) {
      EXPECT_GT(ties_decided, 0);  // the image really exercises the tie rule
    }
  }
}

// The layers built by `threads` OpenMP threads; the count is put back even when an assertion
// above returns early.
void expectLayersEqualACellByCellScan(int width, int height, int threads) {
  const int previous_threads = omp_get_max_threads();
  omp_set_num_threads(threads);
  expectLayersEqualACellByCellScan(width, height);
  omp_set_num_threads(previous_threads);
}

TEST(DistancePyramid, LayersEqualACellByCellScanIncludingTiesAndBorders) {
  expectLayersEqualACellByCellScan(37, 23, 1);
}

TEST(DistancePyramid, LayersOfALargeImageBuiltOnTwoThreadsEqualACellByCellScan) {
  // Above the sizes from which the layers are scanned, bucketed and merged on all threads, with
  // partial border cells at every level: a VGA and an HD depth image (at 1281 x 721 the 16 px
  // layer's merge ran on two threads before it ran at VGA size).
  expectLayersEqualACellByCellScan(641, 481, 2);
  expectLayersEqualACellByCellScan(1281, 721, 2);
}

}  // namespace
}  // namespace occupancy_fusion
