// The rays of a stereo frame: which points can be walked to, and bundle_rays' grouping of the
// points by end voxel (VisibilityStereoConfig::bundle_rays). Internal to the stereo integrator.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace occupancy_fusion {

// A point the ray caster can walk to from origin: finite, within the frame's key range, and with
// a finite, non-negative range sigma; needs_direction: also apart from the origin.
bool isUsableRay(const Eigen::Vector3d& point, float sigma, const Eigen::Vector3d& origin,
                 double resolution, bool needs_direction);

// bundle_rays: per end voxel the nearest and the farthest usable point (see
// VisibilityStereoConfig::bundle_rays), in the order of each voxel's first point, so that
// neighbouring pixels stay neighbouring rays for the previous-ray cache; one ray where they are the
// same point, and always one for OctoMap's update, whose ray ends at the voxel's centre.
// Neighbouring pixels mostly share their end voxel, so the last voxel is checked
// before the hash table.
// visibility_mode: the farthest point of each voxel too, and every point apart from the origin.
// skipped: incremented per unusable point.
std::vector<std::uint32_t> bundleRaysByEndVoxel(const std::vector<Eigen::Vector3f>& points,
                                                const std::vector<float>& sigmas,
                                                const Eigen::Vector3d& origin, double resolution,
                                                bool visibility_mode, std::size_t* skipped);

}  // namespace occupancy_fusion
