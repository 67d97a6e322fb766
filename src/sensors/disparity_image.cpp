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
  const DisparityPointConverter converter(camera, config);
  const int step = converter.step();
  const std::size_t columns = (image.width + step - 1) / step;
  const std::size_t expected = columns * ((image.height + step - 1) / step);
  StereoPoints result;
  // Written by index and cut to size at the end: push_back's capacity checks cost as much as the
  // arithmetic of a point.
  result.points.resize(expected);
  result.depth_sigmas.resize(expected);
  std::size_t kept = 0;
  for (int v = 0; v < image.height; v += step) {
    const double ray_y = converter.rayY(v);
    const float* row = image.row(v);
    for (int u = 0; u < image.width; u += step) {
      const auto converted =
          converter.convert(u, ray_y, row[u], &result.points[kept], &result.depth_sigmas[kept]);
      if (converted == DisparityPointConverter::Result::kPoint) ++kept;
      if (converted == DisparityPointConverter::Result::kUncertain) ++result.dropped_uncertain;
    }
  }
  result.pixels_read = expected;
  result.points.resize(kept);
  result.depth_sigmas.resize(kept);
  return result;
}

}  // namespace occupancy_fusion
