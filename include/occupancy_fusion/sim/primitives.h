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
#include <optional>
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

}  // namespace sim
}  // namespace occupancy_fusion
