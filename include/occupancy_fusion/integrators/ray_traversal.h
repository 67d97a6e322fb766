// Voxel-exact 3D ray traversal (Amanatides & Woo 1987, "A Fast Voxel Traversal Algorithm for
// Ray Tracing"): the voxels a segment passes through, in order, each once.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <type_traits>
#include <utility>

#include "occupancy_fusion/map/floor_to_int.h"

namespace occupancy_fusion {

using VoxelIndex = Eigen::Vector3i;  // floor(p / resolution), per axis, as VoxelMap::indexOf

// The voxel holding a point: the same arithmetic as VoxelMap::indexOf, without a map.
inline VoxelIndex voxelIndexOf(const Eigen::Vector3d& point, double resolution) {
  return {floorToInt(point.x() / resolution), floorToInt(point.y() / resolution),
          floorToInt(point.z() / resolution)};
}

// Walks the voxels of a grid of cubes of edge `resolution` that the segment start -> end passes
// through. Voxel membership follows the floor convention of VoxelMap::indexOf: a point on a
// boundary belongs to the voxel above it. Guarantees, also for boundary cases and
// floating-point ties:
//   - the first voxel is indexOf(start) and the segment part ends at indexOf(end);
//   - consecutive voxels share a face, and every step moves towards the end voxel, so no voxel
//     repeats and the segment part has exactly 1 + |Δx| + |Δy| + |Δz| voxels (Δ: end voxel minus
//     start voxel);
//   - where the segment crosses an edge or corner exactly, the extra voxel(s) needed for face
//     adjacency touch the segment at that edge or corner (ties step x before y before z).
// The step counts per axis are fixed from the two end voxels, so rounding can only change the
// order of steps at near-ties, never skip or overshoot the end voxel (a pure tMax walk can).
// After the end voxel, next() keeps walking along the ray beyond it (for methods that look past
// the measured point). Precondition: start and end finite, |coordinate| / resolution < 2^30.
class RayTraversal {
 public:
  RayTraversal(const Eigen::Vector3d& start, const Eigen::Vector3d& end, double resolution) {
    const Eigen::Vector3d direction = end - start;
    length_ = direction.norm();
    for (int axis = 0; axis < 3; ++axis) {
      const int first = floorToInt(start[axis] / resolution);
      const int last = floorToInt(end[axis] / resolution);
      current_[axis] = first;
      remaining_[axis] = std::abs(last - first);
      const double d = direction[axis];
      if (d > 0.0) {
        step_[axis] = 1;
        t_max_[axis] = ((first + 1) * resolution - start[axis]) / d;
        t_delta_[axis] = resolution / d;
      } else if (d < 0.0) {
        step_[axis] = -1;
        t_max_[axis] = (first * resolution - start[axis]) / d;
        t_delta_[axis] = -resolution / d;
      } else {
        step_[axis] = 0;
        t_max_[axis] = kInfinity;
        t_delta_[axis] = kInfinity;
      }
      // floor(x / r) is monotone in x, so the sign of d matches last - first.
      beyond_t_max_[axis] = t_max_[axis];
      if (remaining_[axis] == 0) t_max_[axis] = kInfinity;
    }
    steps_left_ = remaining_[0] + remaining_[1] + remaining_[2];
  }

  const VoxelIndex& current() const { return current_; }
  // Segment parameter t in [0, 1] (point = start + t * (end - start)) where the ray entered the
  // current voxel; 0 for the first. Multiply by length() for metres.
  double entryParameter() const { return t_entry_; }
  double length() const { return length_; }
  // True while current() is the end voxel (before any step beyond it).
  bool atEnd() const { return steps_left_ == 0 && !beyond_; }
  bool beforeEnd() const { return steps_left_ > 0; }
  // Voxels after current() up to and including the end voxel.
  int stepsToEnd() const { return steps_left_; }

  // Moves to the next voxel: towards the end voxel while before it, then along the ray beyond.
  // Beyond the end of a zero-length segment there is nowhere to go: current() stays.
  void next() {
    if (steps_left_ > 0) {
      stepTowardsEnd();
      return;
    }
    startBeyond();
    const int axis = nextAxis();
    if (t_max_[axis] == kInfinity) return;  // zero-length ray, beyond the end
    current_[axis] += step_[axis];
    t_entry_ = t_max_[axis];
    t_max_[axis] += t_delta_[axis];
  }

  // `steps` (<= stepsToEnd()) calls of stepTowardsEnd(), each followed by fn(current()); fn may
  // return bool: false stops the walk. Returns the calls of fn made.
  template <typename VoxelFn>
  int walkTowardsEnd(int steps, VoxelFn&& fn) {
    return walkAxesTowardsEnd(steps,
                              [&fn](const VoxelIndex& voxel, auto /*axis*/) { return fn(voxel); });
  }

  // walkTowardsEnd with fn(current(), axis), axis the std::integral_constant<int, 0, 1 or 2> of
  // the step just made, for callers that follow the walk incrementally. The walk's state is in
  // locals: indexing the members by the chosen axis keeps them in memory, and each step then
  // waits for the store of the one before.
  template <typename VoxelAxisFn>
  int walkAxesTowardsEnd(int steps, VoxelAxisFn&& fn) {
    using X = std::integral_constant<int, 0>;
    using Y = std::integral_constant<int, 1>;
    using Z = std::integral_constant<int, 2>;
    constexpr bool kMayStop =
        std::is_same_v<std::invoke_result_t<VoxelAxisFn&, const VoxelIndex&, X>, bool>;
    double tx = t_max_[0], ty = t_max_[1], tz = t_max_[2];
    const double dx = t_delta_[0], dy = t_delta_[1], dz = t_delta_[2];
    const int sx = step_[0], sy = step_[1], sz = step_[2];
    int rx = remaining_[0], ry = remaining_[1], rz = remaining_[2];
    VoxelIndex voxel = current_;
    double t_entry = t_entry_;
    int calls = 0;
    auto visit = [&](auto axis) {
      if constexpr (kMayStop) {
        return fn(static_cast<const VoxelIndex&>(voxel), axis);
      } else {
        fn(static_cast<const VoxelIndex&>(voxel), axis);
        return true;
      }
    };
    while (calls < steps) {
      bool go_on;
      // nextAxis(): ties step x before y before z.
      if (tx <= ty && tx <= tz) {
        voxel.x() += sx;
        t_entry = tx;
        tx += dx;
        if (--rx == 0) beyond_t_max_[0] = tx, tx = kInfinity;
        ++calls;
        go_on = visit(X{});
      } else if (ty <= tz) {
        voxel.y() += sy;
        t_entry = ty;
        ty += dy;
        if (--ry == 0) beyond_t_max_[1] = ty, ty = kInfinity;
        ++calls;
        go_on = visit(Y{});
      } else {
        voxel.z() += sz;
        t_entry = tz;
        tz += dz;
        if (--rz == 0) beyond_t_max_[2] = tz, tz = kInfinity;
        ++calls;
        go_on = visit(Z{});
      }
      if (!go_on) break;
    }
    t_max_[0] = tx, t_max_[1] = ty, t_max_[2] = tz;
    remaining_[0] = rx, remaining_[1] = ry, remaining_[2] = rz;
    current_ = voxel;
    t_entry_ = t_entry;
    steps_left_ -= calls;
    return calls;
  }

  // The direction of the walk's steps along an axis: +1, -1, or 0 when it never steps along it.
  int stepOf(int axis) const { return step_[axis]; }

  // next() for the hot loop of a segment walk. Precondition: beforeEnd().
  void stepTowardsEnd() {
    const int axis = nextAxis();
    current_[axis] += step_[axis];
    t_entry_ = t_max_[axis];
    t_max_[axis] += t_delta_[axis];
    --steps_left_;
    if (--remaining_[axis] == 0) {
      beyond_t_max_[axis] = t_max_[axis];
      t_max_[axis] = kInfinity;
    }
  }

 private:
  static constexpr double kInfinity = std::numeric_limits<double>::infinity();

  int nextAxis() const {
    if (t_max_[0] <= t_max_[1]) return t_max_[0] <= t_max_[2] ? 0 : 2;
    return t_max_[1] <= t_max_[2] ? 1 : 2;
  }

  void startBeyond() {
    if (beyond_) return;
    beyond_ = true;
    for (int axis = 0; axis < 3; ++axis) {
      if (t_max_[axis] == kInfinity) t_max_[axis] = beyond_t_max_[axis];
    }
  }

  VoxelIndex current_;
  int step_[3];
  int remaining_[3];
  int steps_left_ = 0;
  double t_max_[3];
  double t_delta_[3];
  double beyond_t_max_[3];  // next boundary of axes whose steps to the end voxel are done
  double t_entry_ = 0.0;
  double length_ = 0.0;
  bool beyond_ = false;
};

enum class RayEnd {
  kInclude,  // visit the end voxel too
  kExclude,  // stop before the end voxel (OctoMap's computeRayKeys: free space up to a hit)
};

// Calls fn(const VoxelIndex&) for each voxel of the segment start -> end in order (see
// RayTraversal). fn may return bool: false stops the walk. Returns the number of calls.
// Excluding the end voxel of a segment inside one voxel visits nothing.
template <typename VoxelFn>
int forEachVoxelOnRay(const Eigen::Vector3d& start, const Eigen::Vector3d& end, double resolution,
                      RayEnd end_mode, VoxelFn&& fn) {
  RayTraversal ray(start, end, resolution);
  const int count = ray.stepsToEnd() + (end_mode == RayEnd::kInclude ? 1 : 0);
  if (count == 0) return 0;
  if constexpr (std::is_same_v<std::invoke_result_t<VoxelFn&, const VoxelIndex&>, bool>) {
    if (!fn(ray.current())) return 1;
  } else {
    fn(ray.current());
  }
  return 1 + ray.walkTowardsEnd(count - 1, fn);
}

}  // namespace occupancy_fusion
