#include "occupancy_fusion/integrators/depth/pyramid_depth_config.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "depth_detail.h"
#include "occupancy_fusion/integrators/depth/depth_inverse_model.h"

namespace occupancy_fusion {

using depth_detail::require;

std::string toString(DepthMethod method) {
  switch (method) {
    case DepthMethod::kPyramid:
      return "pyramid";
    case DepthMethod::kAndert:
      return "andert";
    case DepthMethod::kIdeal:
      return "ideal";
  }
  return "unknown";
}

DepthMethod depthMethodFromString(const std::string& name) {
  if (name == "pyramid") return DepthMethod::kPyramid;
  if (name == "andert") return DepthMethod::kAndert;
  if (name == "ideal") return DepthMethod::kIdeal;
  throw std::invalid_argument("PyramidDepthConfig.method must be pyramid, andert or ideal, not '" +
                              name + "'");
}

void PyramidDepthConfig::validate() const {
  require(std::isfinite(k) && k > 0.0, "PyramidDepthConfig.k must be finite and > 0");
  require(std::isfinite(sigma) && sigma > 0.0, "PyramidDepthConfig.sigma must be finite and > 0");
  // Eq. 7 peaks at 0.5 + k / (sigma sqrt(2 pi)) at z = z_j; its minimum, 0.3, is always valid.
  require(DepthInverseModel::peakAmplitude(k, sigma) < 0.5,
          "PyramidDepthConfig.k and sigma: k / (sigma * sqrt(2 pi)) = " +
              std::to_string(DepthInverseModel::peakAmplitude(k, sigma)) +
              " must be < 0.5, else Eq. 7 gives p >= 1 (raise sigma or lower k)");
  require(std::isfinite(sigma_quadratic) && sigma_quadratic >= 0.0,
          "PyramidDepthConfig.sigma_quadratic must be finite and >= 0");
  require(std::isfinite(min_range) && min_range >= 0.0,
          "PyramidDepthConfig.min_range must be finite and >= 0");
  require(std::isfinite(max_range) && max_range > min_range,
          "PyramidDepthConfig.max_range must be finite and > min_range");
  require(std::isfinite(unknown_behind_sigmas) && unknown_behind_sigmas > 0.0,
          "PyramidDepthConfig.unknown_behind_sigmas must be finite and > 0");
  require(max_pyramid_levels >= 1 && max_pyramid_levels <= 24,
          "PyramidDepthConfig.max_pyramid_levels must be in [1, 24]");
  require(finer_layers >= 0 && finer_layers <= 4,
          "PyramidDepthConfig.finer_layers must be in [0, 4]");
  require(std::isfinite(passed_sigmas) && passed_sigmas > 0.0,
          "PyramidDepthConfig.passed_sigmas must be finite and > 0");
  // Below Eq. 7's own constant 0.3, or it would clear more slowly than the paper.
  require(passed_miss_probability > 0.0 && passed_miss_probability < 0.3,
          "PyramidDepthConfig.passed_miss_probability must be in (0, 0.3)");
}

}  // namespace occupancy_fusion
