// The stereo artifacts set-up of Schauwecker & Zell's Sec. IV-A on the simulator's corridor,
// shared by the disparity unit test and `benchmark disparity-artifacts`: a 160 x 120 stereo
// camera (f = 131.25 px, b = 0.12 m) walks down the corridor at 1.2 m height, 3 cm per frame
// (the paper's rate: 774 m in 26,000 frames), and sees disparity with white noise and patches of
// wrong disparity that persist over frames (as a real matcher makes). Map quality against the
// scene's ground truth: false-occupied voxels and coverage of the surface the trajectory sees.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

#include "occupancy_fusion/integrators/stereo/visibility_stereo_integrator.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/sim/scene.h"
#include "occupancy_fusion/sim/stereo_camera.h"

namespace occupancy_fusion {

struct StereoCorridorSetup {
  int frames = 80;
  double step_per_frame = 0.03;  // m
  double start_x = 0.5;          // m, first camera position along the corridor
  double height = 1.2;           // m, camera height
  double baseline = 0.12;        // m
  double max_range = 8.0;        // m, rendered depth limit

  sim::PinholeCamera camera() const;  // 160 x 120, f = 131.25 px
  StereoCamera stereo() const;
  // White noise 0.3 px; 30 % of 12 px cells shifted by 1.5 px, kept for 10 frames; seed 7.
  sim::DisparityNoise noise() const;
  // The left optical frame's pose per frame.
  std::vector<Eigen::Isometry3d> poses() const;
};

// One frame's points in the map frame, as every mapper of a comparison receives them.
struct StereoFrame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3f> points;
  std::vector<float> sigmas;  // range sigma per point (Eq. 7 along the ray)
};

// The corridor's disparity images, rendered with setup.noise(), converted to points by
// `converter` (its disparity settings: sigma_d, sub-sampling, the sigma_z / z filter).
std::vector<StereoFrame> renderStereoCorridor(const sim::Scene& scene,
                                              const StereoCorridorSetup& setup,
                                              const VisibilityStereoIntegrator& converter);

// A ground-truth surface sample that some pose sees directly (in its image, within range, not
// occluded), with the smallest distance from which one of the checked poses sees it.
struct SeenSurfaceSample {
  Eigen::Vector3d point;
  double nearest_view = 0.0;  // m
};
// Samples spaced `spacing` apart; poses are checked every 4th (12 cm apart at 3 cm per frame).
std::vector<SeenSurfaceSample> seenSurface(const sim::Scene& scene,
                                           const StereoCorridorSetup& setup, double spacing);

// Occupied voxels of a finished map on the shared grid (index = floor(p / resolution), which
// liboctomap's keys follow too).
struct OccupiedVoxelSet {
  std::vector<VoxelIndex> voxels;
  SpatialKeySet keys;
  void add(const VoxelIndex& index);
  bool contains(const VoxelIndex& index) const;
};
OccupiedVoxelSet occupiedVoxelsOf(const VoxelMap& map);

// Coverage of the seen surface in bins of nearest_view: [0, 2), [2, 4), [4, 6), [6, 8] m.
constexpr int kCoverageDistanceBins = 4;
constexpr double kCoverageBinWidth = 2.0;  // m

struct StereoMapQuality {
  std::size_t occupied = 0;
  // Occupied voxels whose centre lies in ground-truth free space more than one voxel diagonal
  // from any surface.
  std::size_t false_occupied = 0;
  // Fraction of the seen surface samples with an occupied voxel within one voxel.
  double coverage = 0.0;
  double coverage_by_distance[kCoverageDistanceBins] = {};  // -1 where a bin holds no sample
  std::size_t samples_by_distance[kCoverageDistanceBins] = {};
  std::vector<bool> is_false;  // per occupied voxel (order of OccupiedVoxelSet::voxels)
};
StereoMapQuality evaluateStereoMap(const sim::Scene& scene, const OccupiedVoxelSet& map,
                                   double resolution,
                                   const std::vector<SeenSurfaceSample>& surface);

// Maps the frames with one integrator configuration into a fresh map of `resolution`.
struct StereoCorridorRun {
  OccupiedVoxelSet occupied;
  double seconds = 0.0;  // wall time of the integrate() calls
  std::size_t voxel_visits = 0;
  std::size_t cache_hits = 0;
};
StereoCorridorRun mapStereoCorridor(const VisibilityStereoConfig& config,
                                    const std::vector<StereoFrame>& frames, double resolution);

}  // namespace occupancy_fusion
