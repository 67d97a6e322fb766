// Depth-image occupancy mapping after Pirker et al. 2011, "Fast and Accurate Environment Modeling
// using Three-Dimensional Occupancy Grids": an inverse sensor model per voxel of the camera
// frustum, read from a pyramid of distance images and interpolated between pyramid layers.
// Also the paper's two references: the ideal model (Eq. 8-9) and Andert's min-depth pyramid.
// Its stages, one file each in src/integrators/depth/: the inverse sensor model (Eq. 7,
// depth_inverse_model.h), the distance pyramid (Eq. 6, 10-11, distance_pyramid.h), the culling of
// the frustum's blocks (Eq. 13, block_culling.cpp) and the per-voxel update (Eq. 12-17 and 8-9,
// voxel_update.cpp), driven by integrate() (pyramid_depth_integrator.cpp).
#pragma once

#include <Eigen/Geometry>
#include <bitset>
#include <cstddef>
#include <limits>
#include <optional>
#include <vector>

#include "occupancy_fusion/integrators/depth/depth_inverse_model.h"
#include "occupancy_fusion/integrators/depth/distance_pyramid.h"
#include "occupancy_fusion/integrators/depth/pyramid_depth_config.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/sensors/depth_image.h"

namespace occupancy_fusion {

// One depth image prepared for per-voxel queries at one map resolution.
struct DepthFrame {
  CameraIntrinsics camera;
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_camera_map = Eigen::Isometry3d::Identity();
  double resolution = 0.0;
  DistancePyramid pyramid;
};

struct DepthIntegrationStats {
  std::size_t voxels_updated = 0;
  // Voxels left alone because their update would change nothing: clamped free, and more than
  // freeBeyondSigmas() in front of every measurement they read (not in voxels_updated).
  std::size_t voxels_unchanged = 0;
  std::size_t blocks_updated = 0;    // blocks holding at least one updated voxel
  std::size_t candidate_blocks = 0;  // blocks examined (conservative frustum culling)
  double milliseconds = 0.0;
};

class PyramidDepthIntegrator {
 public:
  explicit PyramidDepthIntegrator(const PyramidDepthConfig& config);  // validates config

  const PyramidDepthConfig& config() const { return config_; }
  const DepthInverseModel& model() const { return model_; }

  // Eq. 6 and the pyramid the configured method reads (one layer for kIdeal).
  DepthFrame prepare(const DepthImageView& depth, const CameraIntrinsics& camera,
                     const Eigen::Isometry3d& T_map_camera, double resolution) const;

  // The log-odds increment l(z) - l0 (Eq. 3, l0 = 0) the configured method gives the voxel of
  // edge frame.resolution, axis-aligned in the map frame, centred at voxel_center (map frame);
  // nullopt leaves the voxel unchanged. Used by integrate() and by accuracy evaluation.
  std::optional<float> voxelLogOdds(const DepthFrame& frame,
                                    const Eigen::Vector3d& voxel_center) const;

  // Blocks that may hold a voxel the frame updates (a conservative superset).
  std::vector<BlockIndex> candidateBlocks(const DepthFrame& frame) const;

  // Integrates one image. depth: z-depth in metres (0 or NaN: invalid); T_map_camera: pose of
  // the optical frame in the map frame. Voxels are computed in parallel per block, outside the
  // map's lock, then written with VoxelMap::updateBlocks; only blocks with updates are
  // allocated.
  DepthIntegrationStats integrate(const DepthImageView& depth, const CameraIntrinsics& camera,
                                  const Eigen::Isometry3d& T_map_camera, VoxelMap* map) const;

 private:
  // The cells of one layer that Eq. 15 weighs for a voxel, gathered before any Eq. 7
  // evaluation: a voxel none of whose cells informs it (behind every surface it sees) is
  // rejected after a few comparisons. Invalid or absent cells have weight 0.
  struct LayerCells {
    double weights[4] = {};
    float measured[4] = {};
    double weight_sum = 0.0;
    bool informs = false;  // at least one valid cell informs the voxel
    bool complete = true;  // all four cells valid
    float nearest = std::numeric_limits<float>::infinity();    // of the valid cells
    float farthest = -std::numeric_limits<float>::infinity();  // of the valid cells
    bool valid() const { return weight_sum > 0.0; }
  };
  // A pixel's place in one layer (Eq. 14): the first of the four cells Eq. 15 weighs and the
  // fractions <u>, <v> of Eq. 16. Computed once per voxel and layer, for the reach test and the
  // gather.
  struct LayerPosition {
    int level = 0;
    int u0 = 0, v0 = 0;
    double fu = 0.0, fv = 0.0;
  };
  static LayerPosition layerPosition(const DepthFrame& frame, int level, double u, double v);
  // The per-voxel functions return NaN for "no update" (no std::optional in the voxel loop).
  LayerCells gatherCells(const DepthFrame& frame, const LayerPosition& position,
                         double distance) const;  // Eq. 15
  // False where no cell of the layer that Eq. 15 can weigh for the voxel informs it: the
  // farthest of the four cells around its position, read from one table before the gather.
  static bool layerMayInform(const DepthFrame& frame, const LayerPosition& position,
                             double distance);
  float bilinearLogOdds(const LayerCells& cells, double distance) const;  // Eq. 16
  float pyramidLogOdds(const DepthFrame& frame, double u, double v,
                       double distance) const;  // Eq. 12, 17
  float andertLogOdds(const DepthFrame& frame, double u, double v, double distance) const;
  std::optional<float> idealLogOdds(const DepthFrame& frame, const Eigen::Vector3d& voxel_center,
                                    double distance) const;  // Eq. 8-9
  // Eq. 13 for a point in the camera frame: false unless it lies at least min_range from the
  // camera centre, in front of it, and projects inside the image.
  bool projectIntoImage(const CameraIntrinsics& camera, const Eigen::Vector3d& point, double* u,
                        double* v, double* distance) const;

  // A candidate block; far_in_front: every pyramid cell any of its voxels can read is valid
  // and more than supportSigmas() beyond the voxel, so each voxel inside the image gets Eq. 7's
  // constant logit(0.3) without reading the pyramid. The same bounds per voxel, from the
  // pixels of the block's footprint: a voxel farther than `reach` is informed by no cell it
  // can read (no update); one nearer than `front` lies more than supportSigmas() in front of
  // every cell it can read, all valid (-infinity where that does not give Eq. 7's constant
  // exactly). Together they settle voxels without Eq. 15's gathers (on 7-Scenes 14 % of those
  // projecting into the image at 0.02 m, 35 % at 0.08 m).
  //
  // free_front: a voxel nearer than it lies more than freeBeyondSigmas() in front of every
  // valid cell it can read, so its update is negative (or none): if the map holds it clamped
  // free, the update is a no-op and is skipped without projecting it. near: the block's nearest
  // distance from the camera centre.
  struct CandidateBlock {
    BlockIndex index;
    bool far_in_front = false;
    float front = -std::numeric_limits<float>::infinity();       // m
    float reach = std::numeric_limits<float>::infinity();        // m
    float free_front = -std::numeric_limits<float>::infinity();  // m
    float near = 0.0f;                                           // m
  };
  std::vector<CandidateBlock> cullBlocks(const DepthFrame& frame) const;
  // Log-odds of one pyramid cell's measurement for a voxel at `distance` (Eq. 7, tabulated
  // where sigma is constant).
  float cellLogOdds(double distance, float measured) const {
    return table_.empty() ? model_.logOdds(distance, measured)
                          : table_.at((distance - measured) * inverse_sigma_);
  }
  // True when every valid cell read (the nearest of them at `nearest`) lies in front of the
  // voxel beyond the table's support, so Eq. 15-17 give Eq. 7's constant logit(0.3): then the
  // per-cell evaluation is skipped (about 40 % of the updates at 0.02 m on 7-Scenes).
  bool farInFront(double distance, float nearest) const {
    return !table_.empty() && (distance - nearest) * inverse_sigma_ <= -table_.limit();
  }
  // voxelLogOdds for a voxel centre already in the camera frame (pyramid and Andert); NaN: no
  // update.
  float projectedLogOdds(const DepthFrame& frame, const Eigen::Vector3d& point) const;
  // clear_passed beside a nearer surface: true when a ray through the voxel (the centre pixel
  // u, v, or one of a 3 x 3 grid within half a voxel side of it) ends passed_sigmas beyond it and
  // no ray of its footprint (within half a voxel diagonal) ends within half a voxel diagonal and
  // passed_sigmas of it.
  bool seenThrough(const DepthFrame& frame, double u, double v, double distance) const;
  // Writes all kVolume increments of one block (NaN: no update); returns how many are not NaN.
  // With the map's voxel states (optional): voxels at its lower clamping bound and nearer than
  // block.free_front get NaN and are counted in *unchanged instead (skip_settled), and with
  // clear_passed an occupied voxel's update at most passed_log_odds_, or one seenThrough, becomes
  // the passed miss.
  int blockLogOdds(const DepthFrame& frame, const CandidateBlock& block, const VoxelMap& map,
                   float* deltas, const VoxelMap::VoxelStates* states = nullptr,
                   bool skip_settled = false, int* unchanged = nullptr) const;

  PyramidDepthConfig config_;
  DepthInverseModel model_;
  OffsetLogOddsTable table_;
  double inverse_sigma_ = 0.0;
  float passed_miss_log_odds_ = 0.0f;  // clear_passed
  // Eq. 7 passed_sigmas in front of a measurement, sigma at its smallest: updates at most this
  // count as the frame seeing through the voxel.
  float passed_log_odds_ = 0.0f;
};

}  // namespace occupancy_fusion
