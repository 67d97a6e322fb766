// Stereo occupancy mapping after Schauwecker & Zell 2014, "Robust and Efficient
// Volumetric Occupancy Mapping with an Application to Stereo Vision" (Sec.
// III): OctoMap-style ray casting in which each voxel's update is weighted by
// the probability that the voxel is visible from the sensor (Eq. 1-3, estimated
// from the map itself), integrated with the Bayesian network of Fig. 2b (Eq.
// 4-6), and continued past the measured point with the stereo depth error (Eq.
// 7-8). One update per voxel per frame, found through a previous-ray cache in
// front of a hash table (Sec. III-D). The OctoMap update on the same rays is
// the baseline mode.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "occupancy_fusion/integrators/stereo/measured_surface.h"
#include "occupancy_fusion/integrators/stereo/visibility_stereo_config.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/sensors/disparity_image.h"

namespace occupancy_fusion {

struct RayTarget;  // a point's end voxel (internal)
struct FrameRays;  // a disparity frame's rays (internal)

// Phi, the standard normal CDF, tabulated with linear interpolation (Sec. III-D
// pre-computes P(I_v) = Phi((z_q - z) / sigma_z) over depth and distance; with
// sigma_z folded into the argument the same table needs one dimension). Outside
// [-kRange, kRange] it returns 0 or 1.
class NormalCdfTable {
 public:
  static constexpr double kRange = 6.0;
  static constexpr int kSize = 4097;
  NormalCdfTable();
  double operator()(double x) const {
    if (!(x > -kRange)) return 0.0;  // also NaN
    if (x >= kRange) return 1.0;
    const double position = (x + kRange) * kScale;
    const int i = static_cast<int>(position);
    const double fraction = position - i;
    return values_[i] + fraction * (values_[i + 1] - values_[i]);
  }

 private:
  static constexpr double kScale = (kSize - 1) / (2.0 * kRange);
  std::vector<double> values_;
};

// Eq. 3 with the q_max clamp: visibility of a voxel whose predecessor on the
// ray has visibility previous and whose local occlusion (Eq. 1) is p_occluded.
double nextVisibility(double previous, double p_occluded, const VisibilityStereoConfig& config);
// Eq. 4-6: P(O_v | M) for a hit (M = H) or a miss (M = not H) at visibility
// P(V_v).
double occupancyAfterMeasurement(double p_occupied, bool hit, double visibility,
                                 const VisibilityStereoConfig& config);
// Eq. 8: P(I_v) P(O_v | H) + (1 - P(I_v)) P(O_v | not H).
double occupancyAfterInterpolatedMeasurement(double p_occupied, double p_inside, double visibility,
                                             const VisibilityStereoConfig& config);

// The reduced update of one voxel for one frame.
struct StereoVoxelUpdate {
  VoxelIndex index;
  float p_inside = 0.0f;    // max over the frame's rays of P(I_v) (kOctomap: 1 hit, 0 miss)
  float visibility = 0.0f;  // max over the frame's rays of P(V_v) (kOctomap: 1)
  float prior = -1.0f;      // P(O) of Eq. 4-6 if the voxel is unknown; negative: unknown_occupancy
  // clear_passed: a ray of the frame passed the voxel clearly in front of its measured point
  bool passed = false;
};

struct StereoIntegrationStats {
  std::size_t points = 0;          // points given (after the disparity conversion)
  std::size_t skipped_points = 0;  // non-finite, or outside the key range of the map
  // integrate(disparity image) only: valid disparities dropped before ray casting because their
  // sigma_z / z exceeds disparity.max_depth_sigma_ratio (not counted in points)
  std::size_t dropped_uncertain = 0;
  std::size_t rays = 0;            // rays cast (bundle_rays: one per end voxel)
  std::size_t merged_points = 0;   // bundle_rays: usable points merged into another point's ray
  std::size_t rays_invisible = 0;  // rays stopped early because P(V) fell below q_min
  std::size_t voxel_visits = 0;    // voxels walked over all rays
  std::size_t cache_hits = 0;      // of those, found through the previous-ray cache
  std::size_t updated_voxels = 0;  // distinct voxels updated (one update each)
  double seconds = 0.0;            // wall time of the call
  // The call's wall time by stage: the pixels to ray ends (with the measured surface, built
  // beside them; integrate(disparity image) only), the ends grouped by voxel (bundle_rays), the
  // walks of the rays, and writing the reduced updates into the map.
  double conversion_seconds = 0.0;
  double bundling_seconds = 0.0;
  double walk_seconds = 0.0;
  double write_seconds = 0.0;

  double cacheHitRate() const {
    return voxel_visits == 0 ? 0.0 : static_cast<double>(cache_hits) / voxel_visits;
  }
  double milliseconds() const { return 1e3 * seconds; }
};

// Thread safety: const member functions may run concurrently. The map is read
// (copies of the blocks the rays pass, under its shared lock) while rays are
// cast on omp_get_max_threads() threads, then written in one
// VoxelMap::updateBlocks call.
class VisibilityStereoIntegrator {
 public:
  explicit VisibilityStereoIntegrator(const VisibilityStereoConfig& config = {});  // validates
  ~VisibilityStereoIntegrator();

  const VisibilityStereoConfig& config() const { return config_; }

  // A disparity image of the left camera whose optical frame has pose
  // T_map_camera.
  StereoIntegrationStats integrate(const DisparityImageView& disparity, const StereoCamera& camera,
                                   const Eigen::Isometry3d& T_map_camera, VoxelMap* map) const;
  // Points in the map frame seen from sensor_origin, each with the standard
  // deviation of its distance from the origin along its ray (m; sigma_z scaled
  // by range / z for a camera point).
  // `surface`: the frame's measured surface, read by unknown_neighbours: measured (without it,
  // that policy reads unknown neighbours as the prior).
  StereoIntegrationStats integrate(const std::vector<Eigen::Vector3f>& points_in_map,
                                   const std::vector<float>& range_sigmas,
                                   const Eigen::Vector3d& sensor_origin, VoxelMap* map,
                                   const MeasuredSurface* surface = nullptr) const;

  // The ray-casting half of integrate(): the frame's reduced updates, reading
  // the map but not writing it. Fills every stats field except seconds.
  StereoIntegrationStats computeUpdates(const std::vector<Eigen::Vector3f>& points_in_map,
                                        const std::vector<float>& range_sigmas,
                                        const Eigen::Vector3d& sensor_origin, const VoxelMap& map,
                                        std::vector<StereoVoxelUpdate>* updates,
                                        const MeasuredSurface* surface = nullptr) const;
  // The writing half: one VoxelMap::updateBlocks call.
  void apply(const std::vector<StereoVoxelUpdate>& updates, VoxelMap* map) const;

  // Points of a disparity image in the map frame with their range sigmas; optionally the pixels
  // read and the valid disparities dropped for sigma_z / z > disparity.max_depth_sigma_ratio.
  void disparityToMapPoints(const DisparityImageView& disparity, const StereoCamera& camera,
                            const Eigen::Isometry3d& T_map_camera,
                            std::vector<Eigen::Vector3f>* points_in_map,
                            std::vector<float>* range_sigmas, std::size_t* pixels_read,
                            std::size_t* dropped_uncertain = nullptr) const;
  // The frame's measured surface when unknown_neighbours is kMeasured, else an empty one; its grid
  // follows voxel_size_m (MeasuredSurfaceConfig::grid_footprint_fraction), 0: the finest grid.
  MeasuredSurface measuredSurface(const DisparityImageView& disparity, const StereoCamera& camera,
                                  const Eigen::Isometry3d& T_map_camera,
                                  double voxel_size_m = 0.0) const;

 private:
  // computeUpdates() over slots of points with their end voxels given (one per slot; a slot
  // without a point is passed over), or computed here where `ends` is null. ray_columns: the
  // slots per image row where the slots are an image's pixels (the rays are then walked tile by
  // tile, orderByImageTiles), 0 where they are not. With write_to (the
  // map read, after the rays are cast) the updates are written to it straight from the threads'
  // tables, block by block, and `updates` stays empty: integrate() without its timing.
  StereoIntegrationStats computeUpdates(const std::vector<Eigen::Vector3f>& points_in_map,
                                        const std::vector<float>& range_sigmas,
                                        const std::vector<RayTarget>* ends, int ray_columns,
                                        std::size_t point_count,
                                        const Eigen::Vector3d& sensor_origin, const VoxelMap& map,
                                        std::vector<StereoVoxelUpdate>* updates,
                                        const MeasuredSurface* surface,
                                        VoxelMap* write_to = nullptr) const;
  // That computeUpdates(), writing the map.
  StereoIntegrationStats integrateRays(const std::vector<Eigen::Vector3f>& points_in_map,
                                       const std::vector<float>& range_sigmas,
                                       const std::vector<RayTarget>* ends, int ray_columns,
                                       std::size_t point_count,
                                       const Eigen::Vector3d& sensor_origin, VoxelMap* map,
                                       const MeasuredSurface* surface) const;

  VisibilityStereoConfig config_;
  NormalCdfTable phi_;
  // The slots of a disparity frame's rays, kept for the next frame: allocating and zeroing a
  // full image's slots (32 bytes a pixel) anew cost as much as filling them. A call made while
  // another one holds them uses slots of its own.
  mutable std::mutex frame_rays_mutex_;
  std::unique_ptr<FrameRays> frame_rays_;
};

}  // namespace occupancy_fusion
