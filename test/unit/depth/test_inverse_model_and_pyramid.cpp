// Eq. 7 (inverse sensor model), parameter validation, Eq. 6 (distance image) and Eq. 10-11
// (pyramid layers) against values worked out by hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"

namespace occupancy_fusion {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST(DepthInverseModel, Eq7ValuesByHand) {
  PyramidDepthConfig config;  // k = sigma = 0.6, as in the paper's Fig. 1
  const DepthInverseModel model(config);
  // Peak: 0.5 + k / (sigma sqrt(2 pi)) = 0.5 + 1 / sqrt(2 pi).
  EXPECT_NEAR(model.probability(10.0, 10.0), 0.8989422804014326, 1e-12);
  // One sigma in front: 0.3 + (0.398942 + 0.2) e^{-1/2}; one sigma behind: 0.5 + 0.398942 e^{-1/2}.
  EXPECT_NEAR(model.probability(9.4, 10.0), 0.6632768564616702, 1e-12);
  EXPECT_NEAR(model.probability(10.6, 10.0), 0.7419707245191435, 1e-12);
  // Far in front the linear part alone: 0.3.
  EXPECT_NEAR(model.probability(2.0, 10.0), 0.3, 1e-12);
  EXPECT_NEAR(model.logOdds(10.0, 10.0), 2.1855269934031014, 1e-6);
  EXPECT_NEAR(model.logOdds(9.4, 10.0), 0.6779314242308012, 1e-6);
  EXPECT_NEAR(model.logOdds(10.6, 10.0), 1.0562367382227462, 1e-6);
  EXPECT_NEAR(model.logOdds(2.0, 10.0), -0.8472978603872036, 1e-6);
  EXPECT_NEAR(model.logOdds(30.0, 10.0), 0.0, 1e-6);  // far behind: no evidence
}

TEST(DepthInverseModel, SigmaGrowsWithDistance) {
  PyramidDepthConfig config;
  config.sigma_quadratic = 0.01;  // sigma(10 m) = 0.6 + 0.01 * 100 = 1.6 m
  const DepthInverseModel model(config);
  EXPECT_NEAR(model.sigmaAt(10.0), 1.6, 1e-12);
  EXPECT_NEAR(model.probability(10.0, 10.0), 0.6496033551505372, 1e-12);
  // Unknown behind the surface beyond 3 sigma(measured).
  EXPECT_TRUE(model.informs(14.79, 10.0));
  EXPECT_FALSE(model.informs(14.81, 10.0));
}

void expectRejected(const PyramidDepthConfig& config, const std::string& field) {
  try {
    config.validate();
    FAIL() << "accepted a config with a bad " << field;
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find(field), std::string::npos) << error.what();
  }
}

// The default config with one field changed by `change` must be rejected, naming that field.
template <typename Change>
void expectDefaultRejectedWith(Change change, const std::string& field) {
  PyramidDepthConfig config;
  change(config);
  expectRejected(config, "PyramidDepthConfig." + field);
}

TEST(PyramidDepthConfig, RejectsBadParametersNamingTheField) {
  EXPECT_NO_THROW(PyramidDepthConfig().validate());
  PyramidDepthConfig config;
  config.k = 1.0;
  config.sigma = 0.4;  // peak 0.5 + 0.997: p > 1
  expectRejected(config, "PyramidDepthConfig.k");
  config.sigma = 0.8;  // k / (sigma sqrt(2 pi)) = 0.4987: just valid
  EXPECT_NO_THROW(config.validate());
  config.sigma = 0.79;  // 0.5050: invalid
  expectRejected(config, "sigma");
  expectDefaultRejectedWith([](PyramidDepthConfig& c) { c.sigma = 0.0; }, "sigma");
  expectDefaultRejectedWith([](PyramidDepthConfig& c) { c.k = -0.1; }, "k");
  expectDefaultRejectedWith([](PyramidDepthConfig& c) { c.sigma_quadratic = -0.01; },
                            "sigma_quadratic");
  expectDefaultRejectedWith([](PyramidDepthConfig& c) { c.max_range = 0.05; }, "max_range");
  expectDefaultRejectedWith([](PyramidDepthConfig& c) { c.min_range = -1.0; }, "min_range");
  expectDefaultRejectedWith([](PyramidDepthConfig& c) { c.unknown_behind_sigmas = 0.0; },
                            "unknown_behind_sigmas");
  config = PyramidDepthConfig();
  config.max_pyramid_levels = 0;
  expectRejected(config, "PyramidDepthConfig.max_pyramid_levels");
  EXPECT_THROW(PyramidDepthIntegrator{config}, std::invalid_argument);
  EXPECT_THROW(depthMethodFromString("octree"), std::invalid_argument);
  EXPECT_EQ(depthMethodFromString(toString(DepthMethod::kAndert)), DepthMethod::kAndert);
}

TEST(DistancePyramid, Eq6DistanceIsRayLengthTimesDepth) {
  CameraIntrinsics camera;
  camera.width = 4;
  camera.height = 4;
  camera.fx = camera.fy = 2.0;
  camera.cx = camera.cy = 1.5;
  std::vector<float> depth(16, 2.0f);
  const DepthImageView view{4, 4, depth.data()};
  const DistancePyramid pyramid(view, camera, 1.0, 1, 100.0, PyramidSelection::kMinimum);
  // Pixel (0, 0): ray (-0.75, -0.75, 1), length sqrt(2.125); pixel (3, 1): (0.75, -0.25, 1).
  EXPECT_NEAR(pyramid.at(0, 0, 0), 2.0 * std::sqrt(2.125), 1e-5);
  EXPECT_NEAR(pyramid.at(0, 3, 1), 2.0 * std::sqrt(1.625), 1e-5);
  // Beyond max_range (2 sqrt(2.125) = 2.915 m) the corner pixels are invalid.
  const DistancePyramid cut(view, camera, 1.0, 1, 2.9, PyramidSelection::kMinimum);
  EXPECT_TRUE(std::isnan(cut.at(0, 0, 0)));
  EXPECT_FALSE(std::isnan(cut.at(0, 1, 1)));
}

// A focal length so long that every ray has length 1 to 1e-12: M equals the depth image.
CameraIntrinsics flatCamera(int width, int height) {
  CameraIntrinsics camera;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = 1e6;
  camera.cx = 0.5 * (width - 1);
  camera.cy = 0.5 * (height - 1);
  return camera;
}

// A 4 x 4 depth image, row-major, v down, with invalid pixels (NaN, 0) and one beyond the
// pyramids' max_range of 20 m.
std::vector<float> mixedDepthImage() {
  return {1.0f, 3.9f,  7.0f,  0.0f,   //
          5.0f, 4.5f,  kNaN,  kNaN,   //
          2.1f, 9.0f,  50.0f, 0.0f,   // 50 m is beyond max_range
          6.0f, 1.85f, kNaN,  0.0f};  //
}

// The mixed image's pyramid with t0 = 40 m (t1 = 20, t2 = 10), max_range 20 m and `reach`.
DistancePyramid mixedPyramid(const MeasurementReach& reach) {
  const std::vector<float> depth = mixedDepthImage();
  return DistancePyramid({4, 4, depth.data()}, flatCamera(4, 4), 40.0, 3, 20.0,
                         PyramidSelection::kClosestToThreshold, &reach);
}

TEST(DistancePyramid, Eq10KeepsTheMeasurementClosestToEachLayersDistance) {
  // t0 = 8 so t1 = 4 and t2 = 2.
  const std::vector<float> depth = mixedDepthImage();
  const DepthImageView view{4, 4, depth.data()};
  const DistancePyramid closest(view, flatCamera(4, 4), 8.0, 3, 20.0,
                                PyramidSelection::kClosestToThreshold);
  ASSERT_EQ(closest.levels(), 3);
  EXPECT_DOUBLE_EQ(closest.threshold(1), 4.0);
  EXPECT_DOUBLE_EQ(closest.threshold(2), 2.0);
  ASSERT_EQ(closest.width(1), 2);
  ASSERT_EQ(closest.width(2), 1);
  EXPECT_FLOAT_EQ(closest.at(0, 1, 0), 3.9f);  // layer 0 is M itself
  EXPECT_TRUE(std::isnan(closest.at(0, 3, 0)));
  EXPECT_TRUE(std::isnan(closest.at(0, 2, 2)));
  // Layer 1, 2 x 2 blocks, closest to 4: {1, 3.9, 5, 4.5} -> 3.9; {7, -, -, -} -> 7;
  // {2.1, 9, 6, 1.85} -> 2.1 (|2.1 - 4| = 1.9 < |6 - 4| = 2); {50 (invalid), -, -, -} -> none.
  EXPECT_NEAR(closest.at(1, 0, 0), 3.9f, 1e-5);
  EXPECT_NEAR(closest.at(1, 1, 0), 7.0f, 1e-5);
  EXPECT_NEAR(closest.at(1, 0, 1), 2.1f, 1e-5);
  EXPECT_TRUE(std::isnan(closest.at(1, 1, 1)));
  // Layer 2, the whole image, closest to 2: 2.1 (|error| 0.1) beats 1.85 (0.15).
  EXPECT_NEAR(closest.at(2, 0, 0), 2.1f, 1e-5);

  const DistancePyramid minimum(view, flatCamera(4, 4), 8.0, 3, 20.0, PyramidSelection::kMinimum);
  EXPECT_NEAR(minimum.at(1, 0, 0), 1.0f, 1e-5);
  EXPECT_NEAR(minimum.at(1, 0, 1), 1.85f, 1e-5);
  EXPECT_NEAR(minimum.at(2, 0, 0), 1.0f, 1e-5);
}

TEST(DistancePyramid, LayersFinerThanAnyInformedVoxelReadsAreLeftInvalid) {
  const std::vector<float> depth = mixedDepthImage();
  const DepthImageView view{4, 4, depth.data()};
  // t0 = 40 so t1 = 20 and t2 = 10. Reach of the farthest valid distance (9 m) 9 + 3 x 0.1 m
  // <= t_2: every informed voxel reads layer 2 (and layer 0 beyond t_0), never layer 1, which is
  // left invalid. (Had the invalid 50 m counted, its reach beyond t_0 would need every layer.)
  const MeasurementReach near_reach{0.1, 0.0, 3.0};
  const DistancePyramid near(view, flatCamera(4, 4), 40.0, 3, 20.0,
                             PyramidSelection::kClosestToThreshold, &near_reach);
  for (int v = 0; v < 2; ++v) {
    for (int u = 0; u < 2; ++u) EXPECT_TRUE(std::isnan(near.at(1, u, v))) << u << " " << v;
  }
  EXPECT_FLOAT_EQ(near.at(2, 0, 0), 9.0f);  // closest to t_2 = 10
  EXPECT_FLOAT_EQ(near.at(0, 1, 0), 3.9f);
  // Reach 9 + 3 x 1 m lies in (t_2, t_1]: such voxels read layers 1 and 2, so layer 1 is built.
  const MeasurementReach far_reach{1.0, 0.0, 3.0};
  const DistancePyramid farther(view, flatCamera(4, 4), 40.0, 3, 20.0,
                                PyramidSelection::kClosestToThreshold, &far_reach);
  EXPECT_FLOAT_EQ(farther.at(1, 0, 0), 5.0f);  // closest to t_1 = 20 of 1, 3.9, 5, 4.5
  EXPECT_FLOAT_EQ(farther.at(1, 0, 1), 9.0f);
}

TEST(DistancePyramid, ReachOfSquareBoundsTheFourCellsAroundEachPosition) {
  const MeasurementReach reach{0.1, 0.02, 3.0};  // reach(9 m) = 9 + 3 (0.1 + 1.62) in (t_2, t_1]
  const DistancePyramid pyramid = mixedPyramid(reach);
  // Layer 0 is read by no informed voxel: no table, no bound.
  EXPECT_EQ(pyramid.reachOfSquare(0, 1, 1), std::numeric_limits<float>::infinity());
  for (int level = 1; level < pyramid.levels(); ++level) {
    for (int v = -1; v < pyramid.height(level); ++v) {
      for (int u = -1; u < pyramid.width(level); ++u) {
        // Independently: the farthest valid cell of the (up to) four inside the layer.
        float farthest = -std::numeric_limits<float>::infinity();
        for (int cv = v; cv <= v + 1; ++cv) {
          for (int cu = u; cu <= u + 1; ++cu) {
            if (cu < 0 || cv < 0 || cu >= pyramid.width(level) || cv >= pyramid.height(level))
              continue;
            const float cell = pyramid.at(level, cu, cv);
            if (!std::isnan(cell)) farthest = std::max(farthest, cell);
          }
        }
        const float bound = pyramid.reachOfSquare(level, u, v);
        SCOPED_TRACE(testing::Message() << "level " << level << " u " << u << " v " << v);
        if (farthest == -std::numeric_limits<float>::infinity()) {
          EXPECT_EQ(bound, farthest);  // no valid cell: nothing informed
          continue;
        }
        // The smallest float at least the reach: no wider than it must be.
        const double exact = reach.of(farthest);
        EXPECT_GE(static_cast<double>(bound), exact);
        EXPECT_LT(static_cast<double>(std::nextafter(bound, 0.0f)), exact);
      }
    }
  }
  // Layer 1 is [[5, 7], [9, none]] (closest to t_1 = 20; the lower right has no valid pixel).
  EXPECT_EQ(pyramid.reachOfSquare(1, 1, 1), -std::numeric_limits<float>::infinity());
  EXPECT_NEAR(pyramid.reachOfSquare(1, 1, 0), reach.of(7.0), 1e-5);
  EXPECT_NEAR(pyramid.reachOfSquare(1, -1, -1), reach.of(5.0), 1e-5);
  EXPECT_NEAR(pyramid.reachOfSquare(1, 0, 0), reach.of(9.0), 1e-5);
}

TEST(DistancePyramid, LevelCountStopsAtMinRangeOrOneCell) {
  CameraIntrinsics camera;  // 640 x 480
  // t0 = 40 m, min_range 0.1 m: t_9 = 0.078 m is the first t_i <= 0.1 m, and cells of
  // 2^8 = 256 px do not yet cover 640 px, so layers 0..9.
  EXPECT_EQ(DistancePyramid::levelCount(camera, 40.0, 0.1, 24), 10);
  EXPECT_EQ(DistancePyramid::levelCount(camera, 40.0, 0.1, 4), 4);
  // t0 = 0.4 m, min_range 0.1 m: t_2 = 0.1 is the first <= min_range: layers 0..2.
  EXPECT_EQ(DistancePyramid::levelCount(camera, 0.4, 0.1, 24), 3);
  // A 4 x 4 image: layer 2 is one cell, so no more layers whatever t.
  EXPECT_EQ(DistancePyramid::levelCount(flatCamera(4, 4), 1000.0, 0.1, 24), 3);
}

}  // namespace
}  // namespace occupancy_fusion
