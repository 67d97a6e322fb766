// MeasuredSurface: the depth a disparity image measures on a point's line of sight, robust
// against patches of wrong disparity, against a plane's analytic disparity.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "occupancy_fusion/integrators/stereo/measured_surface.h"

namespace occupancy_fusion {
namespace {

constexpr int kWidth = 160, kHeight = 120;
const StereoCamera kCamera{125.0, 125.0, 79.5, 59.5, 0.12};

// A slanted plane in the camera frame, n . p = c: its disparity is linear in (u, v),
// d = f b (n . ((u - cx) / fx, (v - cy) / fy, 1)) / c.
struct Plane {
  Eigen::Vector3d normal{0.3, -0.2, 1.0};
  double offset = 4.0;

  double disparity(double u, double v) const {
    const Eigen::Vector3d ray((u - kCamera.cx) / kCamera.fx, (v - kCamera.cy) / kCamera.fy, 1.0);
    return kCamera.fx * kCamera.baseline * normal.dot(ray) / offset;
  }
  double depth(double u, double v) const { return kCamera.fx * kCamera.baseline / disparity(u, v); }
};

std::vector<float> planeImage(const Plane& plane) {
  std::vector<float> image(static_cast<std::size_t>(kWidth) * kHeight);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      image[static_cast<std::size_t>(v) * kWidth + u] = static_cast<float>(plane.disparity(u, v));
    }
  }
  return image;
}

MeasuredSurface surfaceOf(const std::vector<float>& image,
                          const MeasuredSurfaceConfig& config = {}) {
  const DisparityImageView view{kWidth, kHeight, image.data(), 0};
  return MeasuredSurface(view, kCamera, Eigen::Isometry3d::Identity(), config);
}

// The point at depth z on pixel (u, v)'s line of sight, in the camera (= map) frame.
Eigen::Vector3d pointAt(double u, double v, double z) {
  return {z * (u - kCamera.cx) / kCamera.fx, z * (v - kCamera.cy) / kCamera.fy, z};
}

double surfaceDepth(const MeasuredSurface& surface, double u, double v) {
  double z = 0, z_surface = 0;
  if (!surface.depthAt(pointAt(u, v, 2.0), &z, &z_surface)) return std::nan("");
  EXPECT_NEAR(z, 2.0, 1e-9);
  return z_surface;
}

TEST(MeasuredSurface, GivesAPlanesDepthAtEveryPixel) {
  const Plane plane;
  // The default window (25 values to a median) and a wider one (61).
  MeasuredSurfaceConfig wide;
  wide.window_px = 41;
  for (const MeasuredSurfaceConfig& config : {MeasuredSurfaceConfig(), wide}) {
    const MeasuredSurface surface = surfaceOf(planeImage(plane), config);
    // Up to the image's borders, its last column and row included (not its very corners, where
    // no window has enough symmetric pairs).
    for (double v : {2.0, 13.3, 59.5, 101.7, 119.0}) {
      for (double u : {2.0, 7.2, 79.5, 120.9, 159.0}) {
        EXPECT_NEAR(surfaceDepth(surface, u, v), plane.depth(u, v), 1e-4 * plane.depth(u, v))
            << "pixel " << u << ", " << v << ", window " << config.window_px;
      }
    }
  }
}

TEST(MeasuredSurface, KeepsAPlanesDepthNextToInvalidPixels) {
  // Beyond a diagonal line nothing is measured (a range limit): one-sided windows would read a
  // slanted plane as its nearer part; symmetric pairs do not.
  const Plane plane;
  std::vector<float> image = planeImage(plane);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      if (u + v > 170) image[static_cast<std::size_t>(v) * kWidth + u] = std::nanf("");
    }
  }
  const MeasuredSurface surface = surfaceOf(image);
  int checked = 0;
  for (int v = 40; v < kHeight; v += 7) {
    const int u = 168 - v;  // 2 px inside the valid part
    if (u < 0 || u >= kWidth) continue;
    const double measured = surfaceDepth(surface, u, v);
    if (std::isnan(measured)) continue;  // too few pairs: the image does not say
    EXPECT_NEAR(measured, plane.depth(u, v), 1e-3 * plane.depth(u, v))
        << "pixel " << u << ", " << v;
    ++checked;
  }
  EXPECT_GE(checked, 8);
}

TEST(MeasuredSurface, ReachesTheRangeLimit) {
  // Nothing measured from column 62 on (a range limit between grid nodes 60 and 64, at the default
  // 4 px): node 64 has no symmetric pair, and the pixels from 60 to 62 read their cell's two
  // valid corners and the plane extrapolated one node on, not nothing.
  const Plane plane;
  std::vector<float> image = planeImage(plane);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 62; u < kWidth; ++u) image[static_cast<std::size_t>(v) * kWidth + u] = NAN;
  }
  const MeasuredSurface surface = surfaceOf(image);
  for (double v : {10.0, 37.5, 59.5, 90.2}) {
    for (double u : {60.5, 61.0, 61.9}) {
      EXPECT_NEAR(surfaceDepth(surface, u, v), plane.depth(u, v), 1e-3 * plane.depth(u, v))
          << "pixel " << u << ", " << v;
    }
  }
  // Two nodes past the limit the image does not say.
  EXPECT_TRUE(std::isnan(surfaceDepth(surface, 69.0, 59.5)));
}

// A fronto-parallel plane at 3 m left of column `edge` and one at 3.5 m from it on (a doorway's
// jamb against the wall behind it: 0.71 px of disparity, within the small window's inlier_px).
std::vector<float> stepImage(int edge, double near = 3.0, double far = 3.5) {
  std::vector<float> image(static_cast<std::size_t>(kWidth) * kHeight);
  const double focal_baseline = kCamera.fx * kCamera.baseline;
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      image[static_cast<std::size_t>(v) * kWidth + u] =
          static_cast<float>(focal_baseline / (u < edge ? near : far));
    }
  }
  return image;
}

TEST(MeasuredSurface, DoesNotInterpolateAcrossAStep) {
  // The outline midway between grid nodes 80 and 84. Across it every pixel reads one of the two
  // surfaces (node 80's small window reaches across it: 3 % off), none a surface in between that
  // no pixel sees; interpolating across the step, pixels 80 to 84 do.
  const std::vector<float> image = stepImage(82);
  auto depthsBetween = [&](const MeasuredSurface& surface) {
    int between = 0;
    for (double u = 60; u <= 100; u += 0.5) {
      const double z = surfaceDepth(surface, u, 59.5);
      EXPECT_FALSE(std::isnan(z)) << "pixel " << u;
      if (z > 3.0 * 1.05 && z < 3.5 / 1.05) ++between;
    }
    return between;
  };
  const MeasuredSurface surface = surfaceOf(image);
  EXPECT_EQ(depthsBetween(surface), 0);
  MeasuredSurfaceConfig interpolating;
  interpolating.step_px = 0;
  EXPECT_GE(depthsBetween(surfaceOf(image, interpolating)), 4);
  // The outline where it is, each side's own depth.
  for (double u : {60.0, 70.0, 75.0}) EXPECT_NEAR(surfaceDepth(surface, u, 30.0), 3.0, 1e-4);
  for (double u : {78.0, 81.5}) EXPECT_NEAR(surfaceDepth(surface, u, 30.0), 3.0, 0.1);
  for (double u : {82.0, 84.0, 99.0}) EXPECT_NEAR(surfaceDepth(surface, u, 30.0), 3.5, 1e-4);
}

TEST(MeasuredSurface, PutsNoSurfaceIntoTheGapOfAWideStep) {
  // An object's outline at 2 m against a wall at 4 m (7.5 against 3.75 px), one pixel past grid
  // node 80: node 80's wide window pairs 21 of its 25 samples across the outline, and the median
  // of the pair means (5.6 px, 2.7 m) is a surface no pixel sees, with no small-window pixel
  // within inlier_px of it. The node reads one side instead, and so does every pixel.
  const MeasuredSurface surface = surfaceOf(stepImage(81, 2.0, 4.0));
  for (double u = 60; u <= 100; u += 0.5) {
    const double z = surfaceDepth(surface, u, 59.5);
    EXPECT_TRUE(std::abs(z - 2.0) < 0.02 || std::abs(z - 4.0) < 0.04) << "pixel " << u << ": " << z;
  }
  EXPECT_NEAR(surfaceDepth(surface, 80, 59.5), 2.0, 1e-4);  // the node's own pixel is near
  EXPECT_NEAR(surfaceDepth(surface, 88, 59.5), 4.0, 1e-4);
}

TEST(MeasuredSurface, IgnoresPatchesOfWrongDisparity) {
  // A patch of 12 x 12 px shifted away from the camera (a hole through which the space behind
  // the plane looks visible) and one shifted towards it (a phantom surface in front).
  const Plane plane;
  std::vector<float> image = planeImage(plane);
  auto shift = [&](int u0, int v0, float offset) {
    for (int v = v0; v < v0 + 12; ++v) {
      for (int u = u0; u < u0 + 12; ++u) image[static_cast<std::size_t>(v) * kWidth + u] += offset;
    }
  };
  shift(40, 40, -1.5f);
  shift(100, 60, +1.5f);
  const MeasuredSurface surface = surfaceOf(image);
  for (const auto& [u, v] : {std::pair<double, double>{46, 46}, {41, 51}, {106, 66}, {111, 61}}) {
    const double truth = plane.depth(u, v);
    // The patch itself is 0.1 to 0.3 m off (1.5 px at 3-6 px of disparity).
    const double patch_depth =
        kCamera.fx * kCamera.baseline / (plane.disparity(u, v) + (u < 80 ? -1.5 : 1.5));
    ASSERT_GT(std::abs(patch_depth - truth), 0.3);
    EXPECT_NEAR(surfaceDepth(surface, u, v), truth, 0.02 * truth) << "pixel " << u << ", " << v;
  }
}

TEST(MeasuredSurface, GridPointsAtTheBorderAreExtrapolatedFromThoseInside) {
  // A curved surface (disparity quadratic in u and v): the grid points nearer to the border
  // than a sample step read the linear extrapolation of the two inside them, which the curvature
  // tells apart from their own windows' medians (the exact disparity, without noise).
  std::vector<float> image(static_cast<std::size_t>(kWidth) * kHeight);
  auto truth = [](double u, double v) {
    return 5.0 + 0.002 * (u - 70.0) * (u - 70.0) + 0.001 * (v - 50.0) * (v - 50.0);
  };
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      image[static_cast<std::size_t>(v) * kWidth + u] = static_cast<float>(truth(u, v));
    }
  }
  MeasuredSurfaceConfig cut_windows;
  cut_windows.border_from_interior = false;
  const MeasuredSurface surface = surfaceOf(image), own = surfaceOf(image, cut_windows);
  ASSERT_EQ(surface.gridStep(), 4);
  auto read = [](const MeasuredSurface& s, double u, double v) {
    return kCamera.fx * kCamera.baseline / surfaceDepth(s, u, v);
  };
  for (const double v : {20.0, 60.0, 96.0}) {
    for (const auto& [border, near, far] :
         {std::tuple<double, double, double>{156, 152, 148}, {0, 4, 8}}) {
      const double extrapolated = 2.0 * read(surface, near, v) - read(surface, far, v);
      EXPECT_NEAR(read(surface, border, v), extrapolated, 1e-4) << border << ", " << v;
      // The extrapolation misses the curvature by 2 x 0.002 x 4^2 = 0.064 px, and differs from
      // what the grid point's own window gives: at u = 156 the surface within the small window's
      // bias; at u = 0, where the small window is cut too, the upper median of its four values,
      // 0.064 px above it.
      EXPECT_GT(std::abs(read(surface, border, v) - truth(border, v)), 0.04);
      EXPECT_GT(std::abs(read(surface, border, v) - read(own, border, v)), 0.04);
      if (border > 0) {
        EXPECT_NEAR(read(own, border, v), truth(border, v), 0.02) << v;
      }
    }
  }
  // Likewise at the top and bottom (grid rows 0 and 116 of 0 ... 119).
  for (const auto& [border, near, far] :
       {std::tuple<double, double, double>{0, 4, 8}, {116, 112, 108}}) {
    const double extrapolated = 2.0 * read(surface, 60, near) - read(surface, 60, far);
    EXPECT_NEAR(read(surface, 60, border), extrapolated, 1e-4) << border;
  }
}

TEST(MeasuredSurface, SaysNothingOutsideTheImageOrBehindTheCamera) {
  const Plane plane;
  const MeasuredSurface surface = surfaceOf(planeImage(plane));
  double z = 0, z_surface = 0;
  EXPECT_FALSE(surface.depthAt({0.0, 0.0, -1.0}, &z, &z_surface));           // behind
  EXPECT_FALSE(surface.depthAt(pointAt(-5.0, 60.0, 2.0), &z, &z_surface));   // left of the image
  EXPECT_FALSE(surface.depthAt(pointAt(80.0, 125.0, 2.0), &z, &z_surface));  // below it
  EXPECT_FALSE(MeasuredSurface().depthAt(pointAt(80.0, 60.0, 2.0), &z, &z_surface));
  // An image without valid disparity measures nothing.
  const std::vector<float> empty(static_cast<std::size_t>(kWidth) * kHeight,
                                 std::numeric_limits<float>::quiet_NaN());
  EXPECT_FALSE(surfaceOf(empty).depthAt(pointAt(80.0, 60.0, 2.0), &z, &z_surface));
}

TEST(MeasuredSurface, ReadsTheBorderPixelJustOutsideTheImageWithinTheReach) {
  // A voxel that rays through the border pixels cross can have its centre outside the image; within
  // reach_m (projected at the point's depth: 0.1 m at 2 m is 6.25 px here) it reads the surface of
  // the nearest border pixel.
  const Plane plane;
  const MeasuredSurface surface = surfaceOf(planeImage(plane));
  double z = 0, z_surface = 0;
  ASSERT_TRUE(surface.depthAt(pointAt(-5.0, 60.0, 2.0), &z, &z_surface, 0.1));
  EXPECT_NEAR(z, 2.0, 1e-9);
  EXPECT_NEAR(z_surface, plane.depth(0.0, 60.0), 0.005);
  ASSERT_TRUE(surface.depthAt(pointAt(kWidth + 3.0, kHeight + 5.0, 2.0), &z, &z_surface, 0.1));
  EXPECT_NEAR(z_surface, plane.depth(kWidth - 1.0, kHeight - 1.0), 0.005);
  // Farther out than the reach, or nearer the camera (where 0.1 m projects wider) still inside it.
  EXPECT_FALSE(surface.depthAt(pointAt(-7.0, 60.0, 2.0), &z, &z_surface, 0.1));
  EXPECT_TRUE(surface.depthAt(pointAt(-7.0, 60.0, 1.0), &z, &z_surface, 0.1));
}

TEST(MeasuredSurface, ReadsTheNearestSurfaceWithinTheReachWhereThePixelHasNone) {
  // Columns from 100 on without disparity (beyond the matcher's range): the grid's surfaces end at
  // the node of column 100 (extrapolated from its neighbours). A voxel whose centre projects to
  // column 112 reads that node's surface where 12 px lie within its reach's projection.
  const Plane plane;
  std::vector<float> image = planeImage(plane);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 100; u < kWidth; ++u) {
      image[static_cast<std::size_t>(v) * kWidth + u] = std::numeric_limits<float>::quiet_NaN();
    }
  }
  const MeasuredSurface surface = surfaceOf(image);
  ASSERT_EQ(surface.gridStep(), 4);
  double z = 0, z_surface = 0;
  EXPECT_FALSE(surface.depthAt(pointAt(112.0, 60.0, 1.0), &z, &z_surface));  // no reach
  // 0.1 m is 6.25 px at 2 m and 12.5 px at 1 m.
  EXPECT_FALSE(surface.depthAt(pointAt(112.0, 60.0, 2.0), &z, &z_surface, 0.1));
  ASSERT_TRUE(surface.depthAt(pointAt(112.0, 60.0, 1.0), &z, &z_surface, 0.1));
  EXPECT_NEAR(z, 1.0, 1e-9);
  EXPECT_NEAR(z_surface, plane.depth(100.0, 60.0), 0.01 * plane.depth(100.0, 60.0));
  // The nearest node, not any: from row 61.5 the node of row 60 (1.5 px) and not that of row 64.
  ASSERT_TRUE(surface.depthAt(pointAt(111.0, 61.5, 1.0), &z, &z_surface, 0.1));
  EXPECT_NEAR(z_surface, plane.depth(100.0, 60.0), 0.002 * plane.depth(100.0, 60.0));
}

TEST(MeasuredSurface, GridFollowsTheSmallestVoxelImage) {
  // A voxel of size r at depth z = f b / d is r d / b px wide, whatever f.
  std::vector<float> image(static_cast<std::size_t>(kWidth) * kHeight, 12.0f);
  image[5 * kWidth + 7] = 3.0f;
  const DisparityImageView view{kWidth, kHeight, image.data(), 0};
  MeasuredSurfaceConfig config;
  config.grid_max_step_px = 0;  // the window's width
  auto step = [&](double fraction, double voxel, double min_disparity, double max_range) {
    config.grid_footprint_fraction = fraction;
    SurfaceGridScale scale;
    scale.voxel_size_m = voxel;
    scale.min_disparity_px = min_disparity;
    scale.max_range_m = max_range;
    return MeasuredSurface::gridStepFor(view, kCamera, config, scale);
  };
  // The pixel at d = 3 is off the 4 px sample lattice that the rule reads, so the smallest
  // disparity is 12 px: 0.2 m there is 20 px.
  EXPECT_EQ(step(1.0, 0.2, 0.0, -1.0), 20);
  EXPECT_EQ(step(0.5, 0.2, 0.0, -1.0), 8);   // 10 px, down to a multiple of the 4 px samples
  EXPECT_EQ(step(0.25, 0.2, 0.0, -1.0), 4);  // 5 px
  EXPECT_EQ(step(1.0, 1.0, 0.0, -1.0), 24);  // 100 px: at most the 25 px window
  EXPECT_EQ(step(1.0, 0.02, 0.0, -1.0), 4);  // 2 px: never finer than grid_step_px
  EXPECT_EQ(step(0.0, 0.2, 0.0, -1.0), 4);   // fraction 0: the fixed grid
  EXPECT_EQ(step(1.0, 0.0, 0.0, -1.0), 4);   // no voxel size: the fixed grid
  config.grid_max_step_px = 12;
  EXPECT_EQ(step(1.0, 0.2, 0.0, -1.0), 12);  // 20 px, at most grid_max_step_px
  EXPECT_EQ(step(0.5, 0.2, 0.0, -1.0), 8);
  config.grid_max_step_px = 0;
  // A farther pixel on the lattice: 0.2 m at d = 3 px is 5 px.
  image[8 * kWidth + 12] = 3.0f;
  EXPECT_EQ(step(1.0, 0.2, 0.0, -1.0), 4);
  // ... unless the rays drop it (below min_disparity), or end nearer than its depth: the rays
  // reach 2.5 m at most, where 0.2 m is f b / 2.5 * 0.2 / b = 10 px.
  EXPECT_EQ(step(1.0, 0.2, 5.0, -1.0), 20);
  EXPECT_EQ(step(1.0, 0.2, 0.0, 2.5), 8);
  // An image without a valid disparity keeps the fixed grid.
  std::vector<float> empty(image.size(), std::numeric_limits<float>::quiet_NaN());
  const DisparityImageView nothing{kWidth, kHeight, empty.data(), 0};
  config.grid_footprint_fraction = 1.0;
  EXPECT_EQ(MeasuredSurface::gridStepFor(nothing, kCamera, config, {0.2, 0.0, -1.0}), 4);
}

TEST(MeasuredSurface, ReadsAPlaneAlikeOnACoarseGrid) {
  // A plane is linear in disparity: a 16 px grid reads it as the 4 px grid does.
  const Plane plane;
  const std::vector<float> image = planeImage(plane);
  const DisparityImageView view{kWidth, kHeight, image.data(), 0};
  MeasuredSurfaceConfig config;
  config.grid_footprint_fraction = 1.0;
  config.grid_max_step_px = 0;
  SurfaceGridScale scale;
  scale.voxel_size_m = 2.0;  // over 30 px at the plane's far side: the widest grid
  const MeasuredSurface coarse(view, kCamera, Eigen::Isometry3d::Identity(), config, scale);
  ASSERT_EQ(coarse.gridStep(), 24);
  for (double v : {13.3, 59.5, 101.7}) {
    for (double u : {7.2, 79.5, 120.9}) {
      EXPECT_NEAR(surfaceDepth(coarse, u, v), plane.depth(u, v), 1e-4 * plane.depth(u, v))
          << "pixel " << u << ", " << v;
    }
  }
}

// A grid node's surface by the definition in measured_surface.h, one node at a time with
// std::nth_element: the upper median of the wide window's symmetric sample pairs, then the small
// window's inlier mean, or beside a step the median of the window's own samples.
float nodeByDefinition(const std::vector<float>& image, int width, int height, int u, int v,
                       const MeasuredSurfaceConfig& config) {
  const float kNaN = std::numeric_limits<float>::quiet_NaN();
  auto at = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= width || y >= height) return kNaN;
    const float d = image[static_cast<std::size_t>(y) * width + x];
    return std::isfinite(d) && d > 0 ? d : kNaN;
  };
  auto upperMedian = [](std::vector<float> values) {
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
  };
  const int sample = config.sample_step_px, reach = config.window_px / 2 / sample;
  std::vector<float> pair_means, samples;
  for (int dj = -reach; dj <= reach; ++dj) {
    for (int di = -reach; di <= reach; ++di) {
      const float first = at(u + di * sample, v + dj * sample);
      const bool earlier_half = dj < 0 || (dj == 0 && di < 0);
      if (earlier_half) {
        const float second = at(u - di * sample, v - dj * sample);
        if (!std::isnan(first) && !std::isnan(second))
          pair_means.push_back(0.5f * (first + second));
      }
      if ((di + dj) % 2 == 0 && !std::isnan(first)) samples.push_back(first);
    }
  }
  if (!std::isnan(at(u, v))) pair_means.push_back(at(u, v));
  const int per_side = 2 * reach + 1;
  const double needed = std::ceil(config.min_valid * (per_side * per_side + 1) / 2);
  if (pair_means.empty() || pair_means.size() < needed) return kNaN;
  const float robust = upperMedian(pair_means);
  // The small window's pixel pairs (both in the image and valid), and those near `reference`.
  const int local = config.local_window_px / 2;
  auto localMean = [&](float reference, int* valid, int* inliers) {
    double sum = 0;
    *valid = *inliers = 0;
    for (int dv = -local; dv <= local; ++dv) {
      for (int du = -local; du <= local; ++du) {
        if (dv > 0 || (dv == 0 && du > 0)) continue;
        const float first = at(u + du, v + dv);
        const float second = (du == 0 && dv == 0) ? first : at(u - du, v - dv);
        if (std::isnan(first) || std::isnan(second)) continue;
        ++*valid;
        if (std::abs(first - reference) > config.inlier_px ||
            std::abs(second - reference) > config.inlier_px) {
          continue;
        }
        ++*inliers;
        sum += (du == 0 && dv == 0) ? first : 0.5 * (first + second);
      }
    }
    return *inliers > 0 ? static_cast<float>(sum / *inliers) : kNaN;
  };
  int valid = 0, inliers = 0;
  const float mean = localMean(robust, &valid, &inliers);
  if (inliers >= 4) return mean;
  if (valid < 4 || samples.empty()) return robust;
  const float one_side = upperMedian(samples);
  const float side_mean = localMean(one_side, &valid, &inliers);
  return inliers >= 4 ? side_mean : one_side;
}

// A slanted plane with a nearer box on it (steps), pixel noise, holes and patches of wrong
// disparity; an odd size, so that rows of nodes end in part groups and next to the borders.
constexpr int kOddWidth = 203, kOddHeight = 77;
const StereoCamera kOddCamera{125.0, 125.0, 101.0, 38.0, 0.12};
std::vector<float> noisyImageWithHolesAndPatches() {
  std::mt19937 random(11);
  std::normal_distribution<float> noise(0.0f, 0.3f);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> image(static_cast<std::size_t>(kOddWidth) * kOddHeight);
  for (int v = 0; v < kOddHeight; ++v) {
    for (int u = 0; u < kOddWidth; ++u) {
      const bool box = u > 60 && u < 110 && v > 20 && v < 50;
      float d = 4.0f + 0.02f * u - 0.01f * v + (box ? 3.0f : 0.0f) + noise(random);
      if ((u / 16 + v / 16) % 5 == 0) d += 1.5f;         // patches
      if (unit(random) < 0.1f || (u > 150 && v > 40)) {  // holes
        d = unit(random) < 0.5f ? std::numeric_limits<float>::quiet_NaN() : 0.0f;
      }
      image[static_cast<std::size_t>(v) * kOddWidth + u] = d;
    }
  }
  return image;
}

TEST(MeasuredSurface, NodesOfANoisyImageWithHolesAndPatchesFollowTheDefinition) {
  const std::vector<float> image = noisyImageWithHolesAndPatches();
  const StereoCamera& camera = kOddCamera;
  const DisparityImageView view{kOddWidth, kOddHeight, image.data(), 0};
  for (const auto instructions :
       {MedianNetwork::Instructions::kWidest, MedianNetwork::Instructions::kBaseline}) {
    for (int grid : {4, 8}) {
      MeasuredSurfaceConfig config;
      config.grid_step_px = grid;
      config.instructions = instructions;
      const MeasuredSurface surface(view, camera, Eigen::Isometry3d::Identity(), config);
      ASSERT_EQ(surface.gridStep(), grid);
      int nodes = 0, compared = 0, inside = 0;
      // The definition is that of grid points at least a sample step from the border; those
      // nearer to it are extrapolated (border_from_interior, its own test below).
      const int band = config.sample_step_px;
      for (int v = 0; v < kOddHeight; v += grid) {
        for (int u = 0; u < kOddWidth; u += grid) {
          if (u < band || v < band || u > kOddWidth - 1 - band || v > kOddHeight - 1 - band) {
            continue;
          }
          ++inside;
          const float expected = nodeByDefinition(image, kOddWidth, kOddHeight, u, v, config);
          if (!std::isfinite(expected)) continue;
          ++nodes;
          // At a node's own pixel the grid reads the node (where at most one corner of its cell
          // lacks a surface).
          const Eigen::Vector3d point((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy,
                                      1.0);
          double z = 0, z_surface = 0;
          if (!surface.depthAt(point, &z, &z_surface)) continue;
          ++compared;
          const double read = camera.fx * camera.baseline / z_surface;
          EXPECT_NEAR(read, expected, 1e-4 * expected)
              << "node at " << u << ", " << v << ", grid " << grid;
        }
      }
      EXPECT_GT(nodes, inside / 2);
      EXPECT_GT(compared, 0.9 * nodes) << "grid " << grid;
    }
  }
}

TEST(MeasuredSurface, WidestAndBaselineInstructionsGiveTheSameSurfaceBitForBit) {
  // The AVX2 path (where the processor has it) and plain x86-64's add the same terms in the same
  // order: every pixel's surface depth is the same double.
  const std::vector<float> image = noisyImageWithHolesAndPatches();
  const DisparityImageView view{kOddWidth, kOddHeight, image.data(), 0};
  MeasuredSurfaceConfig widest, baseline;
  baseline.instructions = MedianNetwork::Instructions::kBaseline;
  const MeasuredSurface a(view, kOddCamera, Eigen::Isometry3d::Identity(), widest);
  const MeasuredSurface b(view, kOddCamera, Eigen::Isometry3d::Identity(), baseline);
  int read = 0;
  for (int v = 0; v < kOddHeight; ++v) {
    for (int u = 0; u < kOddWidth; ++u) {
      const Eigen::Vector3d point((u + 0.3 - kOddCamera.cx) / kOddCamera.fx,
                                  (v + 0.6 - kOddCamera.cy) / kOddCamera.fy, 1.0);
      double za = 0, zb = 0, surface_a = 0, surface_b = 0;
      const bool says_a = a.depthAt(point, &za, &surface_a);
      ASSERT_EQ(says_a, b.depthAt(point, &zb, &surface_b)) << "pixel " << u << ", " << v;
      if (!says_a) continue;
      ++read;
      ASSERT_EQ(surface_a, surface_b) << "pixel " << u << ", " << v;
    }
  }
  EXPECT_GT(read, kOddWidth * kOddHeight / 2);
}

TEST(MeasuredSurface, RejectsBadConfigurations) {
  const std::vector<float> image = planeImage(Plane());
  const DisparityImageView view{kWidth, kHeight, image.data(), 0};
  auto rejects = [&](auto change) {
    MeasuredSurfaceConfig config;
    change(config);
    EXPECT_THROW(MeasuredSurface(view, kCamera, Eigen::Isometry3d::Identity(), config),
                 std::invalid_argument);
  };
  rejects([](MeasuredSurfaceConfig& c) { c.window_px = 0; });
  rejects([](MeasuredSurfaceConfig& c) { c.grid_step_px = 0; });
  rejects([](MeasuredSurfaceConfig& c) { c.min_valid = 0.0; });
  rejects([](MeasuredSurfaceConfig& c) { c.local_window_px = 99; });
  rejects([](MeasuredSurfaceConfig& c) { c.inlier_px = 0.0; });
  rejects([](MeasuredSurfaceConfig& c) { c.grid_step_px = 6; });  // not a multiple of 4
  rejects([](MeasuredSurfaceConfig& c) { c.step_px = -0.1; });
  rejects([](MeasuredSurfaceConfig& c) { c.window_px = 128; });  // 33^2 samples
  rejects([](MeasuredSurfaceConfig& c) { c.grid_footprint_fraction = -0.1; });
  rejects([](MeasuredSurfaceConfig& c) { c.grid_max_step_px = 6; });   // not a multiple of 4
  rejects([](MeasuredSurfaceConfig& c) { c.grid_max_step_px = 28; });  // wider than the window
  rejects([](MeasuredSurfaceConfig& c) { c.grid_max_step_px = -4; });
  rejects([](MeasuredSurfaceConfig& c) { c.grid_footprint_fraction = std::nan(""); });
  MeasuredSurfaceConfig widest;
  widest.window_px = 127;  // 31^2 samples: the widest median
  EXPECT_NO_THROW(MeasuredSurface(view, kCamera, Eigen::Isometry3d::Identity(), widest));
}

}  // namespace
}  // namespace occupancy_fusion
