// Per voxel: Eq. 12-17 (the pyramid), Andert's layer and Eq. 8-9 (the ideal model), over a
// block's voxels at once.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "depth_detail.h"
#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"
#include "occupancy_fusion/map/floor_to_int.h"

namespace occupancy_fusion {

using depth_detail::isValidMeasurement;
using depth_detail::kNaN;

namespace {

// Level i with t_{i+1} < distance <= t_i (Eq. 12 with the layers' distances decreasing in i);
// -1 when the voxel lies beyond t_0.
int bracketingLevel(const DistancePyramid& pyramid, double distance) {
  if (distance > pyramid.threshold(0)) return -1;
  int level = 0;
  while (level + 1 < pyramid.levels() && distance <= pyramid.threshold(level + 1)) ++level;
  return level;
}

}  // namespace

std::optional<float> PyramidDepthIntegrator::voxelLogOdds(
    const DepthFrame& frame, const Eigen::Vector3d& voxel_center) const {
  const Eigen::Vector3d point = frame.T_camera_map * voxel_center;
  if (config_.method == DepthMethod::kIdeal) {
    const double distance = point.norm();
    if (distance < config_.min_range) return std::nullopt;
    return idealLogOdds(frame, voxel_center, distance);
  }
  const float delta = projectedLogOdds(frame, point);
  if (std::isnan(delta)) return std::nullopt;
  return delta;
}

// The per-voxel functions below are `inline` (they are private, used in this file only): in a
// shared library built with -fPIC, GCC does not inline an ordinary member function unless
// -fno-semantic-interposition is given (CMakeLists.txt adds it), since another library could
// interpose it; each voxel then pays five calls through the PLT and passes LayerCells through
// memory. `inline` keeps the voxel loop fast in builds without that flag.
inline bool PyramidDepthIntegrator::projectIntoImage(const CameraIntrinsics& camera,
                                                     const Eigen::Vector3d& point, double* u,
                                                     double* v, double* distance) const {
  // The image test first: it rejects most voxels of the frustum's border blocks without the
  // square root.
  if (point.z() <= 0.0) return false;
  const double inverse_z = 1.0 / point.z();  // Eq. 13
  *u = camera.fx * point.x() * inverse_z + camera.cx;
  *v = camera.fy * point.y() * inverse_z + camera.cy;
  if (!(*u >= -0.5 && *u < camera.width - 0.5 && *v >= -0.5 && *v < camera.height - 0.5)) {
    return false;
  }
  *distance = point.norm();
  return *distance >= config_.min_range;
}

inline float PyramidDepthIntegrator::projectedLogOdds(const DepthFrame& frame,
                                                      const Eigen::Vector3d& point) const {
  double u = 0.0, v = 0.0, distance = 0.0;
  if (!projectIntoImage(frame.camera, point, &u, &v, &distance)) return kNaN;
  if (config_.method == DepthMethod::kAndert) return andertLogOdds(frame, u, v, distance);
  return pyramidLogOdds(frame, u, v, distance);
}

inline PyramidDepthIntegrator::LayerPosition PyramidDepthIntegrator::layerPosition(
    const DepthFrame& frame, int level, double pixel_u, double pixel_v) {
  // Eq. 14 with pixel centres at integer coordinates: cell U of layer i is centred on pixel
  // U 2^i + (2^i - 1) / 2, so u maps to (u + 0.5) / 2^i - 0.5 (>= -0.5 inside the image).
  const double scale = frame.pyramid.scale(level);
  const double u = (pixel_u + 0.5) * scale - 0.5;
  const double v = (pixel_v + 0.5) * scale - 0.5;
  LayerPosition position;
  position.level = level;
  position.u0 = floorToInt(u);
  position.v0 = floorToInt(v);
  position.fu = u - position.u0;  // <u> of Eq. 16
  position.fv = v - position.v0;
  return position;
}

inline bool PyramidDepthIntegrator::layerMayInform(const DepthFrame& frame,
                                                   const LayerPosition& position, double distance) {
  // reachOfSquare bounds the four cells gatherCells weighs at this position.
  return distance <= frame.pyramid.reachOfSquare(position.level, position.u0, position.v0);
}

inline PyramidDepthIntegrator::LayerCells PyramidDepthIntegrator::gatherCells(
    const DepthFrame& frame, const LayerPosition& position, double distance) const {
  const DistancePyramid& pyramid = frame.pyramid;
  const int level = position.level;
  const int u0 = position.u0, v0 = position.v0;
  const double fu = position.fu, fv = position.fv;
  const int width = pyramid.width(level);
  const int height = pyramid.height(level);
  const float* cells = pyramid.cells(level);
  const double weights[4] = {(1.0 - fu) * (1.0 - fv), fu * (1.0 - fv), (1.0 - fu) * fv,
                             fu * fv};  // Eq. 15
  // Inside the layer all four cells exist: one test instead of four.
  const bool interior = u0 >= 0 && v0 >= 0 && u0 + 1 < width && v0 + 1 < height;
  LayerCells result;
  for (int i = 0; i < 4; ++i) {
    const int cu = u0 + (i & 1);
    const int cv = v0 + (i >> 1);
    float measured = kNaN;
    if (interior || (cu >= 0 && cv >= 0 && cu < width && cv < height)) {
      measured = cells[static_cast<std::size_t>(cv) * width + cu];
    }
    // Invalid pixels contribute nothing: Eq. 15 is renormalised over the valid neighbours.
    // Their slots keep weight 0 and a harmless measurement, so Eq. 16 needs no branches.
    const bool valid = weights[i] > 0.0 && isValidMeasurement(measured);
    result.weights[i] = valid ? weights[i] : 0.0;
    result.measured[i] = valid ? measured : static_cast<float>(distance);
    result.weight_sum += result.weights[i];
    result.complete = result.complete && valid;
    result.nearest = valid && measured < result.nearest ? measured : result.nearest;
    result.farthest = valid && measured > result.farthest ? measured : result.farthest;
  }
  // DepthInverseModel::informs grows with the measurement (also in floating point: every step
  // of measured + behind sigma(measured) is monotonic), so the farthest valid cell decides.
  result.informs = result.valid() && model_.informs(distance, result.farthest);
  return result;
}

inline float PyramidDepthIntegrator::bilinearLogOdds(const LayerCells& cells,
                                                     double distance) const {
  double weighted = 0.0;
  for (int i = 0; i < 4; ++i) {
    weighted += cells.weights[i] * cellLogOdds(distance, cells.measured[i]);  // Eq. 16
  }
  // With all four cells valid the weights sum to 1 (up to rounding): no division, which is
  // on the voxel's critical path.
  return static_cast<float>(cells.complete ? weighted : weighted / cells.weight_sum);
}

inline float PyramidDepthIntegrator::pyramidLogOdds(const DepthFrame& frame, double u, double v,
                                                    double distance) const {
  const DistancePyramid& pyramid = frame.pyramid;
  const int level = bracketingLevel(pyramid, distance);
  // Beyond t_0, or nearer than the last layer's t: one layer alone.
  if (level < 0 || level + 1 >= pyramid.levels()) {
    const LayerPosition position = layerPosition(frame, std::max(level, 0), u, v);
    if (!layerMayInform(frame, position, distance)) return kNaN;
    const LayerCells only = gatherCells(frame, position, distance);
    if (!only.valid() || !only.informs) return kNaN;
    if (farInFront(distance, only.nearest)) return model_.farInFrontLogOdds();
    return bilinearLogOdds(only, distance);
  }
  // Behind every surface both layers see (a third of the voxels at 0.02-0.05 m): no gathers.
  const LayerPosition fine_position = layerPosition(frame, level, u, v);
  const LayerPosition coarse_position = layerPosition(frame, level + 1, u, v);
  if (!layerMayInform(frame, fine_position, distance) &&
      !layerMayInform(frame, coarse_position, distance)) {
    return kNaN;
  }
  const LayerCells fine = gatherCells(frame, fine_position, distance);
  const LayerCells coarse = gatherCells(frame, coarse_position, distance);
  if (!(fine.informs || coarse.informs)) return kNaN;
  if (farInFront(distance, std::min(fine.nearest, coarse.nearest))) {
    return model_.farInFrontLogOdds();
  }
  if (!fine.valid()) return bilinearLogOdds(coarse, distance);
  if (!coarse.valid()) return bilinearLogOdds(fine, distance);
  const float fine_log_odds = bilinearLogOdds(fine, distance);  // float: Eq. 17 subtracts in float
  const float coarse_log_odds = bilinearLogOdds(coarse, distance);
  // Eq. 17: l^i at z = t_i, l^{i+1} at z = t_{i+1}, linear in between.
  return static_cast<float>(fine_log_odds + (distance - pyramid.threshold(level)) *
                                                (coarse_log_odds - fine_log_odds) *
                                                pyramid.inverseGap(level));
}

inline float PyramidDepthIntegrator::andertLogOdds(const DepthFrame& frame, double u, double v,
                                                   double distance) const {
  // The layer whose cells best match the voxel's footprint of t_0 / z pixels, nearest cell.
  const DistancePyramid& pyramid = frame.pyramid;
  const double footprint_log2 = std::log2(pyramid.threshold(0) / distance);
  const int level =
      std::clamp(static_cast<int>(std::lround(footprint_log2)), 0, pyramid.levels() - 1);
  const double scale = pyramid.scale(level);
  const int cu = std::min(floorToInt((u + 0.5) * scale), pyramid.width(level) - 1);
  const int cv = std::min(floorToInt((v + 0.5) * scale), pyramid.height(level) - 1);
  const float measured = pyramid.at(level, std::max(cu, 0), std::max(cv, 0));
  if (!isValidMeasurement(measured) || !model_.informs(distance, measured)) return kNaN;
  return cellLogOdds(distance, measured);
}

std::optional<float> PyramidDepthIntegrator::idealLogOdds(const DepthFrame& frame,
                                                          const Eigen::Vector3d& voxel_center,
                                                          double distance) const {
  const CameraIntrinsics& camera = frame.camera;
  const double half = 0.5 * frame.resolution;
  const Eigen::Vector3d lo = voxel_center.array() - half;
  const Eigen::Vector3d hi = voxel_center.array() + half;
  // Pixels whose centre rays can cross the voxel: the bounding box of its corners' projections.
  double u_min = std::numeric_limits<double>::infinity(), u_max = -u_min;
  double v_min = u_min, v_max = -u_min;
  bool behind_camera = false;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p(corner & 1 ? hi.x() : lo.x(), corner & 2 ? hi.y() : lo.y(),
                            corner & 4 ? hi.z() : lo.z());
    const Eigen::Vector3d q = frame.T_camera_map * p;
    if (q.z() <= 1e-9) {
      behind_camera = true;
      break;
    }
    const Eigen::Vector2d uv = camera.project(q);
    u_min = std::min(u_min, uv.x());
    u_max = std::max(u_max, uv.x());
    v_min = std::min(v_min, uv.y());
    v_max = std::max(v_max, uv.y());
  }
  const int u_first = behind_camera ? 0 : std::max(0, static_cast<int>(std::ceil(u_min)));
  const int u_last =
      behind_camera ? camera.width - 1 : std::min(camera.width - 1, int(std::floor(u_max)));
  const int v_first = behind_camera ? 0 : std::max(0, static_cast<int>(std::ceil(v_min)));
  const int v_last =
      behind_camera ? camera.height - 1 : std::min(camera.height - 1, int(std::floor(v_max)));

  const Eigen::Vector3d origin = frame.T_map_camera.translation();
  const Eigen::Matrix3d rotation = frame.T_map_camera.linear();
  double weighted = 0.0;
  double eta = 0.0;  // Eq. 9
  bool informs = false;
  for (int v = v_first; v <= v_last; ++v) {
    for (int u = u_first; u <= u_last; ++u) {
      const float measured = frame.pyramid.at(0, u, v);
      if (!isValidMeasurement(measured)) continue;
      // Length of the (unbounded, infinitely thin) pixel ray inside the voxel: slab test.
      const Eigen::Vector3d direction = (rotation * camera.pixelRay(u, v)).normalized();
      double enter = 0.0;
      double exit = std::numeric_limits<double>::infinity();
      for (int axis = 0; axis < 3; ++axis) {
        if (direction[axis] == 0.0) {
          if (origin[axis] < lo[axis] || origin[axis] > hi[axis]) exit = -1.0;
          continue;
        }
        double t1 = (lo[axis] - origin[axis]) / direction[axis];
        double t2 = (hi[axis] - origin[axis]) / direction[axis];
        if (t1 > t2) std::swap(t1, t2);
        enter = std::max(enter, t1);
        exit = std::min(exit, t2);
      }
      const double length = exit - enter;
      if (!(length > 0.0)) continue;
      weighted += length * model_.logOdds(distance, measured);  // Eq. 8
      eta += length;
      informs = informs || model_.informs(distance, measured);
    }
  }
  if (eta <= 0.0 || !informs) return std::nullopt;
  return static_cast<float>(weighted / eta);
}

namespace {

// Voxels x = first ... last of one row (fixed y and z) of a block; empty when last < first.
struct VoxelRun {
  int first = 0;
  int last = VoxelBlock::kSide - 1;
};

// Eq. 13's image test without projecting: a camera-frame point p projects inside the image
// (z > 0, -0.5 <= u < width - 0.5, and likewise v) only if n . p >= 0 for the five planes
// through the camera centre below. n . p is linear in the voxel's index within a block, so per
// row of voxels the ones that can project inside form a run found with five divisions; only
// they are projected (at 0.02 m a third of the examined voxels lie outside the image, at
// 0.08 m two thirds). The run is a superset: each voxel in it still takes the exact test, so
// the map does not change.
class BlockImageRuns {
 public:
  BlockImageRuns(const DepthFrame& frame, const VoxelMap& map, const VoxelIndex& first) {
    const CameraIntrinsics& camera = frame.camera;
    const Eigen::Vector3d normals[kPlanes] = {{0.0, 0.0, 1.0},
                                              {camera.fx, 0.0, camera.cx + 0.5},
                                              {-camera.fx, 0.0, camera.width - 0.5 - camera.cx},
                                              {0.0, camera.fy, camera.cy + 0.5},
                                              {0.0, -camera.fy, camera.height - 0.5 - camera.cy}};
    constexpr int kLast = VoxelBlock::kSide - 1;
    const auto camera_point = [&](int x, int y, int z) -> Eigen::Vector3d {
      return frame.T_camera_map * map.centerOf(first + VoxelIndex(x, y, z));
    };
    const Eigen::Vector3d origin = camera_point(0, 0, 0);
    const Eigen::Vector3d step_x = (camera_point(kLast, 0, 0) - origin) / kLast;
    const Eigen::Vector3d step_y = (camera_point(0, kLast, 0) - origin) / kLast;
    const Eigen::Vector3d step_z = (camera_point(0, 0, kLast) - origin) / kLast;
    for (int k = 0; k < kPlanes; ++k) {
      // A micrometre of slack covers the rounding of the transform and of this linear model
      // (below 1e-9 m for coordinates within kilometres of the origin).
      planes_[k] = {normals[k].dot(origin) + kSlack * normals[k].norm(), normals[k].dot(step_x),
                    normals[k].dot(step_y), normals[k].dot(step_z)};
    }
  }

  VoxelRun of(int y, int z) const {
    VoxelRun run;
    for (const Plane& plane : planes_) {
      clip(plane.at_origin + y * plane.per_y + z * plane.per_z, plane.per_x, &run);
    }
    return run;
  }

 private:
  static constexpr int kPlanes = 5;
  static constexpr double kSlack = 1e-6;  // m
  struct Plane {
    double at_origin = 0.0;  // n . p of voxel (0, 0, 0), plus the slack
    double per_x = 0.0, per_y = 0.0, per_z = 0.0;
  };
  // Keeps the x with at_row_start + x per_x >= 0 (the slack makes this a superset).
  static void clip(double at_row_start, double per_x, VoxelRun* run) {
    const double side = VoxelBlock::kSide;
    if (per_x == 0.0) {
      if (at_row_start < 0.0) run->last = -1;
      return;
    }
    // The crossing, clamped before the conversion to int.
    const double crossing = std::clamp(-at_row_start / per_x, -1.0, side);
    if (per_x > 0.0) {
      run->first = std::max(run->first, static_cast<int>(std::ceil(crossing)));
    } else {
      run->last = std::min(run->last, static_cast<int>(std::floor(crossing)));
    }
  }
  Plane planes_[kPlanes];
};

}  // namespace

namespace {

// VoxelMap::centerOf, the same arithmetic (so the same bits), where the voxel loop can inline it:
// a call into the map's library per voxel was 1 % of a frame's CPU at 0.02 m.
Eigen::Vector3d voxelCenter(const VoxelIndex& index, double resolution) {
  return (index.cast<double>().array() + 0.5) * resolution;
}

}  // namespace

bool PyramidDepthIntegrator::seenThrough(const DepthFrame& frame, double u, double v,
                                         double distance) const {
  const DistancePyramid& pyramid = frame.pyramid;
  const int width = pyramid.width(0), height = pyramid.height(0);
  const int cu = static_cast<int>(std::lround(u)), cv = static_cast<int>(std::lround(v));
  if (cu < 0 || cv < 0 || cu >= width || cv >= height) return false;
  const double half_diagonal = 0.5 * std::sqrt(3.0) * frame.resolution;
  const auto beyond = [&](float measured) {
    return measured - distance > config_.passed_sigmas * model_.sigmaAt(measured);
  };
  const auto ends_there = [&](float measured) {
    return std::abs(measured - distance) <=
           half_diagonal + config_.passed_sigmas * model_.sigmaAt(measured);
  };
  // A surface voxel seen again (most calls): its centre pixel ends in it.
  const float centre = pyramid.at(0, cu, cv);
  const bool centre_returned = isValidMeasurement(centre);
  if (centre_returned && ends_there(centre)) return false;
  // The footprint: pixels within a voxel's half diagonal of the centre's projection.
  constexpr int kMaxRadius = 8;  // px: only near voxels reach it; those pixels decide alone
  const double pixels_per_metre = frame.camera.fx / distance;
  const int radius =
      std::min(kMaxRadius, static_cast<int>(std::ceil(pixels_per_metre * half_diagonal)));
  const int u_first = std::max(cu - radius, 0), u_last = std::min(cu + radius, width - 1);
  const int v_first = std::max(cv - radius, 0), v_last = std::min(cv + radius, height - 1);
  // Any ray through the voxel itself (within half a voxel side of the centre's projection) may
  // show it passed: the centre pixel alone may have no return (a ray past a door's edge into an
  // open room) or end on the edge in front. A 3 x 3 grid of rays over that disc is asked, so that
  // a voxel the frame does not see through (most calls: one behind a nearer surface) costs nine
  // reads, not its footprint's.
  const double inner = 0.5 * frame.resolution * pixels_per_metre;
  const auto passes = [&](double du, double dv) {
    const int pu = floorToInt(u + du + 0.5);  // the nearest pixel (lround calls into libm)
    const int pv = floorToInt(v + dv + 0.5);
    if (pu < u_first || pv < v_first || pu > u_last || pv > v_last) return false;
    const double du_px = pu - u, dv_px = pv - v;
    if (du_px * du_px + dv_px * dv_px > inner * inner) return false;  // misses the voxel's disc
    const float measured = pyramid.at(0, pu, pv);
    return isValidMeasurement(measured) && beyond(measured) && !ends_there(measured);
  };
  bool passed = centre_returned && beyond(centre);
  const double spacing = 0.7 * inner;  // the grid's corners within the disc
  for (int j = -1; j <= 1 && !passed; ++j) {
    for (int i = -1; i <= 1 && !passed; ++i) passed = passes(i * spacing, j * spacing);
  }
  if (!passed) return false;
  for (int pv = v_first; pv <= v_last; ++pv) {
    for (int pu = u_first; pu <= u_last; ++pu) {
      const float measured = pyramid.at(0, pu, pv);
      if (isValidMeasurement(measured) && ends_there(measured)) return false;  // measured there
    }
  }
  return true;
}

int PyramidDepthIntegrator::blockLogOdds(const DepthFrame& frame, const CandidateBlock& block,
                                         const VoxelMap& map, float* deltas,
                                         const VoxelMap::VoxelStates* states, bool skip_settled,
                                         int* unchanged) const {
  std::fill(deltas, deltas + VoxelBlock::kVolume, kNaN);
  int count = 0;
  // A voxel clamped free and nearer than free_front: its update is negative (or none), a no-op.
  const auto settled = [&](int linear, double distance) {
    if (!skip_settled || states == nullptr || !states->at_lower_bound.test(linear) ||
        !(distance < block.free_front)) {
      return false;
    }
    ++*unchanged;
    return true;
  };
  // clear_passed: an occupied voxel the frame sees well in front of the measurements it reads.
  const bool clear_passed = config_.clear_passed && states != nullptr;
  if (config_.method == DepthMethod::kIdeal) {
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
      const std::optional<float> delta =
          voxelLogOdds(frame, map.centerOf(VoxelMap::voxelIndex(block.index, linear)));
      if (!delta) continue;
      deltas[linear] = *delta;
      ++count;
    }
    return count;
  }
  // The same arithmetic as voxelLogOdds (centerOf, then the transform), so both give
  // bit-identical results: Andert's scheme is discontinuous at cell borders.
  const VoxelIndex first = VoxelMap::voxelIndex(block.index, 0);
  const CameraIntrinsics& camera = frame.camera;
  const float far_in_front = model_.farInFrontLogOdds();
  const double resolution = map.resolution();
  const BlockImageRuns runs(frame, map, first);
  for (int z = 0; z < VoxelBlock::kSide; ++z) {
    for (int y = 0; y < VoxelBlock::kSide; ++y) {
      const VoxelRun run = runs.of(y, z);
      for (int x = run.first; x <= run.last; ++x) {
        const Eigen::Vector3d point =
            frame.T_camera_map * voxelCenter(first + VoxelIndex(x, y, z), resolution);
        // The same tests as projectedLogOdds, then the block's bounds before the pyramid.
        double u = 0.0, v = 0.0, distance = 0.0;
        if (!projectIntoImage(camera, point, &u, &v, &distance)) continue;
        if (settled(VoxelBlock::linearIndex(x, y, z), distance)) continue;
        float delta = far_in_front;
        if (!block.far_in_front && !(distance < block.front)) {
          if (distance > block.reach) continue;
          delta = config_.method == DepthMethod::kAndert ? andertLogOdds(frame, u, v, distance)
                                                         : pyramidLogOdds(frame, u, v, distance);
        }
        // The pyramid's cells keep the nearest measurement of their pixels (Eq. 10-11), so an
        // occupied voxel beside a nearer surface in the image (a door beside its jamb, seen at a
        // grazing angle) reads it too, and its update stays short of a free one however many
        // rays pass it: then the pixels are asked. Not where the update itself is occupied
        // evidence (a surface seen again, four in five of the occupied voxels in view).
        const int linear = VoxelBlock::linearIndex(x, y, z);
        const bool ask_pixels = !(delta > 0.0f);  // NaN (no update) included
        if (clear_passed && states->occupied.test(linear) &&
            (delta <= passed_log_odds_ || (ask_pixels && seenThrough(frame, u, v, distance)))) {
          delta = passed_miss_log_odds_;
        }
        if (std::isnan(delta)) continue;
        deltas[linear] = delta;
        ++count;
      }
    }
  }
  return count;
}

}  // namespace occupancy_fusion
