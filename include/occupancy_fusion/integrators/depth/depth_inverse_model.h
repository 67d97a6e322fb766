// Eq. 7 of Pirker et al. 2011: the inverse sensor model of one depth measurement, and its
// log-odds tabulated over the normalised offset for the per-voxel loop.
#pragma once

#include <algorithm>
#include <optional>
#include <vector>

#include "occupancy_fusion/integrators/depth/pyramid_depth_config.h"

namespace occupancy_fusion {

// The farthest distance a measurement m informs (DepthInverseModel::informs): the voxels up to
// behind_sigmas of Eq. 7's sigma(m) = sigma + sigma_quadratic m^2 behind it.
struct MeasurementReach {
  double sigma = 0.0, sigma_quadratic = 0.0, behind_sigmas = 0.0;
  double of(double measured) const {
    return measured + behind_sigmas * (sigma + sigma_quadratic * measured * measured);
  }
};

// Eq. 7, for a voxel at distance z from the camera centre and a measured distance z_j.
class DepthInverseModel {
 public:
  explicit DepthInverseModel(const PyramidDepthConfig& config);  // validates config

  double sigmaAt(double measured) const {
    return reach_.sigma + reach_.sigma_quadratic * measured * measured;
  }
  double probability(double distance, double measured) const;  // Eq. 7
  float logOdds(double distance, double measured) const;       // log(p / (1 - p)) of Eq. 7
  // Eq. 7's log-odds as a function of the normalised offset x = (distance - measured) / sigma:
  // exact where sigma does not depend on the measurement (sigma_quadratic = 0), else nullopt.
  // Beyond +-supportSigmas() the log-odds are the constants logOdds() returns there.
  std::optional<double> logOddsAtOffset(double offset) const;
  static double supportSigmas();
  // k / (sigma sqrt(2 pi)): Eq. 7 peaks at 0.5 plus this at the measurement.
  static double peakAmplitude(double k, double sigma);
  float farInFrontLogOdds() const { return far_in_front_log_odds_; }
  // Offset in sigmas (positive) beyond which, in front of a measurement, Eq. 7 stays below 0.5
  // at every measured distance: 0.3 + (a + 0.2) exp(-x^2 / 2) = 0.5 at the largest amplitude a
  // (sigma at its smallest). A voxel that far in front of every cell it reads gets a negative
  // update, which a voxel clamped free ignores.
  double freeBeyondSigmas() const;
  // False when the voxel lies too far behind the measurement to learn anything from it.
  bool informs(double distance, double measured) const { return distance <= reach_.of(measured); }
  const MeasurementReach& reach() const { return reach_; }

 private:
  double k_;
  MeasurementReach reach_;
  float far_in_front_log_odds_;  // logit(0.3): Eq. 7 in front of the Gaussian's support
};

// Eq. 7 at constant sigma tabulated over the normalised offset x = (z - z_j) / sigma, read
// with linear interpolation: two exp() and one log() per pyramid cell are the bulk of the
// per-voxel cost otherwise. With 1024 samples per sigma the error is below 2e-6 in log-odds
// (the curve's second derivative stays below 10), far under the model's own uncertainty.
class OffsetLogOddsTable {
 public:
  OffsetLogOddsTable() = default;
  explicit OffsetLogOddsTable(const DepthInverseModel& model);  // empty unless sigma constant

  bool empty() const { return values_.empty(); }
  double limit() const { return limit_; }  // in sigmas: beyond it the values are constant
  // Branch-free: the first and last samples are the constants outside the support, so a
  // clamped offset reads them exactly.
  float at(double offset) const {
    const double position = (std::clamp(offset, -limit_, limit_) + limit_) * kSamplesPerSigma;
    // int, not std::size_t: a double to unsigned 64-bit conversion costs a branch on x86-64.
    const int index = std::min(static_cast<int>(position), last_interval_);
    const float fraction = static_cast<float>(position - static_cast<double>(index));
    return values_[index] + fraction * (values_[index + 1] - values_[index]);
  }

 private:
  static constexpr double kSamplesPerSigma = 1024.0;
  double limit_ = 0.0;
  int last_interval_ = 0;  // values_.size() - 2
  std::vector<float> values_;
};

}  // namespace occupancy_fusion
