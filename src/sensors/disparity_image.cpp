#include "occupancy_fusion/sensors/disparity_image.h"

#include <cmath>
#include <stdexcept>

namespace occupancy_fusion {
namespace {

void requirePositiveFinite(double value, const char* field) {
  if (!(std::isfinite(value) && value > 0)) {
    throw std::invalid_argument(std::string(field) + " must be positive and finite");
  }
}

}  // namespace

void StereoCamera::validate() const {
  requirePositiveFinite(fx, "StereoCamera.fx");
  requirePositiveFinite(fy, "StereoCamera.fy");
  if (!std::isfinite(cx)) throw std::invalid_argument("StereoCamera.cx must be finite");
  if (!std::isfinite(cy)) throw std::invalid_argument("StereoCamera.cy must be finite");
  requirePositiveFinite(baseline, "StereoCamera.baseline");
}

void DisparityImageView::validate() const {
  if (disparity == nullptr) throw std::invalid_argument("DisparityImageView.disparity is null");
  if (width <= 0) throw std::invalid_argument("DisparityImageView.width must be positive");
  if (height <= 0) throw std::invalid_argument("DisparityImageView.height must be positive");
  if (row_stride != 0 && row_stride < width) {
    throw std::invalid_argument("DisparityImageView.row_stride must be 0 or >= width");
  }
}

std::string toString(InputResolution resolution) {
  switch (resolution) {
    case InputResolution::kFull:
      return "full";
    case InputResolution::kHalf:
      return "half";
    case InputResolution::kQuarter:
      return "quarter";
  }
  return "unknown";
}

InputResolution inputResolutionFromString(const std::string& name) {
  if (name == "full") return InputResolution::kFull;
  if (name == "half") return InputResolution::kHalf;
  if (name == "quarter") return InputResolution::kQuarter;
  throw std::invalid_argument("input resolution must be full, half or quarter, not '" + name + "'");
}

void DisparityConversionConfig::validate() const {
  if (!(std::isfinite(disparity_sigma_px) && disparity_sigma_px >= 0)) {
    throw std::invalid_argument(
        "DisparityConversionConfig.disparity_sigma_px must be finite and >= 0");
  }
  if (!(std::isfinite(min_disparity_px) && min_disparity_px >= 0)) {
    throw std::invalid_argument(
        "DisparityConversionConfig.min_disparity_px must be finite and >= 0");
  }
  if (std::isnan(max_depth_sigma_ratio)) {
    throw std::invalid_argument("DisparityConversionConfig.max_depth_sigma_ratio must not be NaN");
  }
  const int step = pixelStep(input_resolution);
  if (step != 1 && step != 2 && step != 4) {
    throw std::invalid_argument(
        "DisparityConversionConfig.input_resolution "
        "must be full, half or quarter");
  }
}

StereoPoints disparityToPoints(const DisparityImageView& image, const StereoCamera& camera,
                               const DisparityConversionConfig& config) {
  image.validate();
  camera.validate();
  config.validate();
  const int step = pixelStep(config.input_resolution);
  const double focal_baseline = camera.fx * camera.baseline;
  const double lambda = depthErrorFactor(config.disparity_sigma_px, camera.baseline, camera.fx);
  const double max_ratio = config.max_depth_sigma_ratio;
  StereoPoints result;
  const std::size_t expected = static_cast<std::size_t>((image.width + step - 1) / step) *
                               ((image.height + step - 1) / step);
  result.points.reserve(expected);
  result.depth_sigmas.reserve(expected);
  for (int v = 0; v < image.height; v += step) {
    const double ray_y = (v - camera.cy) / camera.fy;
    for (int u = 0; u < image.width; u += step) {
      ++result.pixels_read;
      const float d = image.at(u, v);
      if (!(std::isfinite(d) && d > 0 && d >= config.min_disparity_px)) continue;
      const double z = focal_baseline / d;
      const double sigma_z = depthSigma(z, lambda);
      if (max_ratio >= 0 && sigma_z > max_ratio * z) {
        ++result.dropped_uncertain;
        continue;
      }
      const Eigen::Vector3f point(static_cast<float>(z * (u - camera.cx) / camera.fx),
                                  static_cast<float>(z * ray_y), static_cast<float>(z));
      // A disparity near 0 or an absurd focal length or baseline can put the point beyond float
      // range or round its depth to 0: the ray caster could not walk to it.
      if (!point.allFinite() || !(point.z() > 0.0f) ||
          !std::isfinite(static_cast<float>(sigma_z))) {
        continue;
      }
      result.points.push_back(point);
      result.depth_sigmas.push_back(static_cast<float>(sigma_z));
    }
  }
  return result;
}

}  // namespace occupancy_fusion
