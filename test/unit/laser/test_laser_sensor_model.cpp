#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "occupancy_fusion/integrators/laser/laser_sensor_model.h"

namespace occupancy_fusion {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Eq. 3-4 written out literally, with probabilities (no log domain, no prefix
// sums), for a short beam where q^z cannot underflow: the reference for
// hitLogRatios.
std::vector<double> literalLogRatios(double r, const LaserSensorModelConfig& c, int cells) {
  const double p = c.prior_occupancy;
  const double q = 1.0 - p;
  auto phi = [](double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); };
  std::vector<double> w(static_cast<std::size_t>(cells) + 1,
                        0.0);  // w[z], z = 1..cells
  for (int z = 1; z <= cells; ++z) {
    const double lo = (z - 1) * c.range_resolution;
    const double hi = z * c.range_resolution;
    // The model cuts the Gaussian beyond 6 sigma: keep the same support.
    if (hi <= r - 6 * c.range_sigma || lo > r + 6 * c.range_sigma) continue;
    w[static_cast<std::size_t>(z)] = phi((hi - r) / c.range_sigma) - phi((lo - r) / c.range_sigma);
  }
  std::vector<double> out;
  for (int rho = 1; rho <= cells; ++rho) {
    double occ = 0.0;
    double emp = 0.0;
    for (int z = 1; z <= cells; ++z) {
      const double pz_occ =
          z < rho ? p * std::pow(q, z - 1) : (z == rho ? std::pow(q, rho - 1) : 0);
      const double pz_emp =
          z < rho ? p * std::pow(q, z - 1) : (z == rho ? 0 : p * std::pow(q, z - 2));
      occ += w[static_cast<std::size_t>(z)] * pz_occ;
      emp += w[static_cast<std::size_t>(z)] * pz_emp;
    }
    double l = occ <= 0 ? -1e300 : (emp <= 0 ? 1e300 : std::log(occ / emp));
    out.push_back(std::min(std::max(l, c.min_log_ratio), c.max_log_ratio));
  }
  return out;
}

TEST(LaserSensorModel, NoErrorGivesFreeThenOccupiedThenNothing) {
  LaserSensorModelConfig c;
  c.range_sigma = 0.0;
  const BeamLogRatios beam = hitLogRatios(1.02, c);  // cell 20 of 5 cm cells
  ASSERT_EQ(beam.log_ratio.size(), 21u);
  // Eq. 3-4 without error: p(z | occ_rho) = 0 for z > rho (-inf), p(z |
  // emp_rho) = 0 at z = rho.
  for (int k = 0; k < 20; ++k) EXPECT_EQ(beam.log_ratio[k], c.min_log_ratio) << k;
  EXPECT_EQ(beam.log_ratio[20], c.max_log_ratio);
}

TEST(LaserSensorModel, HandValuesForTwoCellWindow) {
  // sigma tiny against d_rho and r on the border of cells 9 and 10 (0-based): w
  // = 1/2 each.
  LaserSensorModelConfig c;
  c.range_resolution = 0.1;
  c.range_sigma = 1e-6;
  c.prior_occupancy = 0.5;
  const BeamLogRatios beam = hitLogRatios(1.0, c);
  ASSERT_EQ(beam.log_ratio.size(), 11u);
  // z = k + 1. Cell k = 9 (z = 10): occ = w10 q^9 = 2^-10; emp = w11 p q^9 =
  // 2^-11 -> log 2.
  EXPECT_NEAR(beam.log_ratio[9], std::log(2.0), 1e-6);
  // Cell k = 10 (z = 11): occ = w10 p q^9 + w11 q^10 = 2^-11 + 2^-11; emp = w10
  // p q^9 = 2^-11.
  EXPECT_NEAR(beam.log_ratio[10], std::log(2.0), 1e-6);
  EXPECT_EQ(beam.log_ratio[8], c.min_log_ratio);
}

TEST(LaserSensorModel, MatchesLiteralEquations) {
  for (double p : {0.5, 0.3, 0.7}) {
    for (double sigma : {0.02, 0.05, 0.1}) {
      LaserSensorModelConfig c;
      c.prior_occupancy = p;
      c.range_sigma = sigma;
      c.min_log_ratio = -20.0;
      c.max_log_ratio = 20.0;
      c.negligible_log_ratio = 0.0;  // the whole error window
      const double r = 1.13;
      const BeamLogRatios beam = hitLogRatios(r, c);
      const std::vector<double> literal = literalLogRatios(r, c, 60);
      ASSERT_LE(beam.log_ratio.size(), literal.size());
      for (std::size_t k = 0; k < beam.log_ratio.size(); ++k) {
        EXPECT_NEAR(beam.log_ratio[k], literal[k], 1e-6)
            << "p " << p << " sigma " << sigma << " cell " << k;
      }
      // Behind the window the two likelihoods agree: no information.
      for (std::size_t k = beam.log_ratio.size(); k < literal.size(); ++k) {
        EXPECT_NEAR(literal[k], 0.0, 1e-6) << k;
      }
    }
  }
}

// Behind the reading L falls back to the prior: the trailing cells whose |L| is
// below negligible_log_ratio are cut off (unobserved), everything before them
// is the full model's value.
TEST(LaserSensorModel, NegligibleTailBehindTheHitIsUnobserved) {
  for (double sigma : {0.02, 0.05, 0.1}) {
    for (double r : {5.0, 5.013, 5.025, 5.04}) {
      LaserSensorModelConfig c;
      c.range_sigma = sigma;
      LaserSensorModelConfig whole = c;
      whole.negligible_log_ratio = 0.0;
      const BeamLogRatios cut = hitLogRatios(r, c);
      const BeamLogRatios full = hitLogRatios(r, whole);
      const std::string at = "sigma " + std::to_string(sigma) + " r " + std::to_string(r);
      ASSERT_LT(cut.log_ratio.size(), full.log_ratio.size()) << at;
      for (std::size_t k = 0; k < cut.log_ratio.size(); ++k)
        EXPECT_EQ(cut.log_ratio[k], full.log_ratio[k]) << at << " cell " << k;
      const double peak = *std::max_element(full.log_ratio.begin(), full.log_ratio.end());
      EXPECT_TRUE(std::abs(cut.log_ratio.back()) >= c.negligible_log_ratio ||
                  cut.log_ratio.back() == peak)
          << at;
      for (std::size_t k = cut.log_ratio.size(); k < full.log_ratio.size(); ++k) {
        EXPECT_LT(std::abs(full.log_ratio[k]), c.negligible_log_ratio) << at;
        EXPECT_LT(full.log_ratio[k], peak) << at;
      }
      // The last observed cell holds the reading or lies behind it and starts
      // within 3 sigma of it (the full window reaches 6 sigma).
      const double last_cell = (cut.log_ratio.size() - 1) * c.range_resolution;
      EXPECT_GT(last_cell + c.range_resolution, r) << at;
      EXPECT_LE(last_cell, r + 3.0 * sigma) << at;
    }
  }
  // sigma = d_rho, r on a cell border: -0.62, 0.29, 0.29, 0.068 | 0.0057, ...
  const BeamLogRatios beam = hitLogRatios(5.0, LaserSensorModelConfig());
  ASSERT_EQ(beam.log_ratio.size(), 102u);
  EXPECT_NEAR(beam.log_ratio[101], 0.0681, 1e-4);
}

TEST(LaserSensorModel, ValuesStayInClampRange) {
  LaserSensorModelConfig c;
  const BeamLogRatios beam = hitLogRatios(12.34, c);
  double peak = -1e9;
  for (double v : beam.log_ratio) {
    EXPECT_GE(v, c.min_log_ratio);
    EXPECT_LE(v, c.max_log_ratio);
    peak = std::max(peak, v);
  }
  EXPECT_GT(peak,
            0.1);  // the cells around the reading are evidence of occupancy
  EXPECT_EQ(beam.log_ratio.front(), c.min_log_ratio);
}

TEST(LaserSensorModel, Rep117Readings) {
  LaserRangeConfig strict;
  EXPECT_EQ(classifyBeam(2.0f, 0.1, 10.0, strict).kind, BeamKind::kHit);
  EXPECT_EQ(classifyBeam(kInf, 0.1, 10.0, strict).kind, BeamKind::kNoReturn);
  EXPECT_EQ(classifyBeam(-kInf, 0.1, 10.0, strict).kind, BeamKind::kTooClose);
  EXPECT_EQ(classifyBeam(kNaN, 0.1, 10.0, strict).kind, BeamKind::kInvalid);
  EXPECT_EQ(classifyBeam(11.0f, 0.1, 10.0, strict).kind, BeamKind::kInvalid);
  EXPECT_EQ(classifyBeam(0.05f, 0.1, 10.0, strict).kind, BeamKind::kInvalid);
  LaserRangeConfig carmen;
  carmen.above_range_max_is_no_return = true;
  EXPECT_EQ(classifyBeam(81.83f, 0.0, 49.9, carmen).kind, BeamKind::kNoReturn);
  EXPECT_EQ(classifyBeam(0.05f, 0.1, 10.0, carmen).kind, BeamKind::kInvalid);
}

TEST(LaserSensorModel, PolarFieldFollowsRep117) {
  LaserScan scan;
  scan.angle_min = -0.1;
  scan.angle_increment = 0.05;
  scan.range_min = 0.1;
  scan.range_max = 5.0;
  scan.ranges = {2.0f, kInf, -kInf, kNaN, 7.0f};
  LaserSensorModelConfig c;
  c.no_return_free_length = 1.0;
  PolarField field = buildPolarField(scan, c);
  EXPECT_EQ(field.beams, 5);
  EXPECT_EQ(field.cells, polarCellCount(scan, c));
  const BeamLogRatios hit = hitLogRatios(2.0, c);
  EXPECT_EQ(field.observed_cells[0], static_cast<int>(hit.log_ratio.size()));
  EXPECT_EQ(field.value[field.index(0, 0)], static_cast<float>(c.min_log_ratio));
  EXPECT_EQ(field.observed_cells[1], 20);  // +inf: free for 1 m
  EXPECT_EQ(field.value[field.index(1, 19)], static_cast<float>(c.min_log_ratio));
  EXPECT_EQ(field.observed[field.index(1, 19)], 1.0f);
  EXPECT_EQ(field.observed[field.index(1, 20)], 0.0f);
  EXPECT_EQ(field.observed_cells[2], 0);  // -inf
  EXPECT_EQ(field.observed_cells[3], 0);  // NaN
  EXPECT_EQ(field.observed_cells[4], 0);  // beyond range_max, strict REP-117
  c.ranges.above_range_max_is_no_return = true;
  field = buildPolarField(scan, c);
  EXPECT_EQ(field.observed_cells[4], 20);
  c.no_return_free_length = 0.0;
  field = buildPolarField(scan, c);
  EXPECT_EQ(field.observed_cells[1], 0);
}

TEST(LaserSensorModel, ValidateNamesField) {
  LaserSensorModelConfig c;
  c.prior_occupancy = 1.0;
  try {
    c.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("prior_occupancy"), std::string::npos);
  }
  c = LaserSensorModelConfig();
  c.negligible_log_ratio = -0.1;
  try {
    c.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("negligible_log_ratio"), std::string::npos);
  }
  LaserScan scan;
  scan.angle_increment = 0.0;
  scan.range_max = 1.0;
  scan.ranges = {1.0f};
  EXPECT_THROW(scan.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace occupancy_fusion
