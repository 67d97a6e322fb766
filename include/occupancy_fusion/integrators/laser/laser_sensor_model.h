// Yguel et al. 2006, Sec. II-B: the 1D telemetric sensor model of one laser
// beam over range cells, with a Gaussian range error and a prior, as log-ratios
// (Eq. 8); and the polar grid of those log-ratios for a whole scan (the paper's
// Z-grid).
#pragma once

#include <vector>

#include "occupancy_fusion/sensors/laser_scan.h"

namespace occupancy_fusion {

// Derivation. Range cell k (0-based) covers [k d_rho, (k+1) d_rho); the paper
// numbers it z = k + 1. Every cell is occupied a priori with probability p,
// independently (Eq. 1), and the beam stops at the first occupied cell, so the
// cell z where the detection happens has, knowing the state of cell rho (Eq.
// 3-4, which are the case p = 1/2, q = 1 - p):
//   p(z | occ_rho) = p q^(z-1) for z < rho,   q^(rho-1) for z = rho,   0 for z
//   > rho; p(z | emp_rho) = p q^(z-1) for z < rho,   0 for z = rho,           p
//   q^(z-2) for z > rho.
// The scanner reports a range r with a Gaussian error of standard deviation
// sigma around the true detection, so the probability that the detection
// happened in cell z is the Gaussian mass of that cell, w_z = Phi(((z) d_rho -
// r) / sigma) - Phi(((z-1) d_rho - r) / sigma), cut off beyond 6 sigma (all of
// it in r's cell when sigma = 0). The measurement likelihoods are
//   p(r | occ_rho) = sum_z w_z p(z | occ_rho),   p(r | emp_rho) = sum_z w_z p(z
//   | emp_rho),
// and the beam's contribution to cell rho is the log-ratio of Eq. 8,
//   L(rho) = log(p(r | occ_rho) / p(r | emp_rho))   (natural log, as the map's
//   log-odds).
// The grid's prior term log(p(occ)/p(emp)) of Eq. 8 is the map's business, not
// the sensor's.
//
// Values. Cells in front of the error window have p(r | occ) = 0 (the beam
// would have stopped there): L = -inf, clamped to min_log_ratio. Inside the
// window L rises through 0 to a positive peak near r (about +0.3 for sigma =
// d_rho, p = 1/2; larger for smaller sigma or p), clamped to max_log_ratio,
// then falls back to 0 (the prior) behind r: about +0.07, +0.006, +2e-4, ... per
// cell for sigma = d_rho. Behind the window both likelihoods are equal, L = 0.
// The trailing cells behind the peak with |L| < negligible_log_ratio (default
// 0.05, a probability within 0.0125 of 1/2) are "no information": not
// observed, left unknown, not written as 0. Kept, their tiny positive values
// would add up over many scans to an occupied band up to 6 sigma behind every
// surface. So every value lies in [min_log_ratio, max_log_ratio], and a hit
// beam's last observed cell is its peak or a later cell with |L| >=
// negligible_log_ratio (for sigma = d_rho: at most 2 sigma behind r).
//
// No return (+inf, REP-117): no detection within range_max has likelihood 0 for
// an occupied cell, so cells up to no_return_free_length get min_log_ratio;
// beyond, nothing. Too close (-inf) and invalid readings observe nothing.
struct LaserSensorModelConfig {
  double range_resolution = 0.05;      // d_rho, m: length of a range cell
  double range_sigma = 0.05;           // sigma, m: standard deviation of the range error (>= 0)
  double prior_occupancy = 0.5;        // p: a priori occupancy of every cell (Eq. 3-4 use 1/2)
  double min_log_ratio = -2.0;         // lower clamp of L (free evidence per scan)
  double max_log_ratio = 3.5;          // upper clamp of L (occupied evidence per scan)
  double no_return_free_length = 0.0;  // m: free length of a +inf beam; 0 = observes nothing
  double negligible_log_ratio = 0.05;  // trailing cells of a hit with |L| below: unobserved
  LaserRangeConfig ranges;             // how out-of-limits finite readings are read

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// One beam's log-ratios for cells 0 .. log_ratio.size() - 1 (every later cell
// is unobserved).
struct BeamLogRatios {
  std::vector<double> log_ratio;
};

// Evaluates the model above for a detection at range r (m), in the log domain
// so that q^z does not underflow for thousands of cells.
BeamLogRatios hitLogRatios(double range, const LaserSensorModelConfig& config);

// The Z-grid: one row of range cells per beam. value[b * cells + k] is L for
// beam b, cell k, and observed[...] is 1 where the beam observed that cell,
// else 0 (value 0 there too), so area- or sample-weighted sums of `value` treat
// unobserved cells as "no information".
struct PolarField {
  int beams = 0;
  int cells = 0;                  // range cells per beam
  double range_resolution = 0.0;  // d_rho, m
  double angle_min = 0.0;         // rad, centre of beam 0
  double angle_increment = 0.0;   // d_theta, rad; beam b covers angle(b) +- d_theta / 2
  std::vector<float> value;
  std::vector<float> observed;
  std::vector<int> observed_cells;  // per beam: cells [0, observed_cells[b]) are observed

  double angle(int beam) const { return angle_min + beam * angle_increment; }
  int index(int beam, int cell) const { return beam * cells + cell; }
};

// Number of range cells the polar grid of a scan needs: every cell a beam can
// observe.
int polarCellCount(const LaserScan& scan, const LaserSensorModelConfig& config);

// Builds the Z-grid of a scan (REP-117 semantics as documented above).
// Validates both.
PolarField buildPolarField(const LaserScan& scan, const LaserSensorModelConfig& config);
// The same into an existing field, reusing its buffers from the previous scan: only the cells
// observed now, and those the previous scan observed and this one does not, are written, so a
// stream of scans does not allocate or sweep the whole grid each time. Same result.
void buildPolarField(const LaserScan& scan, const LaserSensorModelConfig& config,
                     PolarField* field);

}  // namespace occupancy_fusion
