#include "occupancy_fusion/integrators/stereo/visibility_stereo_config.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace occupancy_fusion {

std::string toString(StereoIntegrationMethod method) {
  return method == StereoIntegrationMethod::kOctomap ? "octomap" : "visibility";
}

StereoIntegrationMethod stereoIntegrationMethodFromString(const std::string& name) {
  if (name == "visibility") return StereoIntegrationMethod::kVisibility;
  if (name == "octomap") return StereoIntegrationMethod::kOctomap;
  throw std::invalid_argument("stereo method must be visibility or octomap, not '" + name + "'");
}

std::string toString(UnknownNeighbours policy) {
  switch (policy) {
    case UnknownNeighbours::kPrior:
      return "prior";
    case UnknownNeighbours::kMeasured:
      return "measured";
    case UnknownNeighbours::kKnownOnly:
      break;
  }
  return "known_only";
}

UnknownNeighbours unknownNeighboursFromString(const std::string& name) {
  if (name == "known_only") return UnknownNeighbours::kKnownOnly;
  if (name == "prior") return UnknownNeighbours::kPrior;
  if (name == "measured") return UnknownNeighbours::kMeasured;
  throw std::invalid_argument("unknown_neighbours must be known_only, prior or measured, not '" +
                              name + "'");
}

std::string toString(StereoParameterSet set) {
  switch (set) {
    case StereoParameterSet::kFastExpansion:
      return "fast_expansion";
    case StereoParameterSet::kMeasured:
      return "measured";
    case StereoParameterSet::kTableI:
      break;
  }
  return "table_i";
}

StereoParameterSet stereoParameterSetFromString(const std::string& name) {
  if (name == "table_i") return StereoParameterSet::kTableI;
  if (name == "fast_expansion") return StereoParameterSet::kFastExpansion;
  if (name == "measured") return StereoParameterSet::kMeasured;
  throw std::invalid_argument("parameter set must be table_i, fast_expansion or measured, not '" +
                              name + "'");
}

VisibilityStereoConfig visibilityStereoConfigFor(StereoParameterSet set) {
  VisibilityStereoConfig config;  // Table I
  if (set == StereoParameterSet::kFastExpansion) {
    // See StereoParameterSet: deeper rays into unknown space, stronger partial-visibility misses.
    config.visibility_min = 0.003;
    config.prob_hit_invisible = 0.2;
  }
  if (set == StereoParameterSet::kMeasured) {
    config.unknown_neighbours = UnknownNeighbours::kMeasured;
    config.clear_passed = true;  // what has left the view is cleared in 3-4 frames, not 19-20
  }
  return config;
}

namespace {

void requireOpenUnit(double value, const char* field) {
  if (!(value > 0 && value < 1)) {
    throw std::invalid_argument(std::string("VisibilityStereoConfig.") + field +
                                " must be in (0, 1)");
  }
}

}  // namespace

void VisibilityStereoConfig::validate() const {
  if (method != StereoIntegrationMethod::kVisibility &&
      method != StereoIntegrationMethod::kOctomap) {
    throw std::invalid_argument("VisibilityStereoConfig.method is not a known method");
  }
  requireOpenUnit(prob_hit_visible_occupied, "prob_hit_visible_occupied");
  requireOpenUnit(prob_hit_visible_free, "prob_hit_visible_free");
  requireOpenUnit(prob_hit_invisible, "prob_hit_invisible");
  if (!(prob_hit_visible_occupied > prob_hit_visible_free)) {
    // Otherwise a hit would lower the occupancy of a visible voxel.
    throw std::invalid_argument(
        "VisibilityStereoConfig.prob_hit_visible_"
        "occupied must exceed prob_hit_visible_free");
  }
  if (!(prob_visible_if_occluded >= 0 && prob_visible_if_occluded <= 1)) {
    throw std::invalid_argument(
        "VisibilityStereoConfig.prob_visible_if_occluded must be in [0, 1]");
  }
  if (!(prob_visible_if_not_occluded >= 0 && prob_visible_if_not_occluded <= 1)) {
    throw std::invalid_argument(
        "VisibilityStereoConfig.prob_visible_if_not_"
        "occluded must be in [0, 1]");
  }
  if (!(visibility_max > 0 && visibility_max <= 1)) {
    throw std::invalid_argument("VisibilityStereoConfig.visibility_max must be in (0, 1]");
  }
  if (!(visibility_min > 0 && visibility_min <= visibility_max)) {
    throw std::invalid_argument(
        "VisibilityStereoConfig.visibility_min must be in (0, visibility_max]");
  }
  requireOpenUnit(unknown_occupancy, "unknown_occupancy");
  if (unknown_neighbours != UnknownNeighbours::kKnownOnly &&
      unknown_neighbours != UnknownNeighbours::kPrior &&
      unknown_neighbours != UnknownNeighbours::kMeasured) {
    throw std::invalid_argument("VisibilityStereoConfig.unknown_neighbours is not a known policy");
  }
  if (!(unknown_neighbour_occupancy >= 0 && unknown_neighbour_occupancy <= 1)) {
    throw std::invalid_argument(
        "VisibilityStereoConfig.unknown_neighbour_occupancy must be in [0, 1]");
  }
  if (!(passed_sigmas >= 0) || !std::isfinite(passed_sigmas)) {
    throw std::invalid_argument("VisibilityStereoConfig.passed_sigmas must be >= 0");
  }
  if (!(passed_miss_probability > 0 && passed_miss_probability < 0.5)) {
    throw std::invalid_argument(
        "VisibilityStereoConfig.passed_miss_probability must be in (0, 0.5)");
  }
  if (!(inside_stop_probability > 0.5 && inside_stop_probability < 1)) {
    throw std::invalid_argument(
        "VisibilityStereoConfig.inside_stop_probability must be in (0.5, 1)");
  }
  if (std::isnan(max_range)) {
    throw std::invalid_argument("VisibilityStereoConfig.max_range must not be NaN");
  }
  measured_surface.validate();
  if (!(measured_sigma_min_voxels > 0 && measured_sigma_max_voxels >= measured_sigma_min_voxels &&
        std::isfinite(measured_sigma_max_voxels))) {
    throw std::invalid_argument(
        "VisibilityStereoConfig.measured_sigma_min_voxels must be positive and at most "
        "measured_sigma_max_voxels (finite)");
  }
  disparity.validate();
}

}  // namespace occupancy_fusion
