#include "occupancy_fusion/integrators/laser/laser_sensor_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace occupancy_fusion {

namespace {

constexpr double kWindowSigmas = 6.0;  // the Gaussian error is cut off beyond this many sigma

double gaussianCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

// First and last cell (inclusive) carrying Gaussian mass for a reading at
// `range`.
void errorWindow(double range, const LaserSensorModelConfig& c, int* first, int* last) {
  const double reach = kWindowSigmas * c.range_sigma;
  *first = std::max(0, static_cast<int>(std::floor((range - reach) / c.range_resolution)));
  *last = std::max(*first, static_cast<int>(std::floor((range + reach) / c.range_resolution)));
}

// w_z: probability that the true detection lies in cell k, given the reading.
std::vector<long double> cellMasses(double range, int first, int last,
                                    const LaserSensorModelConfig& c) {
  std::vector<long double> mass(static_cast<std::size_t>(last - first + 1), 0.0L);
  if (c.range_sigma == 0.0) {
    mass[static_cast<std::size_t>(static_cast<int>(range / c.range_resolution) - first)] = 1.0L;
    return mass;
  }
  // A cell's upper edge is the next cell's lower edge: one CDF evaluation per edge.
  double below = gaussianCdf((first * c.range_resolution - range) / c.range_sigma);
  for (int k = first; k <= last; ++k) {
    const double above = gaussianCdf(((k + 1) * c.range_resolution - range) / c.range_sigma);
    mass[static_cast<std::size_t>(k - first)] = above - below;
    below = above;
  }
  return mass;
}

double clampedLogRatio(long double occ, long double emp, const LaserSensorModelConfig& c) {
  if (occ <= 0.0L) return c.min_log_ratio;  // also covers occ = emp = 0, which cannot arise
  if (emp <= 0.0L) return c.max_log_ratio;
  // One double log of the ratio: both likelihoods share the scale q^-first, so the ratio is of
  // order one near the reading; a ratio beyond double's range lands on a clamp anyway.
  const double ratio = std::log(static_cast<double>(occ / emp));
  return std::clamp(ratio, c.min_log_ratio, c.max_log_ratio);
}

// Behind its peak L falls back to the prior (0) but stays positive up to the end of the error
// window. Summed over many scans, even 1e-6 per scan makes a cell occupied (log-odds > 0), so the
// trailing cells behind the peak with |L| < negligible carry no information: they are reset to 0
// and not counted as observed. The peak itself stays, however small (a wide sigma spreads the
// hit's evidence thin). Returns the number of cells left.
template <typename T>
int trimNegligibleTail(T* out, int first, int count, double negligible) {
  int peak = first;
  for (int k = first; k < count; ++k) peak = out[k] >= out[peak] ? k : peak;
  while (count - 1 > peak && std::abs(static_cast<double>(out[count - 1])) < negligible) {
    out[--count] = static_cast<T>(0);
  }
  return count;
}

// Eq. 3-4 convolved with the error model, written into out[0 .. capacity): returns the number of
// cells written (last cell of the error window + 1, at most capacity). All terms are scaled by
// q^-first (a common factor of both likelihoods) and summed in long double with prefix and suffix
// sums: O(window) per beam, plus the free cells in front of it.
template <typename T>
int writeHitLogRatios(double range, const LaserSensorModelConfig& c, T* out, int capacity) {
  int first = 0;
  int last = 0;
  errorWindow(range, c, &first, &last);
  const std::vector<long double> mass = cellMasses(range, first, last, c);
  const long double p = c.prior_occupancy;
  const long double q = 1.0L - p;
  const int width = last - first + 1;
  std::vector<long double> q_power(static_cast<std::size_t>(width) + 1, 1.0L);
  for (int i = 1; i <= width; ++i)
    q_power[static_cast<std::size_t>(i)] = q_power[static_cast<std::size_t>(i) - 1] * q;

  // later[i] = sum over window cells k > first + i of w_k p q^(k - 1 - first) (z > rho, emp)
  std::vector<long double> later(static_cast<std::size_t>(width) + 1, 0.0L);
  for (int i = width - 2; i >= 0; --i) {
    later[static_cast<std::size_t>(i)] =
        later[static_cast<std::size_t>(i) + 1] +
        mass[static_cast<std::size_t>(i) + 1] * p * q_power[static_cast<std::size_t>(i)];
  }
  const int count = std::min(capacity, last + 1);
  std::fill(out, out + std::min(count, first), static_cast<T>(c.min_log_ratio));  // -inf
  long double common = 0.0L;  // sum over window cells k < rho of w_k p q^(k - first) (z < rho)
  for (int i = 0; i < width && first + i < count; ++i) {
    const long double w = mass[static_cast<std::size_t>(i)];
    const long double q_i = q_power[static_cast<std::size_t>(i)];
    const long double occ = common + w * q_i;
    const long double emp = common + later[static_cast<std::size_t>(i)];
    out[first + i] = static_cast<T>(clampedLogRatio(occ, emp, c));
    common += w * p * q_i;
  }
  return trimNegligibleTail(out, std::min(first, count), count, c.negligible_log_ratio);
}

}  // namespace

void LaserSensorModelConfig::validate() const {
  if (!(std::isfinite(range_resolution) && range_resolution > 0.0)) {
    throw std::invalid_argument("LaserSensorModelConfig.range_resolution must be finite and > 0");
  }
  if (!(std::isfinite(range_sigma) && range_sigma >= 0.0)) {
    throw std::invalid_argument("LaserSensorModelConfig.range_sigma must be finite and >= 0");
  }
  if (!(prior_occupancy > 0.0 && prior_occupancy < 1.0)) {
    throw std::invalid_argument("LaserSensorModelConfig.prior_occupancy must be in (0, 1)");
  }
  if (!(std::isfinite(min_log_ratio) && min_log_ratio < 0.0)) {
    throw std::invalid_argument("LaserSensorModelConfig.min_log_ratio must be finite and < 0");
  }
  if (!(std::isfinite(max_log_ratio) && max_log_ratio > 0.0)) {
    throw std::invalid_argument("LaserSensorModelConfig.max_log_ratio must be finite and > 0");
  }
  if (!(std::isfinite(no_return_free_length) && no_return_free_length >= 0.0)) {
    throw std::invalid_argument(
        "LaserSensorModelConfig.no_return_free_length must be finite and >= 0");
  }
  if (!(std::isfinite(negligible_log_ratio) && negligible_log_ratio >= 0.0 &&
        negligible_log_ratio < max_log_ratio)) {
    throw std::invalid_argument(
        "LaserSensorModelConfig.negligible_log_ratio must be finite, >= 0 and < max_log_ratio");
  }
  ranges.validate();
}

BeamLogRatios hitLogRatios(double range, const LaserSensorModelConfig& c) {
  int first = 0;
  int last = 0;
  errorWindow(range, c, &first, &last);
  BeamLogRatios out;
  out.log_ratio.resize(static_cast<std::size_t>(last) + 1);
  const int count = writeHitLogRatios(range, c, out.log_ratio.data(), last + 1);
  out.log_ratio.resize(static_cast<std::size_t>(count));
  return out;
}

int polarCellCount(const LaserScan& scan, const LaserSensorModelConfig& c) {
  const double hit_reach = scan.range_max + kWindowSigmas * c.range_sigma;
  const double reach = std::max(hit_reach, c.no_return_free_length);
  return static_cast<int>(std::floor(reach / c.range_resolution)) + 1;
}

PolarField buildPolarField(const LaserScan& scan, const LaserSensorModelConfig& c) {
  PolarField field;
  buildPolarField(scan, c, &field);
  return field;
}

// Only the cells observed now are written, and only the cells observed by the previous scan and
// not now are reset: far fewer than the whole grid, whose cells beyond every reading stay 0.
void buildPolarField(const LaserScan& scan, const LaserSensorModelConfig& c, PolarField* field) {
  scan.validate();
  c.validate();
  const int beams = scan.beamCount();
  const int cells = polarCellCount(scan, c);
  const std::size_t total = static_cast<std::size_t>(beams) * cells;
  const bool same_shape = field->beams == beams && field->cells == cells &&
                          field->value.size() == total && field->observed.size() == total &&
                          field->observed_cells.size() == static_cast<std::size_t>(beams);
  if (!same_shape) {
    field->beams = beams;
    field->cells = cells;
    field->value.assign(total, 0.0f);
    field->observed.assign(total, 0.0f);
    field->observed_cells.assign(static_cast<std::size_t>(beams), 0);
  }
  field->range_resolution = c.range_resolution;
  field->angle_min = scan.angle_min;
  field->angle_increment = scan.angle_increment;

  const int free_cells =
      std::min(cells, static_cast<int>(std::floor(c.no_return_free_length / c.range_resolution)));
  for (int b = 0; b < beams; ++b) {
    const BeamReading reading = classifyBeam(scan.ranges[static_cast<std::size_t>(b)],
                                             scan.range_min, scan.range_max, c.ranges);
    float* value = field->value.data() + field->index(b, 0);
    float* observed = field->observed.data() + field->index(b, 0);
    int count = 0;
    if (reading.kind == BeamKind::kHit) {
      count = writeHitLogRatios(reading.range, c, value, cells);
    } else if (reading.kind == BeamKind::kNoReturn) {
      count = free_cells;
      std::fill(value, value + count, static_cast<float>(c.min_log_ratio));
    }
    int& previous = field->observed_cells[static_cast<std::size_t>(b)];
    if (previous > count) {
      std::fill(value + count, value + previous, 0.0f);
      std::fill(observed + count, observed + previous, 0.0f);
    } else {
      std::fill(observed + previous, observed + count, 1.0f);
    }
    previous = count;
  }
}

}  // namespace occupancy_fusion
