// Eq. 7: the inverse sensor model of one measurement, and its table over the normalised offset.
#include "occupancy_fusion/integrators/depth/depth_inverse_model.h"

#include <cmath>
#include <cstddef>
#include <optional>

namespace occupancy_fusion {

namespace {

const double kSqrtTwoPi = std::sqrt(2.0 * M_PI);
// Beyond this many sigmas the Gaussian of Eq. 7 is below 1e-13 of its peak: the log-odds equal
// their limits to far better than float precision, so exp() and log() can be skipped.
constexpr double kGaussianSupportSigmas = 8.0;

}  // namespace

DepthInverseModel::DepthInverseModel(const PyramidDepthConfig& config)
    : k_(config.k),
      reach_{config.sigma, config.sigma_quadratic, config.unknown_behind_sigmas},
      far_in_front_log_odds_(static_cast<float>(std::log(0.3 / 0.7))) {
  config.validate();
}

double DepthInverseModel::probability(double distance, double measured) const {
  const double sigma = sigmaAt(measured);
  const double offset = (distance - measured) / sigma;
  const double gaussian = std::exp(-0.5 * offset * offset);
  const double amplitude = k_ / (sigma * kSqrtTwoPi);
  if (distance <= measured) return 0.3 + (amplitude + 0.2) * gaussian;
  return 0.5 + amplitude * gaussian;
}

std::optional<double> DepthInverseModel::logOddsAtOffset(double offset) const {
  if (reach_.sigma_quadratic != 0.0) return std::nullopt;
  if (offset < -kGaussianSupportSigmas) return far_in_front_log_odds_;
  if (offset > kGaussianSupportSigmas) return 0.0;
  const double gaussian = std::exp(-0.5 * offset * offset);
  const double amplitude = k_ / (reach_.sigma * kSqrtTwoPi);
  const double p = offset <= 0.0 ? 0.3 + (amplitude + 0.2) * gaussian : 0.5 + amplitude * gaussian;
  return std::log(p / (1.0 - p));
}

double DepthInverseModel::supportSigmas() { return kGaussianSupportSigmas; }

double DepthInverseModel::freeBeyondSigmas() const {
  const double amplitude = peakAmplitude(k_, reach_.sigma);
  return std::sqrt(2.0 * std::log((amplitude + 0.2) / 0.2));
}

double DepthInverseModel::peakAmplitude(double k, double sigma) { return k / (sigma * kSqrtTwoPi); }

OffsetLogOddsTable::OffsetLogOddsTable(const DepthInverseModel& model)
    : limit_(DepthInverseModel::supportSigmas()) {
  if (!model.logOddsAtOffset(0.0)) return;
  const auto samples = static_cast<std::size_t>(2.0 * limit_ * kSamplesPerSigma) + 1;
  values_.resize(samples);
  last_interval_ = static_cast<int>(samples) - 2;
  for (std::size_t i = 0; i < samples; ++i) {
    values_[i] = static_cast<float>(
        *model.logOddsAtOffset(static_cast<double>(i) / kSamplesPerSigma - limit_));
  }
  // The constants beyond the support (they differ from the samples at +-limit_ by < 1e-13).
  values_.front() = model.farInFrontLogOdds();
  values_.back() = 0.0f;
}

float DepthInverseModel::logOdds(double distance, double measured) const {
  const double offset = (distance - measured) / sigmaAt(measured);
  if (offset < -kGaussianSupportSigmas) return far_in_front_log_odds_;
  if (offset > kGaussianSupportSigmas) return 0.0f;
  const double p = probability(distance, measured);
  return static_cast<float>(std::log(p / (1.0 - p)));
}

}  // namespace occupancy_fusion
