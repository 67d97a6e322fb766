#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "occupancy_fusion/integrators/laser/polar_to_cartesian.h"

namespace occupancy_fusion {

namespace {

constexpr double kPi = 3.14159265358979323846;

void addDelta(float delta, float* cell) { *cell = std::isnan(*cell) ? delta : *cell + delta; }

// Polar coordinates of raster points in the sensor's frame, in units of the
// field's texels.
class PolarLocator {
 public:
  PolarLocator(const PolarField& field, const Pose2D& sensor)
      : field_(field),
        sensor_(sensor),
        fov_centre_(field.angle_min + 0.5 * (field.beams - 1) * field.angle_increment) {}

  // u: beams (beam b spans [b, b + 1)); v: range cells. Returns the range in m.
  double locate(double x, double y, double* u, double* v) const {
    const double dx = x - sensor_.x;
    const double dy = y - sensor_.y;
    const double range = std::sqrt(dx * dx + dy * dy);
    double angle = fastAtan2(dy, dx) - sensor_.yaw - fov_centre_;
    angle -= 2.0 * kPi * std::floor((angle + kPi) / (2.0 * kPi));  // into [-pi, pi)
    *u = (angle + fov_centre_ - field_.angle_min) / field_.angle_increment + 0.5;
    *v = range / field_.range_resolution;
    return range;
  }
  bool inside(double u, double v) const { return u >= 0.0 && u < field_.beams && v < field_.cells; }

 private:
  const PolarField& field_;
  Pose2D sensor_;
  double fov_centre_;
};

double cellCentre(int origin, int i, double resolution) { return (origin + i + 0.5) * resolution; }

// The farthest range any beam observed (m): cells farther away get nothing,
// whatever the method.
double observedReach(const PolarField& field) {
  int cells = 0;
  for (int observed : field.observed_cells) cells = std::max(cells, observed);
  return cells * field.range_resolution;
}

// Calls cell(x, y) for every raster cell of the reachable tiles, tiles spread over the threads.
template <typename CellFunction>
void forEachReachableCell(const ReachableTiles& tiles, const LogOddsRaster& raster,
                          CellFunction&& cell) {
  const std::vector<int>& list = tiles.tiles();
  const int count = static_cast<int>(list.size());
#pragma omp parallel for schedule(dynamic, 2)
  for (int i = 0; i < count; ++i) {
    const int column = list[static_cast<std::size_t>(i)] % tiles.columns();
    const int row = list[static_cast<std::size_t>(i)] / tiles.columns();
    const int x_end = std::min(raster.width, (column + 1) * ReachableTiles::kSide);
    const int y_end = std::min(raster.height, (row + 1) * ReachableTiles::kSide);
    for (int y = row * ReachableTiles::kSide; y < y_end; ++y) {
      for (int x = column * ReachableTiles::kSide; x < x_end; ++x) cell(x, y);
    }
  }
}

// Angle of (x, y) from the direction `centre`, in [-pi, pi).
double angleFrom(double x, double y, double centre) {
  double angle = fastAtan2(y, x) - centre;  // its 2e-6 rad error is far inside the beam margin
  angle -= 2.0 * kPi * std::floor((angle + kPi) / (2.0 * kPi));
  return angle;
}

}  // namespace

ReachableTiles::ReachableTiles(const PolarField& field, const Pose2D& sensor,
                               const LogOddsRaster& raster, double always_within) {
  const int side = kSide;
  columns_ = (raster.width + side - 1) / side;
  rows_ = (raster.height + side - 1) / side;
  reachable_.assign(static_cast<std::size_t>(columns_) * rows_, 0);
  const double res = raster.resolution;
  const double d_rho = field.range_resolution;
  const double inc = field.angle_increment;
  // Mipmap filters reach up to two texels of the level after the cell's footprint: up to 4 cell
  // sizes along the range, 4 footprints plus 2 beams across; chords lie inside the arcs.
  const double range_margin = 4.0 * res + 2.0 * d_rho;
  const double fov_centre = field.angle_min + 0.5 * (field.beams - 1) * inc;
  const double heading = sensor.yaw + fov_centre;
  int max_observed = 0;
  for (int observed : field.observed_cells) max_observed = std::max(max_observed, observed);
  const double max_reach = std::max(max_observed * d_rho + range_margin, always_within);

  for (int row = 0; row < rows_; ++row) {
    const double y0 = (raster.origin_cell.y() + row * side) * res - sensor.y;
    const double y1 =
        (raster.origin_cell.y() + std::min((row + 1) * side, raster.height)) * res - sensor.y;
    const double dy = y0 > 0.0 ? y0 : (y1 < 0.0 ? -y1 : 0.0);
    for (int column = 0; column < columns_; ++column) {
      const double x0 = (raster.origin_cell.x() + column * side) * res - sensor.x;
      const double x1 =
          (raster.origin_cell.x() + std::min((column + 1) * side, raster.width)) * res - sensor.x;
      const double dx = x0 > 0.0 ? x0 : (x1 < 0.0 ? -x1 : 0.0);
      const double nearest = std::sqrt(dx * dx + dy * dy);
      if (nearest >= max_reach) continue;
      bool reach = nearest < always_within;
      if (!reach && max_observed > 0) {
        int first_beam = 0;
        int last_beam = field.beams - 1;
        if (nearest > 0.0) {
          double low = kPi;
          double high = -kPi;
          for (double cx : {x0, x1}) {
            for (double cy : {y0, y1}) {
              const double angle = angleFrom(cx, cy, heading);
              low = std::min(low, angle);
              high = std::max(high, angle);
            }
          }
          if (high - low < kPi) {  // else the tile straddles the direction behind the sensor
            const double beam_margin = 2.0 + 4.0 * res / (nearest * inc);
            const double offset = (fov_centre - field.angle_min) / inc + 0.5;
            first_beam = std::max(first_beam,
                                  static_cast<int>(std::floor(low / inc + offset - beam_margin)));
            last_beam = std::min(last_beam,
                                 static_cast<int>(std::floor(high / inc + offset + beam_margin)));
          }
        }
        int observed = 0;
        for (int b = first_beam; b <= last_beam; ++b)
          observed = std::max(observed, field.observed_cells[static_cast<std::size_t>(b)]);
        reach = observed > 0 && nearest < observed * d_rho + range_margin;
      }
      if (reach) {
        reachable_[static_cast<std::size_t>(column + columns_ * row)] = 1;
        tiles_.push_back(column + columns_ * row);
      }
    }
  }
}

const char* methodName(PolarToCartesianMethod method) {
  switch (method) {
    case PolarToCartesianMethod::kExact:
      return "exact";
    case PolarToCartesianMethod::kSampling:
      return "sampling";
    case PolarToCartesianMethod::kMipmap:
      return "mipmap";
    case PolarToCartesianMethod::kLines:
      return "lines";
  }
  return "unknown";
}

PolarToCartesianMethod parsePolarToCartesianMethod(const std::string& name) {
  for (PolarToCartesianMethod method :
       {PolarToCartesianMethod::kExact, PolarToCartesianMethod::kSampling,
        PolarToCartesianMethod::kMipmap, PolarToCartesianMethod::kLines}) {
    if (name == methodName(method)) return method;
  }
  throw std::invalid_argument("unknown polar-to-cartesian method '" + name +
                              "' (exact, sampling, mipmap, lines)");
}

// Minimax-style odd polynomial for atan on [0, 1] (error below 2e-6 rad), then
// octant fix-ups.
double fastAtan2(double y, double x) {
  const double ax = std::abs(x);
  const double ay = std::abs(y);
  const double big = std::max(ax, ay);
  if (big == 0.0) return 0.0;
  const double t = std::min(ax, ay) / big;
  const double s = t * t;
  double r = t * (0.99997726 +
                  s * (-0.33262347 +
                       s * (0.19354346 + s * (-0.11643287 + s * (0.05265332 - s * 0.01172120)))));
  if (ay > ax) r = 0.5 * kPi - r;
  if (x < 0.0) r = kPi - r;
  return y < 0.0 ? -r : r;
}

// --- lines
// ---------------------------------------------------------------------------------

void projectLines(const PolarField& field, const Pose2D& sensor, LogOddsRaster* raster) {
  const double res = raster->resolution;
  const int x0 = static_cast<int>(std::floor(sensor.x / res)) - raster->origin_cell.x();
  const int y0 = static_cast<int>(std::floor(sensor.y / res)) - raster->origin_cell.y();
  for (int b = 0; b < field.beams; ++b) {
    const int observed = field.observed_cells[static_cast<std::size_t>(b)];
    if (observed == 0) continue;
    const double angle = sensor.yaw + field.angle(b);
    const double length = observed * field.range_resolution;
    const int x1 = static_cast<int>(std::floor((sensor.x + length * std::cos(angle)) / res)) -
                   raster->origin_cell.x();
    const int y1 = static_cast<int>(std::floor((sensor.y + length * std::sin(angle)) / res)) -
                   raster->origin_cell.y();
    const float* values = field.value.data() + field.index(b, 0);
    // Bresenham: integer error term, one cell per step along the major axis.
    const int dx = std::abs(x1 - x0);
    const int dy = -std::abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1;
    const int sy = y0 < y1 ? 1 : -1;
    int error = dx + dy;
    for (int x = x0, y = y0;;) {
      if (x >= 0 && y >= 0 && x < raster->width && y < raster->height) {
        const double cx = cellCentre(raster->origin_cell.x(), x, res) - sensor.x;
        const double cy = cellCentre(raster->origin_cell.y(), y, res) - sensor.y;
        const int k = static_cast<int>(std::sqrt(cx * cx + cy * cy) / field.range_resolution);
        if (k < observed) {
          addDelta(values[k], &raster->data[static_cast<std::size_t>(x + raster->width * y)]);
        }
      }
      if (x == x1 && y == y1) break;
      const int twice = 2 * error;
      if (twice >= dy) {
        error += dy;
        x += sx;
      }
      if (twice <= dx) {
        error += dx;
        y += sy;
      }
    }
  }
}

// --- adaptive sampling
// ---------------------------------------------------------------------

void projectSampling(const PolarField& field, const Pose2D& sensor, int max_samples_per_axis,
                     LogOddsRaster* raster) {
  if (max_samples_per_axis < 1) {
    throw std::invalid_argument("projectSampling: max_samples_per_axis must be >= 1");
  }
  const PolarLocator locator(field, sensor);
  const double res = raster->resolution;
  const double reach = observedReach(field) + res;
  const double polar_area = field.range_resolution * field.angle_increment;  // times rho
  const ReachableTiles tiles(field, sensor, *raster);
  forEachReachableCell(tiles, *raster, [&](int x, int y) {
    const double cy = cellCentre(raster->origin_cell.y(), y, res);
    const double cx = cellCentre(raster->origin_cell.x(), x, res);
    const double range =
        std::sqrt((cx - sensor.x) * (cx - sensor.x) + (cy - sensor.y) * (cy - sensor.y));
    if (range > reach) return;
    const double ns = res * res / (std::max(range, 1e-9) * polar_area);  // Eq. 6
    const int k = std::clamp(static_cast<int>(std::ceil(std::sqrt(ns))), 1, max_samples_per_axis);
    double sum = 0.0;
    bool any_observed = false;
    for (int j = 0; j < k; ++j) {
      const double py = cy + res * ((j + 0.5) / k - 0.5);
      for (int i = 0; i < k; ++i) {
        const double px = cx + res * ((i + 0.5) / k - 0.5);
        double u = 0.0;
        double v = 0.0;
        locator.locate(px, py, &u, &v);
        if (!locator.inside(u, v)) continue;
        const int index = field.index(static_cast<int>(u), static_cast<int>(v));
        if (field.observed[static_cast<std::size_t>(index)] == 0.0f) continue;
        any_observed = true;
        sum += field.value[static_cast<std::size_t>(index)];
      }
    }
    if (any_observed) {
      addDelta(static_cast<float>(sum / (k * k)),
               &raster->data[static_cast<std::size_t>(x + raster->width * y)]);
    }
  });
}

// --- mipmap
// --------------------------------------------------------------------------------

void MipmapConfig::validate() const {
  if (!(std::isfinite(safety_radius) && safety_radius >= 0.0)) {
    throw std::invalid_argument("MipmapConfig.safety_radius must be finite and >= 0");
  }
}

namespace {

int levelCount(int size) {
  int levels = 1;
  while (size > 1) {
    size = (size + 1) / 2;
    ++levels;
  }
  return levels;
}

// Halves one axis of a level: texel j of the result averages texels 2j and 2j +
// 1 (or copies the last one when the size is odd).
template <bool kAlongBeams>
void halve(const std::vector<float>& in, int beams, int cells, std::vector<float>* out) {
  const int out_beams = kAlongBeams ? (beams + 1) / 2 : beams;
  const int out_cells = kAlongBeams ? cells : (cells + 1) / 2;
  out->assign(static_cast<std::size_t>(out_beams) * out_cells, 0.0f);
  for (int b = 0; b < out_beams; ++b) {
    for (int k = 0; k < out_cells; ++k) {
      const int b0 = kAlongBeams ? 2 * b : b;
      const int k0 = kAlongBeams ? k : 2 * k;
      const int b1 = kAlongBeams ? std::min(b0 + 1, beams - 1) : b0;
      const int k1 = kAlongBeams ? k0 : std::min(k0 + 1, cells - 1);
      (*out)[static_cast<std::size_t>(b * out_cells + k)] =
          0.5f * (in[static_cast<std::size_t>(b0 * cells + k0)] +
                  in[static_cast<std::size_t>(b1 * cells + k1)]);
    }
  }
}

}  // namespace

PolarMipmap::PolarMipmap(const PolarField& field, double cell_size) {
  angle_levels_ = levelCount(field.beams);
  // A cell spans about cell_size / d_rho range cells wherever it lies: only the
  // two range levels around log2 of that are ever read.
  const double range_footprint = std::log2(std::max(1.0, cell_size / field.range_resolution));
  first_range_level_ =
      std::min(static_cast<int>(std::floor(range_footprint)), levelCount(field.cells) - 1);
  // When the footprint is a whole power of two (cells as long as the range cells, the usual
  // case) the blend gives the coarser level weight 0: it is not built.
  const bool whole = range_footprint == std::floor(range_footprint);
  range_levels_ = std::min(whole ? 1 : 2, levelCount(field.cells) - first_range_level_);

  // Only the range cells up to the farthest observed one (plus two texels of the coarsest level
  // kept, all zero, so that lookups clamped at the end still read zeros) enter the pyramid.
  int max_observed = 0;
  for (int observed : field.observed_cells) max_observed = std::max(max_observed, observed);
  const int coarsest = 1 << (first_range_level_ + range_levels_ - 1);
  const int used = std::min(field.cells, (max_observed / coarsest + 3) * coarsest);
  Level base;
  base.beams = field.beams;
  base.cells = used;
  base.value.resize(static_cast<std::size_t>(field.beams) * used);
  base.observed.resize(base.value.size());
  for (int b = 0; b < field.beams; ++b) {
    const std::size_t from = static_cast<std::size_t>(field.index(b, 0));
    const std::size_t to = static_cast<std::size_t>(b) * used;
    std::copy_n(field.value.begin() + from, used, base.value.begin() + to);
    std::copy_n(field.observed.begin() + from, used, base.observed.begin() + to);
  }
  for (int r = 0; r < first_range_level_; ++r) {
    Level coarser;
    coarser.beams = base.beams;
    coarser.cells = (base.cells + 1) / 2;
    halve<false>(base.value, base.beams, base.cells, &coarser.value);
    halve<false>(base.observed, base.beams, base.cells, &coarser.observed);
    base = std::move(coarser);
  }
  levels_.resize(static_cast<std::size_t>(range_levels_ * angle_levels_));
  for (int r = 0; r < range_levels_; ++r) {
    Level& first = levels_[static_cast<std::size_t>(r * angle_levels_)];
    if (r == 0) {
      first = base;
    } else {
      const Level& finer = levels_[static_cast<std::size_t>((r - 1) * angle_levels_)];
      first.beams = finer.beams;
      first.cells = (finer.cells + 1) / 2;
      halve<false>(finer.value, finer.beams, finer.cells, &first.value);
      halve<false>(finer.observed, finer.beams, finer.cells, &first.observed);
    }
    for (int a = 1; a < angle_levels_; ++a) {
      const Level& finer = levels_[static_cast<std::size_t>(r * angle_levels_ + a - 1)];
      Level& coarser = levels_[static_cast<std::size_t>(r * angle_levels_ + a)];
      coarser.beams = (finer.beams + 1) / 2;
      coarser.cells = finer.cells;
      halve<true>(finer.value, finer.beams, finer.cells, &coarser.value);
      halve<true>(finer.observed, finer.beams, finer.cells, &coarser.observed);
    }
  }
}

bool PolarMipmap::hasRangeLevel(int range_level) const {
  return range_level >= first_range_level_ && range_level < first_range_level_ + range_levels_;
}

const PolarMipmap::Level& PolarMipmap::level(int angle_level, int range_level) const {
  const int r = std::clamp(range_level - first_range_level_, 0, range_levels_ - 1);
  const int a = std::clamp(angle_level, 0, angle_levels_ - 1);
  return levels_[static_cast<std::size_t>(r * angle_levels_ + a)];
}

void PolarMipmap::lookup(int angle_level, int range_level, double u, double v, float* value,
                         float* observed) const {
  const Level& l = level(angle_level, range_level);
  // Texel j of level n spans base [j 2^n, (j + 1) 2^n): its centre is at (j +
  // 0.5) 2^n.
  // 2^-n as a product (exact for these small n), cheaper than ldexp per lookup.
  const int a = std::clamp(angle_level, 0, angle_levels_ - 1);
  const int r = std::clamp(range_level, first_range_level_, first_range_level_ + range_levels_ - 1);
  const double tu = u * (1.0 / static_cast<double>(1 << a)) - 0.5;
  const double tv = v * (1.0 / static_cast<double>(1 << r)) - 0.5;
  const int b0 = static_cast<int>(std::floor(tu));
  const int k0 = static_cast<int>(std::floor(tv));
  const float fu = static_cast<float>(tu - b0);
  const float fv = static_cast<float>(tv - k0);
  const int bl = std::clamp(b0, 0, l.beams - 1);
  const int bh = std::clamp(b0 + 1, 0, l.beams - 1);
  const int kl = std::clamp(k0, 0, l.cells - 1);
  const int kh = std::clamp(k0 + 1, 0, l.cells - 1);
  auto bilinear = [&](const std::vector<float>& t) {
    const float low = t[static_cast<std::size_t>(bl * l.cells + kl)] * (1.0f - fv) +
                      t[static_cast<std::size_t>(bl * l.cells + kh)] * fv;
    const float high = t[static_cast<std::size_t>(bh * l.cells + kl)] * (1.0f - fv) +
                       t[static_cast<std::size_t>(bh * l.cells + kh)] * fv;
    return low * (1.0f - fu) + high * fu;
  };
  *value = bilinear(l.value);
  *observed = bilinear(l.observed);
}

namespace {

// The worst case near the sensor (Sec. V-A): the largest log-ratio any beam
// observed within `radius` (plus the cells that straddle it). Returns false if
// nothing was observed there.
bool worstCaseNearSensor(const PolarField& field, double radius, float* worst) {
  const int cells =
      std::min(field.cells, static_cast<int>(std::ceil(radius / field.range_resolution)) + 1);
  bool any = false;
  *worst = -std::numeric_limits<float>::infinity();
  for (int b = 0; b < field.beams; ++b) {
    const int observed = std::min(cells, field.observed_cells[static_cast<std::size_t>(b)]);
    for (int k = 0; k < observed; ++k) {
      *worst = std::max(*worst, field.value[static_cast<std::size_t>(field.index(b, k))]);
      any = true;
    }
  }
  return any;
}

}  // namespace

void projectMipmap(const PolarField& field, const Pose2D& sensor, const MipmapConfig& config,
                   LogOddsRaster* raster) {
  config.validate();
  const double res = raster->resolution;
  const PolarMipmap mipmap(field, res);
  const PolarLocator locator(field, sensor);
  float worst = 0.0f;
  const bool has_worst = worstCaseNearSensor(field, config.safety_radius, &worst);
  const double range_level = std::log2(std::max(1.0, res / field.range_resolution));
  const int range_low = static_cast<int>(std::floor(range_level));
  // Without a coarser range level (a field only a few cells long) the finer one
  // takes it all.
  const float range_fraction =
      mipmap.hasRangeLevel(range_low + 1) ? static_cast<float>(range_level - range_low) : 0.0f;
  const double angular_footprint = res / field.angle_increment;  // beams spanned, times range
  const double reach = observedReach(field) + res;

  const ReachableTiles tiles(field, sensor, *raster, has_worst ? config.safety_radius + res : 0.0);
  forEachReachableCell(tiles, *raster, [&](int x, int y) {
    const double cy = cellCentre(raster->origin_cell.y(), y, res);
    const double cx = cellCentre(raster->origin_cell.x(), x, res);
    double u = 0.0;
    double v = 0.0;
    const double range = locator.locate(cx, cy, &u, &v);
    if (range > reach) return;
    if (!locator.inside(u, v)) return;
    float* cell = &raster->data[static_cast<std::size_t>(x + raster->width * y)];
    if (range < config.safety_radius) {
      if (has_worst) addDelta(worst, cell);
      return;
    }
    const double angle_level = std::log2(std::max(1.0, angular_footprint / range));
    const int angle_low = static_cast<int>(std::floor(angle_level));
    const float angle_fraction = static_cast<float>(angle_level - angle_low);
    float value = 0.0f;
    float observed = 0.0f;
    for (int dr = 0; dr < 2; ++dr) {
      const float wr = dr == 0 ? 1.0f - range_fraction : range_fraction;
      if (wr == 0.0f || !mipmap.hasRangeLevel(range_low + dr)) continue;
      for (int da = 0; da < 2; ++da) {
        const float wa = da == 0 ? 1.0f - angle_fraction : angle_fraction;
        if (wa == 0.0f) continue;
        float level_value = 0.0f;
        float level_observed = 0.0f;
        mipmap.lookup(angle_low + da, range_low + dr, u, v, &level_value, &level_observed);
        value += wr * wa * level_value;
        observed += wr * wa * level_observed;
      }
    }
    if (observed > 0.0f) addDelta(value, cell);
  });
}

}  // namespace occupancy_fusion
