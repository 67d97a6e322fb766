// A scene: the union of analytic solid primitives, with ground-truth queries (ray casting,
// occupancy, distance to the surface, surface samples) for renderers, tests and evaluation.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <variant>
#include <vector>

#include "occupancy_fusion/sim/primitives.h"

namespace occupancy_fusion {
namespace sim {

using Primitive = std::variant<Box, Sphere, Plane, Cylinder>;

// Built once with add(), then only read: const member functions may run concurrently (the
// renderers call castRay from OpenMP threads).
class Scene {
 public:
  // Adds a primitive after validating it (throws std::invalid_argument naming the bad field).
  Scene& add(const Primitive& primitive);
  const std::vector<Primitive>& primitives() const { return primitives_; }

  // Distance t (m) to the first surface crossed by origin + t * unit_dir with
  // kRayEpsilon < t <= max_range, or nullopt. unit_dir must have length 1.
  std::optional<double> castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& unit_dir,
                                double max_range) const;

  // True inside any primitive or on its boundary.
  bool isOccupied(const Eigen::Vector3d& point) const;

  // Minimum over primitives of the exact distance to each primitive's boundary. Exact for
  // points outside all solids; inside overlapping solids it may be smaller than the distance
  // to the union's surface (it counts buried faces), which is acceptable for evaluation.
  double distanceToSurface(const Eigen::Vector3d& point) const;

  // Points on the scene's visible boundary, about `spacing` (m) apart: samples of each
  // primitive that lie inside (or on) another primitive are buried and left out, e.g. the
  // floor under a box. Half-spaces are sampled only within bounds().
  std::vector<Eigen::Vector3d> sampleSurface(double spacing) const;

  // Axis-aligned bounds of the finite primitives (half-spaces are unbounded and not counted);
  // empty when there are none.
  const Eigen::AlignedBox3d& bounds() const { return bounds_; }

 private:
  // A box prepared for castRay: its rotation inverted once, a bounding sphere to skip rays that
  // cannot hit it, and a flag for the common axis-aligned case.
  struct RayBox {
    Eigen::Matrix3d R_box_world;
    Eigen::Vector3d center;
    Eigen::Vector3d half_extents;
    double bound_radius;
    bool axis_aligned;
  };
  struct RayCylinder {
    Cylinder cylinder;
    double bound_radius;
  };

  std::vector<Primitive> primitives_;
  Eigen::AlignedBox3d bounds_;
  // Typed copies for castRay's inner loop: no variant dispatch, inlined intersections.
  std::vector<RayBox> boxes_;
  std::vector<RayCylinder> cylinders_;
  std::vector<Sphere> spheres_;
  std::vector<Plane> planes_;
};

}  // namespace sim
}  // namespace occupancy_fusion
