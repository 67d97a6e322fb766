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
