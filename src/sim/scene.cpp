#include "occupancy_fusion/sim/scene.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace occupancy_fusion {
namespace sim {

namespace {

// False when the ray cannot cross the sphere (center, radius) ahead of its origin at a distance
// below `nearest`.
bool mayHitCloser(const Eigen::Vector3d& center, double radius, const Eigen::Vector3d& origin,
                  const Eigen::Vector3d& unit_dir, double nearest) {
  const Eigen::Vector3d to_center = center - origin;
  const double along = to_center.dot(unit_dir);
  const double across_squared = to_center.squaredNorm() - along * along;
  if (across_squared > radius * radius) return false;
  const double half_chord = std::sqrt(radius * radius - across_squared);
  return along + half_chord > kRayEpsilon && along - half_chord < nearest;
}

// Slab test of the box |q_i| <= half_i for the ray o + t d (box frame), given 1 / d per axis.
// Updates `nearest` with the first crossing ahead of the origin (entry, or exit from inside).
void intersectCenteredBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                          const Eigen::Vector3d& inverse_d, const Eigen::Vector3d& half,
                          double& nearest) {
  double t_enter = -std::numeric_limits<double>::infinity();
  double t_exit = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) {
      if (std::abs(o[i]) > half[i]) return;
      continue;
    }
    double t_near = (-half[i] - o[i]) * inverse_d[i];
    double t_far = (half[i] - o[i]) * inverse_d[i];
    if (t_near > t_far) std::swap(t_near, t_far);
    t_enter = std::max(t_enter, t_near);
    t_exit = std::min(t_exit, t_far);
    if (t_enter > t_exit || t_exit <= kRayEpsilon || t_enter >= nearest) return;
  }
  const double t = t_enter > kRayEpsilon ? t_enter : t_exit;
  if (t < nearest) nearest = t;
}

}  // namespace

Scene& Scene::add(const Primitive& primitive) {
  std::visit([](const auto& p) { p.validate(); }, primitive);
  primitives_.push_back(primitive);
  const Eigen::AlignedBox3d primitive_bounds =
      std::visit([](const auto& p) { return p.bounds(); }, primitive);
  if (!primitive_bounds.isEmpty()) bounds_.extend(primitive_bounds);
  if (const auto* box = std::get_if<Box>(&primitive)) {
    const Eigen::Matrix3d R = box->T_world_box.linear();
    boxes_.push_back({R.transpose(), box->T_world_box.translation(), box->half_extents,
                      box->half_extents.norm(), R.isIdentity(0.0)});
  } else if (const auto* cylinder = std::get_if<Cylinder>(&primitive)) {
    cylinders_.push_back({*cylinder, std::hypot(cylinder->radius, 0.5 * cylinder->height)});
  } else if (const auto* sphere = std::get_if<Sphere>(&primitive)) {
    spheres_.push_back(*sphere);
  } else {
    planes_.push_back(std::get<Plane>(primitive));
  }
  return *this;
}

std::optional<double> Scene::castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& unit_dir,
                                     double max_range) const {
  // Same result as intersecting every primitive of primitives() and keeping the nearest hit:
  // the bounding spheres only skip primitives that cannot be hit closer.
  double nearest = std::numeric_limits<double>::infinity();
  auto keep = [&nearest](const std::optional<double>& t) {
    if (t && *t < nearest) nearest = *t;
  };
  for (const Plane& plane : planes_) keep(plane.intersect(origin, unit_dir));
  for (const Sphere& sphere : spheres_) keep(sphere.intersect(origin, unit_dir));
  const Eigen::Vector3d inverse_dir = unit_dir.cwiseInverse();
  for (const RayBox& box : boxes_) {
    if (!mayHitCloser(box.center, box.bound_radius, origin, unit_dir, nearest)) continue;
    if (box.axis_aligned) {
      intersectCenteredBox(origin - box.center, unit_dir, inverse_dir, box.half_extents, nearest);
    } else {
      const Eigen::Vector3d d = box.R_box_world * unit_dir;
      intersectCenteredBox(box.R_box_world * (origin - box.center), d, d.cwiseInverse(),
                           box.half_extents, nearest);
    }
  }
  for (const RayCylinder& entry : cylinders_) {
    if (mayHitCloser(entry.cylinder.center, entry.bound_radius, origin, unit_dir, nearest)) {
      keep(entry.cylinder.intersect(origin, unit_dir));
    }
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
