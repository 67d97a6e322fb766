#include "occupancy_fusion/sim/primitives.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace occupancy_fusion {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Tolerance when keeping surface samples inside a clip box whose faces they lie on.
constexpr double kClipTolerance = 1e-9;

void require(bool condition, const std::string& field, const std::string& what) {
  if (!condition) throw std::invalid_argument(field + " " + what);
}

bool isUnit(const Eigen::Vector3d& v) { return v.allFinite() && std::abs(v.norm() - 1.0) < 1e-6; }

std::optional<double> smallestPositive(double a, double b) {
  if (a > b) std::swap(a, b);
  if (a > kRayEpsilon) return a;
  if (b > kRayEpsilon) return b;
  return std::nullopt;
}

// Number of cells of at most `spacing` that cover `length`.
int cellCount(double length, double spacing) {
  return std::max(1, static_cast<int>(std::ceil(length / spacing - 1e-9)));
}

void appendIfInside(const Eigen::Vector3d& point, const Eigen::AlignedBox3d& clip,
                    std::vector<Eigen::Vector3d>& out) {
  const Eigen::Vector3d tolerance = Eigen::Vector3d::Constant(kClipTolerance);
  if ((point.array() >= (clip.min() - tolerance).array()).all() &&
      (point.array() <= (clip.max() + tolerance).array()).all()) {
    out.push_back(point);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Box: slab method in the box's own frame.

Box Box::axisAligned(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
  Box box;
  box.T_world_box.translation() = 0.5 * (min + max);
  box.half_extents = 0.5 * (max - min);
  return box;
}

Box Box::yawed(const Eigen::Vector3d& center, const Eigen::Vector3d& size, double yaw) {
  Box box;
  box.T_world_box.translation() = center;
  box.T_world_box.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  box.half_extents = 0.5 * size;
  return box;
}

std::optional<double> Box::intersect(const Eigen::Vector3d& origin,
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
  return smallestPositive(t_enter, t_exit);
}

bool Box::contains(const Eigen::Vector3d& point) const {
  const Eigen::Vector3d q = T_world_box.inverse() * point;
  return (q.cwiseAbs().array() <= half_extents.array()).all();
}

double Box::distanceToSurface(const Eigen::Vector3d& point) const {
  const Eigen::Vector3d excess = (T_world_box.inverse() * point).cwiseAbs() - half_extents;
  const double outside = excess.cwiseMax(0.0).norm();
  return outside > 0.0 ? outside : -excess.maxCoeff();
}

Eigen::AlignedBox3d Box::bounds() const {
  Eigen::AlignedBox3d box;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d sign((corner & 1) ? 1 : -1, (corner & 2) ? 1 : -1, (corner & 4) ? 1 : -1);
    box.extend(T_world_box * sign.cwiseProduct(half_extents));
  }
  return box;
}

void Box::appendSurfaceSamples(double spacing, const Eigen::AlignedBox3d& clip,
                               std::vector<Eigen::Vector3d>& out) const {
  for (int axis = 0; axis < 3; ++axis) {
    const int b = (axis + 1) % 3;
    const int c = (axis + 2) % 3;
    const int nb = cellCount(2 * half_extents[b], spacing);
    const int nc = cellCount(2 * half_extents[c], spacing);
    for (double side : {-1.0, 1.0}) {
      for (int i = 0; i < nb; ++i) {
        for (int j = 0; j < nc; ++j) {
          Eigen::Vector3d q;
          q[axis] = side * half_extents[axis];
          q[b] = -half_extents[b] + (i + 0.5) * 2 * half_extents[b] / nb;
          q[c] = -half_extents[c] + (j + 0.5) * 2 * half_extents[c] / nc;
          appendIfInside(T_world_box * q, clip, out);
        }
      }
    }
  }
}

void Box::validate() const {
  require(half_extents.allFinite() && (half_extents.array() > 0).all(), "Box.half_extents",
          "must be positive and finite");
  const Eigen::Matrix3d R = T_world_box.linear();
  require(T_world_box.translation().allFinite(), "Box.T_world_box", "translation must be finite");
  require(R.allFinite() && (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-6 &&
              R.determinant() > 0,
          "Box.T_world_box", "rotation must be a proper rotation");
}

// ---------------------------------------------------------------------------------------------
// Sphere.

std::optional<double> Sphere::intersect(const Eigen::Vector3d& origin,
                                        const Eigen::Vector3d& unit_dir) const {
  // |o + t d - c|^2 = r^2 with |d| = 1: t^2 + 2 b t + c0 = 0.
  const Eigen::Vector3d oc = origin - center;
  const double b = oc.dot(unit_dir);
  const double c0 = oc.squaredNorm() - radius * radius;
  const double discriminant = b * b - c0;
  if (discriminant < 0) return std::nullopt;
  const double root = std::sqrt(discriminant);
  return smallestPositive(-b - root, -b + root);
}

bool Sphere::contains(const Eigen::Vector3d& point) const {
  return (point - center).squaredNorm() <= radius * radius;
}

double Sphere::distanceToSurface(const Eigen::Vector3d& point) const {
  return std::abs((point - center).norm() - radius);
}

Eigen::AlignedBox3d Sphere::bounds() const {
  return {center.array() - radius, center.array() + radius};
}

void Sphere::appendSurfaceSamples(double spacing, const Eigen::AlignedBox3d& clip,
                                  std::vector<Eigen::Vector3d>& out) const {
  // Fibonacci lattice: n nearly uniform points, each covering an area of about spacing^2.
  const int n =
      std::max(1, static_cast<int>(std::ceil(4 * kPi * radius * radius / (spacing * spacing))));
  const double golden_angle = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden_angle * i;
    appendIfInside(center + radius * Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z), clip,
                   out);
  }
}

void Sphere::validate() const {
  require(center.allFinite(), "Sphere.center", "must be finite");
  require(std::isfinite(radius) && radius > 0, "Sphere.radius", "must be positive and finite");
}

// ---------------------------------------------------------------------------------------------
// Plane (half-space).

std::optional<double> Plane::intersect(const Eigen::Vector3d& origin,
                                       const Eigen::Vector3d& unit_dir) const {
  const double denominator = normal.dot(unit_dir);
  if (std::abs(denominator) < 1e-15) return std::nullopt;
  const double t = normal.dot(point - origin) / denominator;
  if (t > kRayEpsilon) return t;
  return std::nullopt;
}

bool Plane::contains(const Eigen::Vector3d& p) const { return normal.dot(p - point) <= 0; }

double Plane::distanceToSurface(const Eigen::Vector3d& p) const {
  return std::abs(normal.dot(p - point));
}

Eigen::AlignedBox3d Plane::bounds() const { return Eigen::AlignedBox3d(); }

void Plane::appendSurfaceSamples(double spacing, const Eigen::AlignedBox3d& clip,
                                 std::vector<Eigen::Vector3d>& out) const {
  if (clip.isEmpty()) return;
  // A square grid in the plane, centred on the clip box centre's projection and large enough
  // to cover the whole box; points outside the box are dropped.
  const Eigen::Vector3d u = normal.unitOrthogonal();
  const Eigen::Vector3d w = normal.cross(u);
  const Eigen::Vector3d middle = clip.center() - normal.dot(clip.center() - point) * normal;
  const double half = 0.5 * clip.diagonal().norm();
  const int n = cellCount(2 * half, spacing);
  const double step = 2 * half / n;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      appendIfInside(middle + (-half + (i + 0.5) * step) * u + (-half + (j + 0.5) * step) * w, clip,
                     out);
    }
  }
}

void Plane::validate() const {
  require(point.allFinite(), "Plane.point", "must be finite");
  require(isUnit(normal), "Plane.normal", "must be a unit vector");
}

// ---------------------------------------------------------------------------------------------
// Cylinder: side as a quadratic in the plane across the axis, caps as two planes.

Cylinder Cylinder::upright(double x, double y, double base_z, double radius, double height) {
  Cylinder cylinder;
  cylinder.center = Eigen::Vector3d(x, y, base_z + 0.5 * height);
  cylinder.axis = Eigen::Vector3d::UnitZ();
  cylinder.radius = radius;
  cylinder.height = height;
  return cylinder;
}

std::optional<double> Cylinder::intersect(const Eigen::Vector3d& origin,
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

bool Cylinder::contains(const Eigen::Vector3d& point) const {
  const Eigen::Vector3d o = point - center;
  const double along = axis.dot(o);
  return std::abs(along) <= 0.5 * height && (o - along * axis).squaredNorm() <= radius * radius;
}

double Cylinder::distanceToSurface(const Eigen::Vector3d& point) const {
  const Eigen::Vector3d o = point - center;
  const double along = axis.dot(o);
  const double radial_excess = (o - along * axis).norm() - radius;
  const double axial_excess = std::abs(along) - 0.5 * height;
  if (radial_excess <= 0 && axial_excess <= 0) return std::min(-radial_excess, -axial_excess);
  return std::hypot(std::max(radial_excess, 0.0), std::max(axial_excess, 0.0));
}

Eigen::AlignedBox3d Cylinder::bounds() const {
  // Each cap disc reaches radius * sqrt(1 - axis_i^2) along world axis i.
  const Eigen::Vector3d reach =
      radius * (Eigen::Vector3d::Ones() - axis.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt();
  Eigen::AlignedBox3d box;
  for (double side : {-0.5, 0.5}) {
    const Eigen::Vector3d cap = center + side * height * axis;
    box.extend(cap - reach);
    box.extend(cap + reach);
  }
  return box;
}

void Cylinder::appendSurfaceSamples(double spacing, const Eigen::AlignedBox3d& clip,
                                    std::vector<Eigen::Vector3d>& out) const {
  const Eigen::Vector3d u = axis.unitOrthogonal();
  const Eigen::Vector3d w = axis.cross(u);
  auto around = [&](double r, double angle) {
    return r * (std::cos(angle) * u + std::sin(angle) * w);
  };
  const int n_around = cellCount(2 * kPi * radius, spacing);
  const int n_along = cellCount(height, spacing);
  for (int i = 0; i < n_along; ++i) {
    const double along = -0.5 * height + (i + 0.5) * height / n_along;
    for (int j = 0; j < n_around; ++j) {
      appendIfInside(center + along * axis + around(radius, 2 * kPi * (j + 0.5) / n_around), clip,
                     out);
    }
  }
  // Caps: concentric rings, each sampled at about `spacing`.
  const int n_rings = cellCount(radius, spacing);
  for (double side : {-0.5, 0.5}) {
    const Eigen::Vector3d cap = center + side * height * axis;
    for (int ring = 0; ring < n_rings; ++ring) {
      const double r = (ring + 0.5) * radius / n_rings;
      const int n = cellCount(2 * kPi * r, spacing);
      for (int j = 0; j < n; ++j)
        appendIfInside(cap + around(r, 2 * kPi * (j + 0.5) / n), clip, out);
    }
  }
}

void Cylinder::validate() const {
  require(center.allFinite(), "Cylinder.center", "must be finite");
  require(isUnit(axis), "Cylinder.axis", "must be a unit vector");
  require(std::isfinite(radius) && radius > 0, "Cylinder.radius", "must be positive and finite");
  require(std::isfinite(height) && height > 0, "Cylinder.height", "must be positive and finite");
}

}  // namespace sim
}  // namespace occupancy_fusion
