// Analytic solid primitives of the scene simulator: ray intersection, inside test, exact
// distance to the surface and surface sampling, each in closed form.
//
// Conventions shared by every primitive:
//  - A primitive is a closed solid; its boundary counts as inside (contains() is inclusive).
//  - intersect(origin, unit_dir) returns the smallest t > kRayEpsilon at which the ray
//    origin + t * unit_dir crosses the primitive's surface, entering or leaving it. A ray that
//    starts inside therefore reports where it leaves the solid.
//  - distanceToSurface(p) is the unsigned Euclidean distance from p to the primitive's boundary,
//    exact, inside or outside.
//  - appendSurfaceSamples(spacing, clip, out) appends points of the boundary, roughly `spacing`
//    apart, that lie inside the box `clip` (needed for the unbounded Plane).
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

namespace occupancy_fusion {
namespace sim {

// Rays must move this far (m) before a crossing counts, so a ray starting on a surface does not
// report that same surface.
constexpr double kRayEpsilon = 1e-9;

// A box with arbitrary pose: the solid { T_world_box * q : |q_i| <= half_extents_i }.
struct Box {
  Eigen::Isometry3d T_world_box = Eigen::Isometry3d::Identity();  // box centre and orientation
  Eigen::Vector3d half_extents = Eigen::Vector3d::Constant(0.5);  // m, along the box's axes

  // The axis-aligned box spanning [min, max].
  static Box axisAligned(const Eigen::Vector3d& min, const Eigen::Vector3d& max);
  // A box of size `size` centred at `center`, turned by `yaw` (rad) about the world z axis.
  static Box yawed(const Eigen::Vector3d& center, const Eigen::Vector3d& size, double yaw);

  std::optional<double> intersect(const Eigen::Vector3d& origin,
                                  const Eigen::Vector3d& unit_dir) const;
  bool contains(const Eigen::Vector3d& point) const;
  double distanceToSurface(const Eigen::Vector3d& point) const;
  Eigen::AlignedBox3d bounds() const;
  void appendSurfaceSamples(double spacing, const Eigen::AlignedBox3d& clip,
                            std::vector<Eigen::Vector3d>& out) const;
  void validate() const;  // throws std::invalid_argument naming the bad field
};

struct Sphere {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0.5;  // m

  std::optional<double> intersect(const Eigen::Vector3d& origin,
                                  const Eigen::Vector3d& unit_dir) const;
  bool contains(const Eigen::Vector3d& point) const;
  double distanceToSurface(const Eigen::Vector3d& point) const;
  Eigen::AlignedBox3d bounds() const;
  void appendSurfaceSamples(double spacing, const Eigen::AlignedBox3d& clip,
                            std::vector<Eigen::Vector3d>& out) const;
  void validate() const;
};

// A half-space bounded by an infinite plane: solid on the side opposite the normal, so a floor
// is Plane{point on the floor, +z}: everything below it is solid.
struct Plane {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, pointing into free space

  std::optional<double> intersect(const Eigen::Vector3d& origin,
                                  const Eigen::Vector3d& unit_dir) const;
  bool contains(const Eigen::Vector3d& point) const;
  double distanceToSurface(const Eigen::Vector3d& point) const;
  Eigen::AlignedBox3d bounds() const;  // empty: a half-space has no finite bounds
  void appendSurfaceSamples(double spacing, const Eigen::AlignedBox3d& clip,
                            std::vector<Eigen::Vector3d>& out) const;
  void validate() const;
};

// A finite solid cylinder (with both caps) whose axis runs through `center`.
struct Cylinder {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // midpoint of the axis segment
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();   // unit
  double radius = 0.5;                               // m
  double height = 1.0;                               // m, length along the axis

  // An upright cylinder standing on the plane z = base_z.
  static Cylinder upright(double x, double y, double base_z, double radius, double height);

  std::optional<double> intersect(const Eigen::Vector3d& origin,
                                  const Eigen::Vector3d& unit_dir) const;
  bool contains(const Eigen::Vector3d& point) const;
  double distanceToSurface(const Eigen::Vector3d& point) const;
  Eigen::AlignedBox3d bounds() const;
  void appendSurfaceSamples(double spacing, const Eigen::AlignedBox3d& clip,
                            std::vector<Eigen::Vector3d>& out) const;
  void validate() const;
};

// ---------------------------------------------------------------------------------------------
// Ray intersections are defined here, inline, because they are the renderers' inner loop.

namespace detail {
// The smaller of two crossing parameters that lies ahead of the ray origin.
inline std::optional<double> smallestPositive(double a, double b) {
  if (a > b) std::swap(a, b);
  if (a > kRayEpsilon) return a;
  if (b > kRayEpsilon) return b;
  return std::nullopt;
}
}  // namespace detail

inline std::optional<double> Box::intersect(const Eigen::Vector3d& origin,
                                            const Eigen::Vector3d& unit_dir) const {
  const Eigen::Matrix3d R_box_world = T_world_box.linear().transpose();
  const Eigen::Vector3d o = R_box_world * (origin - T_world_box.translation());
  const Eigen::Vector3d d = R_box_world * unit_dir;
  double t_enter = -std::numeric_limits<double>::infinity();
  double t_exit = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) {
      // Parallel to this slab: either always inside it or never.
      if (std::abs(o[i]) > half_extents[i]) return std::nullopt;
      continue;
    }
    double t_near = (-half_extents[i] - o[i]) / d[i];
    double t_far = (half_extents[i] - o[i]) / d[i];
    if (t_near > t_far) std::swap(t_near, t_far);
    t_enter = std::max(t_enter, t_near);
    t_exit = std::min(t_exit, t_far);
  }
  if (t_enter > t_exit) return std::nullopt;
  return detail::smallestPositive(t_enter, t_exit);
}

inline std::optional<double> Sphere::intersect(const Eigen::Vector3d& origin,
                                               const Eigen::Vector3d& unit_dir) const {
  // |o + t d - c|^2 = r^2 with |d| = 1: t^2 + 2 b t + c0 = 0.
  const Eigen::Vector3d oc = origin - center;
  const double b = oc.dot(unit_dir);
  const double c0 = oc.squaredNorm() - radius * radius;
  const double discriminant = b * b - c0;
  if (discriminant < 0) return std::nullopt;
  const double root = std::sqrt(discriminant);
  return detail::smallestPositive(-b - root, -b + root);
}

inline std::optional<double> Plane::intersect(const Eigen::Vector3d& origin,
                                              const Eigen::Vector3d& unit_dir) const {
  const double denominator = normal.dot(unit_dir);
  if (std::abs(denominator) < 1e-15) return std::nullopt;
  const double t = normal.dot(point - origin) / denominator;
  if (t > kRayEpsilon) return t;
  return std::nullopt;
}

inline std::optional<double> Cylinder::intersect(const Eigen::Vector3d& origin,
                                                 const Eigen::Vector3d& unit_dir) const {
  const Eigen::Vector3d o = origin - center;
  const double o_along = axis.dot(o);
  const double d_along = axis.dot(unit_dir);
  const Eigen::Vector3d o_across = o - o_along * axis;
  const Eigen::Vector3d d_across = unit_dir - d_along * axis;
  const double half_height = 0.5 * height;
  double best = std::numeric_limits<double>::infinity();
  auto consider = [&](double t) {
    if (t > kRayEpsilon && t < best) best = t;
  };
  // Side: |o_across + t d_across|^2 = r^2, valid where the hit lies between the caps.
  const double a = d_across.squaredNorm();
  if (a > 1e-15) {
    const double b = o_across.dot(d_across) / a;
    const double c = (o_across.squaredNorm() - radius * radius) / a;
    const double discriminant = b * b - c;
    if (discriminant >= 0) {
      const double root = std::sqrt(discriminant);
      for (double t : {-b - root, -b + root}) {
        if (std::abs(o_along + t * d_along) <= half_height) consider(t);
      }
    }
  }
  // Caps: the planes at +-half_height along the axis, valid inside the disc.
  if (std::abs(d_along) > 1e-15) {
    for (double cap : {-half_height, half_height}) {
      const double t = (cap - o_along) / d_along;
      if ((o_across + t * d_across).squaredNorm() <= radius * radius) consider(t);
    }
  }
  if (std::isinf(best)) return std::nullopt;
  return best;
}

}  // namespace sim
}  // namespace occupancy_fusion
