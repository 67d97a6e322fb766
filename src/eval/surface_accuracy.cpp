#include "occupancy_fusion/eval/surface_accuracy.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace occupancy_fusion {

double distanceToIsoSurface(const VoxelMap& map, const Eigen::Vector3d& point) {
  const VoxelIndex center = map.indexOf(point);
  const double resolution = map.resolution();
  // A crossing lies on a segment between neighbouring centres; one within a voxel of the point
  // has both centres within two voxels of the point's voxel along every axis.
  constexpr int kReach = 2;
  double nearest = std::numeric_limits<double>::infinity();
  for (int dz = -kReach; dz <= kReach; ++dz) {
    for (int dy = -kReach; dy <= kReach; ++dy) {
      for (int dx = -kReach; dx <= kReach; ++dx) {
        const VoxelIndex a = center + VoxelIndex(dx, dy, dz);
        const float la = map.logOdds(a).value_or(0.0f);
        for (int axis = 0; axis < 3; ++axis) {
          const VoxelIndex b = a + VoxelIndex::Unit(axis);
          const float lb = map.logOdds(b).value_or(0.0f);
          if ((la > 0.0f) == (lb > 0.0f)) continue;
          // Opposite labels, so la - lb != 0; the zero of the linear interpolation.
          const double fraction = static_cast<double>(la) / (static_cast<double>(la) - lb);
          const Eigen::Vector3d crossing =
              map.centerOf(a) + fraction * resolution * Eigen::Vector3d::Unit(axis);
          nearest = std::min(nearest, (crossing - point).norm());
        }
      }
    }
  }
  return nearest;
}

bool occupiedWithinOneVoxel(const VoxelMap& map, const Eigen::Vector3d& point) {
  const VoxelIndex center = map.indexOf(point);
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const std::optional<float> value = map.logOdds(center + VoxelIndex(dx, dy, dz));
        if (value && *value > 0.0f) return true;
      }
    }
  }
  return false;
}

bool observesSurfacePoint(const PosedDepthView& view, const CameraIntrinsics& camera,
                          const Eigen::Vector3d& point, double tolerance) {
  const Eigen::Vector3d p = view.T_world_camera.inverse() * point;
  if (p.z() <= 0.0) return false;
  const Eigen::Vector2d uv = camera.project(p);
  // Pixel centres at integer coordinates: the pixel a point falls in is the rounded one.
  const long u = std::lround(uv.x());
  const long v = std::lround(uv.y());
  if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) return false;
  const float depth = view.depth.at(static_cast<int>(u), static_cast<int>(v));
  return std::abs(static_cast<double>(depth) - p.z()) < tolerance;  // false for NaN
}

SurfaceScores scoreSurfacePoints(const VoxelMap& map, const std::vector<Eigen::Vector3d>& points) {
  const double resolution = map.resolution();
  std::size_t near_iso = 0, near_occupied = 0;
  const long count = static_cast<long>(points.size());
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : near_iso, near_occupied)
  for (long i = 0; i < count; ++i) {
    near_iso += distanceToIsoSurface(map, points[i]) <= resolution;
    near_occupied += occupiedWithinOneVoxel(map, points[i]);
  }
  return {points.size(), near_iso, near_occupied};
}

FreeSpaceScores scoreFreeSpace(
    const VoxelMap& map, const std::function<bool(const Eigen::Vector3d&)>& is_ground_truth_free) {
  FreeSpaceScores scores;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    if (!is_ground_truth_free(map.centerOf(index))) return;
    ++scores.voxels;
    scores.labelled_free += map.classify(log_odds) == Occupancy::kFree;
  });
  return scores;
}

}  // namespace occupancy_fusion
