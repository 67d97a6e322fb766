// Eq. 6, 10 and 11 of Pirker et al. 2011: the distance image M and its pyramid of layers M_i,
// each keeping per 2^i x 2^i block the measurement closest to the layer's distance t_i (or, for
// Andert's baseline, the nearest).
#pragma once

#include <cstddef>
#include <vector>

#include "occupancy_fusion/integrators/depth/depth_inverse_model.h"
#include "occupancy_fusion/sensors/depth_image.h"

namespace occupancy_fusion {

// Which measurement of a 2^i x 2^i block a pyramid layer keeps.
enum class PyramidSelection {
  kClosestToThreshold,  // Eq. 10: the one closest to t_i (Pirker)
  kMinimum,             // the nearest obstacle (Andert)
};

class DistanceBuckets;

// The distance image M (Eq. 6) and its layers M_i (Eq. 10-11), identical to scanning each
// 2^i x 2^i block of M in row order and keeping the first best measurement.
// Layer i has ceil(width / 2^i) x ceil(height / 2^i) cells; cell (U, V) covers the pixels
// U 2^i ... U 2^i + 2^i - 1 (and likewise in v). NaN marks a cell without valid measurement.
class DistancePyramid {
 public:
  // t0 = focal length x resolution: at that distance a voxel projects onto one pixel.
  // reach (optional, kClosestToThreshold only): how far behind a measurement voxels are
  // informed. Scanned layers finer than any informed voxel reads are then left invalid instead
  // of built, and the layers that are read get reachOfSquare's tables.
  DistancePyramid(const DepthImageView& depth, const CameraIntrinsics& camera, double t0,
                  int levels, double max_range, PyramidSelection selection,
                  const MeasurementReach* reach = nullptr);
  // Hands the layers' storage to the next pyramid built on this thread.
  ~DistancePyramid();
  DistancePyramid(const DistancePyramid&) = default;
  DistancePyramid& operator=(const DistancePyramid&) = default;
  DistancePyramid(DistancePyramid&&) = default;
  DistancePyramid& operator=(DistancePyramid&&) = default;

  // Layers needed for voxels down to min_range: until t_i <= min_range or one cell covers the
  // image, at most max_levels.
  static int levelCount(const CameraIntrinsics& camera, double t0, double min_range,
                        int max_levels);

  int levels() const { return static_cast<int>(layers_.size()); }
  double threshold(int level) const { return thresholds_[level]; }  // t_i = t0 / 2^i (Eq. 11)
  double scale(int level) const { return scales_[level]; }          // 2^-i, exact
  // 1 / (t_{i+1} - t_i), Eq. 17's denominator, for i < levels() - 1.
  double inverseGap(int level) const { return inverse_gaps_[level]; }
  int width(int level) const { return layers_[level].width; }
  int height(int level) const { return layers_[level].height; }
  float at(int level, int u, int v) const {
    const Layer& layer = layers_[level];
    return layer.cells[static_cast<std::size_t>(v) * layer.width + u];
  }
  const float* cells(int level) const { return layers_[level].cells.data(); }  // row-major
  // At least the reach (the constructor's) of the farthest valid cell among the layer's cells
  // (u, v), (u + 1, v), (u, v + 1) and (u + 1, v + 1) that lie inside it, for -1 <= u < width
  // and -1 <= v < height: the cells Eq. 15 can weigh for one voxel, so no cell informs a voxel
  // farther than this. -inf where none is valid; +inf where the layer has no table (no reach
  // given, Andert's layers, layers no informed voxel reads).
  float reachOfSquare(int level, int u, int v) const {
    const Layer& squares = squares_[level];
    if (squares.cells.empty()) return kNoBound;
    return squares.cells[static_cast<std::size_t>(v + 1) * squares.width + (u + 1)];
  }

 private:
  struct Layer {
    int width = 0;
    int height = 0;
    std::vector<float> cells;
  };
  void sizeLayer(int level);
  void buildMinimumLayers();  // Andert: 2 x 2 minima of the layer below
  // The first layer an informed voxel can read (see the constructor); 0 without a reach.
  int firstReadLevel(const MeasurementReach* reach) const;
  // Eq. 10: fine layers scanned, coarse ones from distance buckets.
  void buildClosestLayers(int first_read_level);
  // reachOfSquare's tables for the layers from first_level on.
  void buildSquareReaches(int first_level, const MeasurementReach& reach);
  void fillBuckets(int level, DistanceBuckets* buckets) const;
  void takeClosest(const DistanceBuckets& buckets, int level);
  // The first measurement of the cell, in scan order, of least |d - target|.
  float scanCell(int level, int cell_u, int cell_v, float target) const;
  // Layer `level` keeps, per cell, the first measurement of least score(measurement).
  template <class Score>
  static void fillLayer(const Layer& full, int level, Score score, Layer* layer);

  std::vector<double> thresholds_;  // t_i per layer, read for every voxel
  std::vector<double> scales_;      // 2^-i per layer, read for every voxel
  std::vector<double> inverse_gaps_;
  std::vector<Layer> layers_;   // layers_[0] is M itself
  std::vector<Layer> squares_;  // per layer: (width + 1) x (height + 1), or empty
  static constexpr float kNoBound = __builtin_huge_valf();
  float farthest_ = 0.0f;  // the farthest valid distance of M; 0: none valid
};

}  // namespace occupancy_fusion
