// Stereo disparity images and their conversion to 3D points with the stereo
// depth-error model of Schauwecker & Zell 2014, "Robust and Efficient
// Volumetric Occupancy Mapping with an Application to Stereo Vision" (Sec.
// III-C, Eq. 7).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "occupancy_fusion/sensors/camera_intrinsics.h"

namespace occupancy_fusion {

// A rectified stereo pair as the disparity image needs it, in the ROS
// convention (stereo_msgs/DisparityImage f and T, the left camera_info's
// principal point): pixel (u, v) has its centre at integer (u, v), the optical
// frame has z forward, x right, y down.
struct StereoCamera {
  double fx = 525.0;      // px, focal length of the left camera (DisparityImage.f)
  double fy = 525.0;      // px, usually equal to fx after rectification
  double cx = 319.5;      // px
  double cy = 239.5;      // px
  double baseline = 0.1;  // m, distance between the optical centres (DisparityImage.T)

  void validate() const;  // throws std::invalid_argument naming the bad field
  // The left camera's intrinsics for images of width x height (what its camera_info holds).
  CameraIntrinsics leftIntrinsics(int width, int height) const {
    CameraIntrinsics left;
    left.width = width;
    left.height = height;
    left.fx = fx;
    left.fy = fy;
    left.cx = cx;
    left.cy = cy;
    return left;
  }
};

// A non-owning, row-major view of disparity in pixels of the left image (d = fx
// * baseline / z). NaN, infinite and non-positive values mark pixels without a
// match. It can wrap a std::vector, a cv::Mat of CV_32FC1 or the data of a
// stereo_msgs/DisparityImage without copying.
struct DisparityImageView {
  int width = 0;
  int height = 0;
  const float* disparity = nullptr;  // disparity[v * row_stride + u]
  int row_stride = 0;                // floats per row; 0 means width

  float at(int u, int v) const { return row(v)[u]; }
  const float* row(int v) const {
    return disparity + static_cast<std::size_t>(v) * (row_stride > 0 ? row_stride : width);
  }
  void validate() const;  // throws std::invalid_argument unless non-null with positive size
};

// The paper's input resolutions (Sec. IV): a matcher that outputs half or
// quarter resolution keeps the full-resolution disparity values at every 2nd or
// 4th pixel of each row and column.
enum class InputResolution { kFull = 1, kHalf = 2, kQuarter = 4 };
std::string toString(InputResolution resolution);
InputResolution inputResolutionFromString(const std::string& name);  // "full", "half", "quarter"
inline int pixelStep(InputResolution resolution) { return static_cast<int>(resolution); }

struct DisparityConversionConfig {
  // px, standard deviation of the matcher's disparity error, sigma_d of Eq. 7.
  // A sensor property; 0.5 px is typical of sub-pixel block matching (the paper
  // leaves it open).
  double disparity_sigma_px = 0.5;
  // px; smaller disparities (farther points) are dropped. 0 keeps every
  // positive disparity.
  double min_disparity_px = 0.0;
  // Points whose relative depth error sigma_z / z (Eq. 7: = lambda z = sigma_d / d) exceeds it are
  // dropped; negative: none. Equivalently, disparities below disparity_sigma_px / ratio. A
  // disparity near 0 (a match lost in noise) gives a point kilometres away whose sigma_z exceeds
  // its depth: Eq. 8 then gives every voxel of its ray P(I_v) near 0.5, and since a voxel keeps the
  // largest P(I_v) of its rays, the voxels next to the sensor are never cleared. A kept point's
  // P(I_v) at distance s in front of the sensor is at most Phi(-(1 - s / z) / ratio): at 0.5,
  // Phi(-2) = 0.023 at the sensor and 0.16 at half its depth, still a net miss in Eq. 8.
  double max_depth_sigma_ratio = 0.5;
  InputResolution input_resolution = InputResolution::kFull;

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// Eq. 7: lambda = sigma_d / (b * f), sigma_z = lambda * z^2, z = f * b / d.
inline double depthFromDisparity(double disparity_px, double focal_px, double baseline_m) {
  return focal_px * baseline_m / disparity_px;
}
inline double depthErrorFactor(double disparity_sigma_px, double baseline_m, double focal_px) {
  return disparity_sigma_px / (baseline_m * focal_px);
}
inline double depthSigma(double depth_m, double lambda) { return lambda * depth_m * depth_m; }

// Points of a disparity image in the left camera's optical frame, with each
// point's depth standard deviation sigma_z (Eq. 7, along the optical z axis),
// in pixel order (row-major).
struct StereoPoints {
  std::vector<Eigen::Vector3f> points;
  std::vector<float> depth_sigmas;  // m, sigma_z of points[i]
  std::size_t pixels_read = 0;      // pixels looked at (after sub-sampling)
  std::size_t dropped_uncertain =
      0;  // valid disparities dropped: sigma_z / z > max_depth_sigma_ratio

  std::size_t size() const { return points.size(); }
};

// disparityToPoints' rule for one pixel, for callers that convert rows themselves (on several
// threads, or straight into the map frame). Inline: it runs once per pixel.
class DisparityPointConverter {
 public:
  enum class Result { kPoint, kNoMatch, kUncertain };  // kUncertain: sigma_z / z too large

  DisparityPointConverter(const StereoCamera& camera, const DisparityConversionConfig& config)
      : camera_(camera),
        focal_baseline_(camera.fx * camera.baseline),
        lambda_(depthErrorFactor(config.disparity_sigma_px, camera.baseline, camera.fx)),
        max_ratio_(config.max_depth_sigma_ratio),
        min_disparity_(config.min_disparity_px),
        step_(pixelStep(config.input_resolution)) {}

  int step() const { return step_; }  // pixels between the converted ones, in rows and columns
  double rayY(int v) const { return (v - camera_.cy) / camera_.fy; }  // of row v, for convert()

  // Pixel (u, v) of disparity d, with ray_y = rayY(v): its point in the camera's optical frame and
  // sigma_z when the result is kPoint.
  Result convert(int u, double ray_y, float d, Eigen::Vector3f* point, float* sigma_z) const {
    if (!(std::isfinite(d) && d > 0 && d >= min_disparity_)) return Result::kNoMatch;
    const double z = depthOf(d);
    return finish(d, z, xOf(u, z), ray_y, point, sigma_z);
  }

  // convert()'s two divisions, apart so that a run of pixels can take them together (vector
  // division, the same bits): the depth z of disparity d and the x of pixel column u at depth z.
  double depthOf(float d) const { return focal_baseline_ / d; }
  double xOf(int u, double z) const { return z * (u - camera_.cx) / camera_.fx; }
  double depthSigmaOf(double z) const { return depthSigma(z, lambda_); }  // convert()'s sigma_z

  // convert() given depthOf(d) and xOf(u, depthOf(d)), whatever d is (also an invalid one).
  Result finish(float d, double z, double x, double ray_y, Eigen::Vector3f* point,
                float* sigma_z) const {
    if (!(std::isfinite(d) && d > 0 && d >= min_disparity_)) return Result::kNoMatch;
    const double sigma = depthSigmaOf(z);
    if (max_ratio_ >= 0 && sigma > max_ratio_ * z) return Result::kUncertain;
    *point = Eigen::Vector3f(static_cast<float>(x), static_cast<float>(z * ray_y),
                             static_cast<float>(z));
    *sigma_z = static_cast<float>(sigma);
    // A disparity near 0 or an absurd focal length or baseline can put the point beyond float
    // range or round its depth to 0: the ray caster could not walk to it.
    if (!point->allFinite() || !(point->z() > 0.0f) || !std::isfinite(*sigma_z)) {
      return Result::kNoMatch;
    }
    return Result::kPoint;
  }

 private:
  StereoCamera camera_;
  double focal_baseline_, lambda_, max_ratio_, min_disparity_;
  int step_;
};

// Converts the valid pixels (finite d > max(0, min_disparity_px)) whose sigma_z / z is within
// max_depth_sigma_ratio at the configured input resolution: pixel (u, v) with depth z gives z * ((u
// - cx) / fx, (v - cy) / fy, 1); points beyond float range or with a
// depth that rounds to 0 are skipped.
StereoPoints disparityToPoints(const DisparityImageView& image, const StereoCamera& camera,
                               const DisparityConversionConfig& config);

}  // namespace occupancy_fusion
