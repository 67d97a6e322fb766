#include "occupancy_fusion/sim/scene.h"

#include <limits>
#include <stdexcept>

namespace occupancy_fusion {
namespace sim {

Scene& Scene::add(const Primitive& primitive) {
  std::visit([](const auto& p) { p.validate(); }, primitive);
  primitives_.push_back(primitive);
  const Eigen::AlignedBox3d primitive_bounds =
      std::visit([](const auto& p) { return p.bounds(); }, primitive);
  if (!primitive_bounds.isEmpty()) bounds_.extend(primitive_bounds);
  return *this;
}

std::optional<double> Scene::castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& unit_dir,
                                     double max_range) const {
  double nearest = std::numeric_limits<double>::infinity();
  for (const Primitive& primitive : primitives_) {
    const std::optional<double> t =
        std::visit([&](const auto& p) { return p.intersect(origin, unit_dir); }, primitive);
    if (t && *t < nearest) nearest = *t;
  }
  if (nearest <= max_range) return nearest;
  return std::nullopt;
}

bool Scene::isOccupied(const Eigen::Vector3d& point) const {
  for (const Primitive& primitive : primitives_) {
    if (std::visit([&](const auto& p) { return p.contains(point); }, primitive)) return true;
  }
  return false;
}

double Scene::distanceToSurface(const Eigen::Vector3d& point) const {
  double nearest = std::numeric_limits<double>::infinity();
  for (const Primitive& primitive : primitives_) {
    nearest = std::min(
        nearest, std::visit([&](const auto& p) { return p.distanceToSurface(point); }, primitive));
  }
  return nearest;
}

std::vector<Eigen::Vector3d> Scene::sampleSurface(double spacing) const {
  if (!(spacing > 0)) throw std::invalid_argument("sampleSurface spacing must be positive");
  std::vector<Eigen::Vector3d> visible;
  for (std::size_t i = 0; i < primitives_.size(); ++i) {
    std::vector<Eigen::Vector3d> samples;
    std::visit([&](const auto& p) { p.appendSurfaceSamples(spacing, bounds_, samples); },
               primitives_[i]);
    for (const Eigen::Vector3d& sample : samples) {
      bool buried = false;
      for (std::size_t j = 0; j < primitives_.size() && !buried; ++j) {
        buried =
            j != i && std::visit([&](const auto& p) { return p.contains(sample); }, primitives_[j]);
      }
      if (!buried) visible.push_back(sample);
    }
  }
  return visible;
}

}  // namespace sim
}  // namespace occupancy_fusion
