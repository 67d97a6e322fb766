// Disparity to points with the stereo depth error of Eq. 7, and input sub-sampling.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "occupancy_fusion/sensors/disparity_image.h"

namespace occupancy_fusion {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST(DisparityPointsTest, Equation7ByHand) {
  // f = 500 px, b = 0.1 m, d = 10 px: z = 500 * 0.1 / 10 = 5 m. sigma_d = 0.5 px:
  // lambda = 0.5 / (0.1 * 500) = 0.01 / m, sigma_z = 0.01 * 25 = 0.25 m.
  EXPECT_DOUBLE_EQ(depthFromDisparity(10.0, 500.0, 0.1), 5.0);
  EXPECT_DOUBLE_EQ(depthErrorFactor(0.5, 0.1, 500.0), 0.01);
  EXPECT_DOUBLE_EQ(depthSigma(5.0, 0.01), 0.25);
}

TEST(DisparityPointsTest, PointsAndSigmasOfAFullResolutionImage) {
  // 4 x 2 image, cx = 1.5, cy = 0.5, fx = fy = 500, b = 0.1.
  const std::vector<float> disparity = {10, 20, kNaN, 0, 25, -1, 50, 10};
  const DisparityImageView view{4, 2, disparity.data(), 0};
  const StereoCamera camera{500.0, 500.0, 1.5, 0.5, 0.1};
  DisparityConversionConfig config;
  config.disparity_sigma_px = 0.5;
  const StereoPoints points = disparityToPoints(view, camera, config);
  EXPECT_EQ(points.pixels_read, 8u);
  ASSERT_EQ(points.size(), 5u);  // NaN, 0 and -1 are no matches
  // Pixel (0, 0), d = 10: z = 5, x = 5 * (0 - 1.5) / 500 = -0.015, y = 5 * (0 - 0.5) / 500.
  EXPECT_NEAR(points.points[0].x(), -0.015, 1e-6);
  EXPECT_NEAR(points.points[0].y(), -0.005, 1e-6);
  EXPECT_NEAR(points.points[0].z(), 5.0, 1e-6);
  EXPECT_NEAR(points.depth_sigmas[0], 0.25, 1e-7);
  // Pixel (1, 0), d = 20: z = 2.5, sigma = 0.01 * 6.25.
  EXPECT_NEAR(points.points[1].z(), 2.5, 1e-6);
  EXPECT_NEAR(points.depth_sigmas[1], 0.0625, 1e-7);
  // Pixel (2, 1), d = 50: z = 1, x = (2 - 1.5) / 500, y = (1 - 0.5) / 500, sigma = 0.01.
  EXPECT_NEAR(points.points[3].x(), 0.001, 1e-7);
  EXPECT_NEAR(points.points[3].y(), 0.001, 1e-7);
  EXPECT_NEAR(points.depth_sigmas[3], 0.01, 1e-8);
}

TEST(DisparityPointsTest, HalfAndQuarterResolutionReadEverySecondOrFourthPixel) {
  std::vector<float> disparity(8 * 8);
  for (int i = 0; i < 64; ++i) disparity[i] = 1.0f + i;  // unique per pixel
  const DisparityImageView view{8, 8, disparity.data(), 0};
  const StereoCamera camera{100.0, 100.0, 3.5, 3.5, 0.1};
  DisparityConversionConfig config;
  config.input_resolution = InputResolution::kHalf;
  const StereoPoints half = disparityToPoints(view, camera, config);
  ASSERT_EQ(half.size(), 16u);
  // The second point is pixel (2, 0): d = 3, z = 10 / 3.
  EXPECT_NEAR(half.points[1].z(), 10.0 / 3.0, 1e-5);
  // The fifth is pixel (0, 2): d = 17.
  EXPECT_NEAR(half.points[4].z(), 10.0 / 17.0, 1e-6);
  config.input_resolution = InputResolution::kQuarter;
  const StereoPoints quarter = disparityToPoints(view, camera, config);
  ASSERT_EQ(quarter.size(), 4u);
  EXPECT_NEAR(quarter.points[3].z(), 10.0 / 37.0, 1e-6);  // pixel (4, 4)
}

TEST(DisparityPointsTest, RowStrideAndMinimumDisparity) {
  const std::vector<float> padded = {10, 20, 99, 5, 40, 99};  // 2 x 2 with stride 3
  const DisparityImageView view{2, 2, padded.data(), 3};
  const StereoCamera camera{100.0, 100.0, 0.5, 0.5, 0.1};
  DisparityConversionConfig config;
  config.min_disparity_px = 8.0;
  const StereoPoints points = disparityToPoints(view, camera, config);
  ASSERT_EQ(points.size(), 3u);  // d = 5 is below the minimum, the 99s are padding
  EXPECT_NEAR(points.points[2].z(), 10.0 / 40.0, 1e-6);
}

TEST(DisparityPointsTest, PointsWithALargeRelativeDepthErrorAreDroppedAndCounted) {
  // f * b = 10 m px, sigma_d = 0.5 px: sigma_z / z = sigma_d / d.
  const std::vector<float> disparity = {10, 0.9f, 0.001f, 1.1f};  // ratios 0.05, 0.56, 500, 0.45
  const DisparityImageView view{4, 1, disparity.data(), 0};
  const StereoCamera camera{100.0, 100.0, 1.5, 0.0, 0.1};
  DisparityConversionConfig config;
  EXPECT_DOUBLE_EQ(config.max_depth_sigma_ratio, 0.5);  // the default drops d < 1 px
  const StereoPoints capped = disparityToPoints(view, camera, config);
  ASSERT_EQ(capped.size(), 2u);
  EXPECT_EQ(capped.dropped_uncertain, 2u);
  EXPECT_NEAR(capped.points[1].z(), 10.0 / 1.1, 1e-5);
  EXPECT_NEAR(capped.depth_sigmas[1], 0.05 * (10.0 / 1.1) * (10.0 / 1.1), 1e-5);
  config.max_depth_sigma_ratio = 0.6;  // keeps d = 0.9 px
  EXPECT_EQ(disparityToPoints(view, camera, config).size(), 3u);
  config.max_depth_sigma_ratio = -1.0;  // none
  const StereoPoints all = disparityToPoints(view, camera, config);
  EXPECT_EQ(all.size(), 4u);
  EXPECT_EQ(all.dropped_uncertain, 0u);
  EXPECT_NEAR(all.depth_sigmas[2], 0.05 * 1e4 * 1e4, 100.0);
  config.max_depth_sigma_ratio = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(config.validate(), std::invalid_argument);
}

TEST(DisparityPointsTest, ValidationNamesTheField) {
  DisparityConversionConfig config;
  config.disparity_sigma_px = -1;
  try {
    config.validate();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("disparity_sigma_px"), std::string::npos);
  }
  StereoCamera camera;
  camera.baseline = 0;
  EXPECT_THROW(camera.validate(), std::invalid_argument);
  EXPECT_EQ(inputResolutionFromString("quarter"), InputResolution::kQuarter);
  EXPECT_EQ(toString(InputResolution::kHalf), "half");
  EXPECT_THROW(inputResolutionFromString("third"), std::invalid_argument);
}

}  // namespace
}  // namespace occupancy_fusion
