#include "occupancy_fusion/integrators/measured_surface.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace occupancy_fusion {

void MeasuredSurfaceConfig::validate() const {
  if (window_px < 1 || window_px > 1001) {
    throw std::invalid_argument("MeasuredSurfaceConfig.window_px must be in [1, 1001]");
  }
  if (local_window_px < 0 || local_window_px > window_px) {
    throw std::invalid_argument("MeasuredSurfaceConfig.local_window_px must be in [0, window_px]");
  }
  if (!(inlier_px > 0))
    throw std::invalid_argument("MeasuredSurfaceConfig.inlier_px must be positive");
  if (sample_step_px < 1 || sample_step_px > window_px) {
    throw std::invalid_argument("MeasuredSurfaceConfig.sample_step_px must be in [1, window_px]");
  }
  if (grid_step_px < 1 || grid_step_px > window_px) {
    throw std::invalid_argument("MeasuredSurfaceConfig.grid_step_px must be in [1, window_px]");
  }
  if (!(min_valid > 0 && min_valid <= 1)) {
    throw std::invalid_argument("MeasuredSurfaceConfig.min_valid must be in (0, 1]");
  }
}

namespace {

constexpr float kNoSurface = std::numeric_limits<float>::quiet_NaN();

bool isValidDisparity(float d) { return std::isfinite(d) && d > 0; }

}  // namespace

namespace {

// The means of the point-symmetric sample pairs about (u, v) within `reach` px, `step` px apart,
// and the centre sample; a pair only where both samples are accepted (valid and within `limit`
// of `reference`, when limit > 0). On a plane, whose disparity is linear in u and v, every pair
// mean is the centre's disparity, whatever the slope and also where invalid pixels (the range
// limit, an image border, a matcher's holes) lie on one side only.
void symmetricPairMeans(const DisparityImageView& image, int u, int v, int reach, int step,
                        float reference, double limit, std::vector<float>* means) {
  auto accepted = [&](int x, int y, float* d) {
    if (x < 0 || x >= image.width || y < 0 || y >= image.height) return false;
    *d = image.at(x, y);
    return isValidDisparity(*d) && (limit <= 0 || std::abs(*d - reference) <= limit);
  };
  means->clear();
  reach = (reach / step) * step;
  for (int dv = -reach; dv <= 0; dv += step) {
    for (int du = -reach; du <= reach; du += step) {
      if (dv == 0 && du > 0) break;
      float first = 0, second = 0;
      if (!accepted(u + du, v + dv, &first)) continue;
      if (dv == 0 && du == 0) {
        means->push_back(first);
      } else if (accepted(u - du, v - dv, &second)) {
        means->push_back(0.5f * (first + second));
      }
    }
  }
}

float medianOf(std::vector<float>* values) {
  auto middle = values->begin() + static_cast<std::ptrdiff_t>(values->size() / 2);
  std::nth_element(values->begin(), middle, values->end());
  return *middle;
}

}  // namespace

MeasuredSurface::MeasuredSurface(const DisparityImageView& disparity, const StereoCamera& camera,
                                 const Eigen::Isometry3d& T_map_camera,
                                 const MeasuredSurfaceConfig& config)
    : T_camera_map_(T_map_camera.inverse()),
      fx_(camera.fx),
      fy_(camera.fy),
      cx_(camera.cx),
      cy_(camera.cy),
      focal_baseline_(camera.fx * camera.baseline),
      width_(disparity.width),
      height_(disparity.height),
      step_(config.grid_step_px) {
  config.validate();
  disparity.validate();
  columns_ = (width_ - 1) / step_ + 1;
  rows_ = (height_ - 1) / step_ + 1;
  cells_.assign(static_cast<std::size_t>(columns_) * rows_, kNoSurface);
  // The wide window sampled sparsely: its median needs only more pairs than a patch spoils.
  const int sample_step = config.sample_step_px;
  const int per_side = 2 * ((config.window_px / 2) / sample_step) + 1;
  const std::size_t needed =
      static_cast<std::size_t>(std::ceil(config.min_valid * (per_side * per_side + 1) / 2));
#pragma omp parallel
  {
    std::vector<float> means;
#pragma omp for schedule(static)
    for (int j = 0; j < rows_; ++j) {
      for (int i = 0; i < columns_; ++i) {
        const int u = i * step_, v = j * step_;
        // 1. The wide window's median: robust while a patch spoils fewer than half its pairs, but
        // on a
        //    kink of the surface (a corner, an object's edge) biased by the window's size.
        symmetricPairMeans(disparity, u, v, config.window_px / 2, sample_step, 0.0f, 0.0, &means);
        if (means.size() < needed || means.empty()) continue;
        const float robust = medianOf(&means);
        // 2. The small window's mean over the pixels within inlier_px of it: the patches' pixels
        //    left out, and a kink's bias that of the small window.
        float surface = robust;
        if (config.local_window_px > 0) {
          symmetricPairMeans(disparity, u, v, config.local_window_px / 2, 1, robust,
                             config.inlier_px, &means);
          if (means.size() >= 4) {
            double sum = 0;
            for (float d : means) sum += d;
            surface = static_cast<float>(sum / means.size());
          }
        }
        cells_[static_cast<std::size_t>(j) * columns_ + i] = surface;
      }
    }
  }
}

double MeasuredSurface::disparityAt(double u, double v) const {
  // Past the last grid column or row (the image's last pixels) the last two extrapolate.
  const double gu = u / step_, gv = v / step_;
  const int i0 = std::max(0, std::min(static_cast<int>(gu), columns_ - 2));
  const int j0 = std::max(0, std::min(static_cast<int>(gv), rows_ - 2));
  const int i1 = std::min(i0 + 1, columns_ - 1), j1 = std::min(j0 + 1, rows_ - 1);
  const double fu = i1 > i0 ? gu - i0 : 0.0, fv = j1 > j0 ? gv - j0 : 0.0;
  const double d00 = cellAt(i0, j0), d10 = cellAt(i1, j0);
  const double d01 = cellAt(i0, j1), d11 = cellAt(i1, j1);
  const int missing = std::isnan(d00) + std::isnan(d10) + std::isnan(d01) + std::isnan(d11);
  // Four corners: bilinear. Three: the plane through them, so that next to invalid pixels (the
  // range limit, a hole) a slanted surface is not read as its nearer corner's depth. Fewer: the
  // image does not say.
  if (missing == 0) {
    return (1 - fv) * ((1 - fu) * d00 + fu * d10) + fv * ((1 - fu) * d01 + fu * d11);
  }
  if (missing > 1) return std::numeric_limits<double>::quiet_NaN();
  if (std::isnan(d11)) return d00 + (d10 - d00) * fu + (d01 - d00) * fv;
  if (std::isnan(d00)) return d11 + (d01 - d11) * (1 - fu) + (d10 - d11) * (1 - fv);
  if (std::isnan(d10)) return d01 + (d11 - d01) * fu + (d00 - d01) * (1 - fv);
  return d10 + (d00 - d10) * (1 - fu) + (d11 - d10) * fv;
}

bool MeasuredSurface::depthAt(const Eigen::Vector3d& point_in_map, double* z,
                              double* z_surface) const {
  if (empty()) return false;
  const Eigen::Vector3d p = T_camera_map_ * point_in_map;
  if (!(p.z() > 0)) return false;
  const double u = fx_ * p.x() / p.z() + cx_, v = fy_ * p.y() / p.z() + cy_;
  if (!(u >= 0 && v >= 0 && u <= width_ - 1 && v <= height_ - 1)) return false;
  const double d = disparityAt(u, v);
  if (!(d > 0)) return false;
  *z = p.z();
  *z_surface = focal_baseline_ / d;
  return true;
}

}  // namespace occupancy_fusion
