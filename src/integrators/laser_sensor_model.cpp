#include "occupancy_fusion/integrators/laser/laser_sensor_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace occupancy_fusion {

namespace {

constexpr double kWindowSigmas =
    6.0; // the Gaussian error is cut off beyond this many sigma

double gaussianCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

// First and last cell (inclusive) carrying Gaussian mass for a reading at
// `range`.
void errorWindow(double range, const LaserSensorModelConfig &c, int *first,
                 int *last) {
  const double reach = kWindowSigmas * c.range_sigma;
  *first = std::max(
      0, static_cast<int>(std::floor((range - reach) / c.range_resolution)));
  *last = std::max(*first, static_cast<int>(std::floor((range + reach) /
                                                       c.range_resolution)));
}

// w_z: probability that the true detection lies in cell k, given the reading.
std::vector<long double> cellMasses(double range, int first, int last,
                                    const LaserSensorModelConfig &c) {
  std::vector<long double> mass(static_cast<std::size_t>(last - first + 1),
                                0.0L);
  if (c.range_sigma == 0.0) {
    mass[static_cast<std::size_t>(static_cast<int>(range / c.range_resolution) -
                                  first)] = 1.0L;
    return mass;
  }
  for (int k = first; k <= last; ++k) {
    const double lower = (k * c.range_resolution - range) / c.range_sigma;
    const double upper = ((k + 1) * c.range_resolution - range) / c.range_sigma;
    mass[static_cast<std::size_t>(k - first)] =
        gaussianCdf(upper) - gaussianCdf(lower);
  }
  return mass;
}

double clampedLogRatio(long double occ, long double emp,
                       const LaserSensorModelConfig &c) {
  if (occ <= 0.0L)
    return c.min_log_ratio; // also covers occ = emp = 0, which cannot arise
  if (emp <= 0.0L)
    return c.max_log_ratio;
  const double ratio = static_cast<double>(std::log(occ) - std::log(emp));
  return std::clamp(ratio, c.min_log_ratio, c.max_log_ratio);
}

} // namespace

void LaserSensorModelConfig::validate() const {
  if (!(std::isfinite(range_resolution) && range_resolution > 0.0)) {
    throw std::invalid_argument(
        "LaserSensorModelConfig.range_resolution must be finite and > 0");
  }
  if (!(std::isfinite(range_sigma) && range_sigma >= 0.0)) {
    throw std::invalid_argument(
        "LaserSensorModelConfig.range_sigma must be finite and >= 0");
  }
  if (!(prior_occupancy > 0.0 && prior_occupancy < 1.0)) {
    throw std::invalid_argument(
        "LaserSensorModelConfig.prior_occupancy must be in (0, 1)");
  }
  if (!(std::isfinite(min_log_ratio) && min_log_ratio < 0.0)) {
    throw std::invalid_argument(
        "LaserSensorModelConfig.min_log_ratio must be finite and < 0");
  }
  if (!(std::isfinite(max_log_ratio) && max_log_ratio > 0.0)) {
    throw std::invalid_argument(
        "LaserSensorModelConfig.max_log_ratio must be finite and > 0");
  }
  if (!(std::isfinite(no_return_free_length) && no_return_free_length >= 0.0)) {
    throw std::invalid_argument(
        "LaserSensorModelConfig.no_return_free_length must be finite and >= 0");
  }
  ranges.validate();
}

// Eq. 3-4 convolved with the error model. All terms are scaled by q^-first (a
// common factor of both likelihoods) and summed in long double with prefix and
// suffix sums: O(cells) per beam.
BeamLogRatios hitLogRatios(double range, const LaserSensorModelConfig &c) {
  int first = 0;
  int last = 0;
  errorWindow(range, c, &first, &last);
  const std::vector<long double> mass = cellMasses(range, first, last, c);
  const long double p = c.prior_occupancy;
  const long double q = 1.0L - p;
  const int width = last - first + 1;

  // later[i] = sum over window cells k > first + i of w_k p q^(k - 1 - first)
  // (z > rho, emp)
  std::vector<long double> later(static_cast<std::size_t>(width) + 1, 0.0L);
  for (int i = width - 1; i >= 0; --i) {
    const long double term =
        i + 1 < width
            ? mass[static_cast<std::size_t>(i + 1)] * p * std::pow(q, i)
            : 0.0L;
    later[static_cast<std::size_t>(i)] =
        later[static_cast<std::size_t>(i) + 1] + term;
  }

  BeamLogRatios out;
  out.log_ratio.assign(static_cast<std::size_t>(last) + 1,
                       c.min_log_ratio); // k < first: -inf
  long double common =
      0.0L; // sum over window cells k < rho of w_k p q^(k - first)  (z < rho)
  for (int i = 0; i < width; ++i) {
    const long double w = mass[static_cast<std::size_t>(i)];
    const long double q_i = std::pow(q, i);
    const long double occ = common + w * q_i;
    const long double emp = common + later[static_cast<std::size_t>(i)];
    out.log_ratio[static_cast<std::size_t>(first + i)] =
        clampedLogRatio(occ, emp, c);
    common += w * p * q_i;
  }
  return out;
}

int polarCellCount(const LaserScan &scan, const LaserSensorModelConfig &c) {
  const double hit_reach = scan.range_max + kWindowSigmas * c.range_sigma;
  const double reach = std::max(hit_reach, c.no_return_free_length);
  return static_cast<int>(std::floor(reach / c.range_resolution)) + 1;
}

PolarField buildPolarField(const LaserScan &scan,
                           const LaserSensorModelConfig &c) {
  scan.validate();
  c.validate();
  PolarField field;
  field.beams = scan.beamCount();
  field.cells = polarCellCount(scan, c);
  field.range_resolution = c.range_resolution;
  field.angle_min = scan.angle_min;
  field.angle_increment = scan.angle_increment;
  const std::size_t total = static_cast<std::size_t>(field.beams) * field.cells;
  field.value.assign(total, 0.0f);
  field.observed.assign(total, 0.0f);
  field.observed_cells.assign(static_cast<std::size_t>(field.beams), 0);

  const int free_cells =
      std::min(field.cells, static_cast<int>(std::floor(
                                c.no_return_free_length / c.range_resolution)));
  for (int b = 0; b < field.beams; ++b) {
    const BeamReading reading =
        classifyBeam(scan.ranges[static_cast<std::size_t>(b)], scan.range_min,
                     scan.range_max, c.ranges);
    float *value = field.value.data() + field.index(b, 0);
    float *observed = field.observed.data() + field.index(b, 0);
    int count = 0;
    if (reading.kind == BeamKind::kHit) {
      const BeamLogRatios beam = hitLogRatios(reading.range, c);
      count = std::min(field.cells, static_cast<int>(beam.log_ratio.size()));
      for (int k = 0; k < count; ++k)
        value[k] = static_cast<float>(beam.log_ratio[k]);
    } else if (reading.kind == BeamKind::kNoReturn) {
      count = free_cells;
      std::fill(value, value + count, static_cast<float>(c.min_log_ratio));
    }
    std::fill(observed, observed + count, 1.0f);
    field.observed_cells[static_cast<std::size_t>(b)] = count;
  }
  return field;
}

} // namespace occupancy_fusion
