// Accuracy of an occupancy map against analytic ground truth, as the depth paper's Sec. 5.1
// experiments are scored (`benchmark depth-accuracy`): how close the p = 0.5 iso-surface lies
// to the true surface points that the views observed, and how much of the observed free space
// is labelled free.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <functional>
#include <vector>

#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/sensors/camera_intrinsics.h"
#include "occupancy_fusion/sensors/depth_image.h"

namespace occupancy_fusion {

// Distance from `point` to the nearest place where the p = 0.5 iso-surface crosses the segment
// between two axis-neighbouring voxel centres of opposite label (log-odds > 0 against <= 0,
// unknown read as 0, i.e. p = 0.5), the crossing placed by linear interpolation of the
// log-odds between the two centres. Centres within two voxels (per axis) of the point's voxel
// are searched, so every crossing within one voxel of the point is found. Infinity when none.
double distanceToIsoSurface(const VoxelMap& map, const Eigen::Vector3d& point);

// True when one of the 3 x 3 x 3 voxels around the point's voxel is occupied (log-odds > 0).
bool occupiedWithinOneVoxel(const VoxelMap& map, const Eigen::Vector3d& point);

// A depth image (z-depth, NaN or 0: no measurement) and the pose of its optical frame.
struct PosedDepthView {
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  DepthImageView depth;
};

// True when the view measured the surface at `point`: the point projects into the image and
// the depth of the pixel it falls in differs from the point's own by less than `tolerance`.
bool observesSurfacePoint(const PosedDepthView& view, const CameraIntrinsics& camera,
                          const Eigen::Vector3d& point, double tolerance);

struct SurfaceScores {
  std::size_t points = 0;         // surface points scored
  std::size_t near_iso = 0;       // distanceToIsoSurface <= one voxel
  std::size_t near_occupied = 0;  // occupiedWithinOneVoxel
};

// Scores the given (already observed) true surface points; parallel over the points.
SurfaceScores scoreSurfacePoints(const VoxelMap& map, const std::vector<Eigen::Vector3d>& points);

struct FreeSpaceScores {
  std::size_t voxels = 0;         // known voxels that are free in the ground truth
  std::size_t labelled_free = 0;  // ... and classified free by the map (p <= threshold)
};

// Over the known (observed) voxels whose centre `is_ground_truth_free` accepts.
FreeSpaceScores scoreFreeSpace(
    const VoxelMap& map, const std::function<bool(const Eigen::Vector3d&)>& is_ground_truth_free);

}  // namespace occupancy_fusion
