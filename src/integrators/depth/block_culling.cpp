// Eq. 13 per block: the blocks of the frustum that may hold an updated voxel, and the bounds
// that settle whole blocks or voxels without reading the pyramid.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "depth_detail.h"
#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"

namespace occupancy_fusion {

using depth_detail::isValidMeasurement;
using depth_detail::kParallelPixels;

std::vector<BlockIndex> PyramidDepthIntegrator::candidateBlocks(const DepthFrame& frame) const {
  std::vector<BlockIndex> blocks;
  for (const CandidateBlock& block : cullBlocks(frame)) blocks.push_back(block.index);
  return blocks;
}

namespace {

// Nearest and farthest valid distance and the valid count per pixel column, over the rows
// added (NaN, invalid, never compares, so it drops out).
struct ColumnExtremes {
  explicit ColumnExtremes(int width) : nearest(width), farthest(width), valid(width) {}
  void reset() {
    std::fill(nearest.begin(), nearest.end(), std::numeric_limits<float>::infinity());
    std::fill(farthest.begin(), farthest.end(), -std::numeric_limits<float>::infinity());
    std::fill(valid.begin(), valid.end(), 0);
  }
  void add(const float* row) {
    const int width = static_cast<int>(valid.size());
    for (int u = 0; u < width; ++u) {
      nearest[u] = row[u] < nearest[u] ? row[u] : nearest[u];
      farthest[u] = row[u] > farthest[u] ? row[u] : farthest[u];
      valid[u] += isValidMeasurement(row[u]);
    }
  }
  std::vector<float> nearest, farthest;
  std::vector<int> valid;
};

}  // namespace

namespace {

// Bounds of the pixels of some 8 x 8 tiles (see cullBlocks).
struct TileBounds {
  float reach = -1.0f;                                   // the farthest any of them informs
  float front = std::numeric_limits<float>::infinity();  // Eq. 7's constant ends here
  bool all_valid = true;
  void merge(const TileBounds& other) {
    reach = std::max(reach, other.reach);
    front = std::min(front, other.front);
    all_valid = all_valid && other.all_valid;
  }
};

// A rectangle of tiles' bounds in two reads per tile row instead of one per tile (a block's
// footprint at 0.08 m spans hundreds of tiles): per row, the bounds of every run of 2^k tiles
// (a sparse table); any run of n tiles is the union of two runs of 2^floor(log2 n), and
// max / min / and do not mind the overlap, so the result equals the tile by tile one.
class TileFootprints {
 public:
  TileFootprints(const std::vector<float>& reach, const std::vector<float>& front,
                 const std::vector<char>& all_valid, int tiles_u)
      : tiles_u_(tiles_u) {
    runs_.emplace_back(reach.size());
    for (std::size_t tile = 0; tile < reach.size(); ++tile) {
      runs_[0][tile] = {reach[tile], front[tile], all_valid[tile] != 0};
    }
    for (int length = 2; length <= tiles_u_; length *= 2) {
      const std::vector<TileBounds>& half = runs_.back();
      std::vector<TileBounds> runs(half.size());
      for (std::size_t row = 0; row < half.size(); row += tiles_u_) {
        for (int tu = 0; tu + length <= tiles_u_; ++tu) {
          runs[row + tu] = half[row + tu];
          runs[row + tu].merge(half[row + tu + length / 2]);
        }
      }
      runs_.push_back(std::move(runs));
    }
  }

  // Tiles tu0 ... tu1 of rows tv0 ... tv1 (nothing: the bounds of no pixel).
  TileBounds over(int tu0, int tu1, int tv0, int tv1) const {
    TileBounds bounds;
    if (tu0 > tu1) return bounds;
    int level = 0;
    while ((2 << level) <= tu1 - tu0 + 1) ++level;
    const std::vector<TileBounds>& runs = runs_[level];
    for (int tv = tv0; tv <= tv1; ++tv) {
      const std::size_t row = static_cast<std::size_t>(tv) * tiles_u_;
      bounds.merge(runs[row + tu0]);
      bounds.merge(runs[row + tu1 + 1 - (1 << level)]);
    }
    return bounds;
  }

 private:
  int tiles_u_;
  std::vector<std::vector<TileBounds>> runs_;  // runs_[k][row + tu]: tiles tu ... tu + 2^k - 1
};

}  // namespace

std::vector<PyramidDepthIntegrator::CandidateBlock> PyramidDepthIntegrator::cullBlocks(
    const DepthFrame& frame) const {
  const CameraIntrinsics& camera = frame.camera;
  const DistancePyramid& pyramid = frame.pyramid;
  // Per 8 x 8 tile of pixels: the farthest distance it can inform (measurement + unknown
  // margin), the nearest distance where Eq. 7 departs from its constant in front of the
  // Gaussian, and whether every pixel is valid.
  constexpr int kTile = 8;
  const int tiles_u = (camera.width + kTile - 1) / kTile;
  const int tiles_v = (camera.height + kTile - 1) / kTile;
  const std::size_t tile_count = static_cast<std::size_t>(tiles_u) * tiles_v;
  std::vector<float> reach(tile_count, -1.0f);
  std::vector<float> front(tile_count, std::numeric_limits<float>::infinity());
  std::vector<char> all_valid(tile_count, 1);
  // Slightly nearer than Eq. 7's support, so rounding cannot claim a voxel it would not give.
  constexpr double kFrontSafety = 1e-6;  // m
  // From each tile's nearest and farthest measurement: reach grows with the measurement, and
  // front = measured - supportSigmas() sigma(measured) is at least nearest - supportSigmas()
  // sigma(farthest) (exact for constant sigma). Branch-free min / max passes; NaN (invalid)
  // never compares, so it drops out.
  const float* distances = pyramid.cells(0);
  const bool parallel = static_cast<long>(camera.width) * camera.height >= kParallelPixels;
#pragma omp parallel if (parallel)
  {
    // Per pixel column over the rows of one row of tiles (elementwise, so it vectorises),
    // then per tile over its columns: the same extremes as a scan of each tile.
    ColumnExtremes columns(camera.width);
#pragma omp for schedule(static)
    for (int tv = 0; tv < tiles_v; ++tv) {
      const int v_end = std::min(camera.height, (tv + 1) * kTile);
      columns.reset();
      for (int v = tv * kTile; v < v_end; ++v) {
        columns.add(distances + static_cast<std::size_t>(v) * camera.width);
      }
      for (int tu = 0; tu < tiles_u; ++tu) {
        const int u_end = std::min(camera.width, (tu + 1) * kTile);
        float nearest = std::numeric_limits<float>::infinity();
        float farthest = -std::numeric_limits<float>::infinity();
        int valid = 0;
        for (int u = tu * kTile; u < u_end; ++u) {
          nearest = std::min(nearest, columns.nearest[u]);
          farthest = std::max(farthest, columns.farthest[u]);
          valid += columns.valid[u];
        }
        const std::size_t tile = static_cast<std::size_t>(tv) * tiles_u + tu;
        all_valid[tile] = valid == (v_end - tv * kTile) * (u_end - tu * kTile);
        if (valid == 0) continue;
        const double sigma_far = model_.sigmaAt(farthest);
        reach[tile] = static_cast<float>(farthest + config_.unknown_behind_sigmas * sigma_far);
        front[tile] = static_cast<float>(nearest - DepthInverseModel::supportSigmas() * sigma_far -
                                         kFrontSafety);
      }
    }
  }
  const TileFootprints footprints(reach, front, all_valid, tiles_u);
  const float max_reach = *std::max_element(reach.begin(), reach.end());
  if (max_reach <= config_.min_range) return {};

  // Axis-aligned box of the frustum truncated at z = max_reach (distance >= z-depth).
  Eigen::AlignedBox3d box;
  box.extend(frame.T_map_camera.translation());
  for (double u : {-0.5, camera.width - 0.5}) {
    for (double v : {-0.5, camera.height - 0.5}) {
      box.extend(frame.T_map_camera * (camera.pixelRay(u, v) * max_reach));
    }
  }
  const double block_size = VoxelBlock::kSide * frame.resolution;
  const Eigen::Vector3i first = (box.min() / block_size).array().floor().cast<int>();
  const Eigen::Vector3i last = (box.max() / block_size).array().floor().cast<int>();
  const double radius = 0.5 * std::sqrt(3.0) * block_size;
  const double t0 = pyramid.threshold(0);
  // A hundredth of a sigma short of Eq. 7's crossing of 0.5 (the table interpolates it to 2e-6
  // in log-odds).
  const double free_slab_metres =
      (DepthInverseModel::supportSigmas() - model_.freeBeyondSigmas() - 0.01) * config_.sigma;

  // nullopt: the block gets nothing.
  auto classify = [&](const BlockIndex& block) -> std::optional<CandidateBlock> {
    const Eigen::Vector3d center = (block.cast<double>().array() + 0.5) * block_size;
    const Eigen::Vector3d p = frame.T_camera_map * center;
    const double distance = p.norm();
    if (p.z() + radius <= 0.0 || distance + radius < config_.min_range) return std::nullopt;
    const double near = std::max(distance - radius, 1e-6);
    if (near > max_reach) return std::nullopt;
    // Conservative pixel box of the block's bounding sphere, widened by the support of the
    // coarsest pyramid cell its voxels may read (Eq. 15 reads two cells of 2^i pixels).
    double u_lo = -0.5, u_hi = camera.width - 0.5, v_lo = -0.5, v_hi = camera.height - 0.5;
    if (p.z() - radius > 1e-6) {
      const double z_near = p.z() - radius, z_far = p.z() + radius;
      u_lo = camera.fx * std::min((p.x() - radius) / z_near, (p.x() - radius) / z_far) + camera.cx;
      u_hi = camera.fx * std::max((p.x() + radius) / z_near, (p.x() + radius) / z_far) + camera.cx;
      v_lo = camera.fy * std::min((p.y() - radius) / z_near, (p.y() - radius) / z_far) + camera.cy;
      v_hi = camera.fy * std::max((p.y() + radius) / z_near, (p.y() + radius) / z_far) + camera.cy;
      if (u_hi < -0.5 || u_lo > camera.width - 0.5 || v_hi < -0.5 || v_lo > camera.height - 0.5) {
        return std::nullopt;
      }
      const int coarsest =
          std::clamp(static_cast<int>(std::floor(std::log2(std::max(t0 / near, 1.0)))) + 1, 0,
                     pyramid.levels() - 1);
      const double margin = 2.0 * (1 << coarsest) + 1.0;
      u_lo -= margin, u_hi += margin, v_lo -= margin, v_hi += margin;
    }
    const int tu0 = std::max(0, static_cast<int>(std::floor(u_lo + 0.5)) / kTile);
    const int tu1 = std::min(tiles_u - 1, static_cast<int>(std::max(0.0, u_hi + 0.5)) / kTile);
    const int tv0 = std::max(0, static_cast<int>(std::floor(v_lo + 0.5)) / kTile);
    const int tv1 = std::min(tiles_v - 1, static_cast<int>(std::max(0.0, v_hi + 0.5)) / kTile);
    const TileBounds footprint = footprints.over(tu0, tu1, tv0, tv1);
    const float footprint_reach = footprint.reach;
    const float footprint_front = footprint.front;
    const bool footprint_valid = footprint.all_valid;
    if (footprint_reach < near) return std::nullopt;
    CandidateBlock candidate;
    candidate.index = block;
    candidate.far_in_front = footprint_valid && distance + radius < footprint_front;
    // One float step outwards: the tiles hold float-rounded bounds of double ones, at any range.
    candidate.reach = std::nextafter(footprint_reach, std::numeric_limits<float>::infinity());
    // Per voxel only where the far-in-front branch of Eq. 15-17 gives the constant exactly.
    if (footprint_valid && !table_.empty()) {
      candidate.front = std::nextafter(footprint_front, -std::numeric_limits<float>::infinity());
    }
    // Eq. 7 stays below 0.5 from freeBeyondSigmas() in front of a measurement: each tile's
    // nearest - that sigma(farthest) is at least its front + (support - free) sigma, sigma at its
    // smallest (exact for constant sigma). Invalid pixels give no update, so the valid ones'
    // bound holds whatever else the footprint holds (not for Eq. 8-9, which reads pixel rays).
    if (config_.method != DepthMethod::kIdeal) {
      candidate.free_front = std::nextafter(static_cast<float>(footprint_front + free_slab_metres),
                                            -std::numeric_limits<float>::infinity());
    }
    candidate.near = static_cast<float>(near);
    return candidate;
  };

  std::vector<CandidateBlock> blocks;
#pragma omp parallel
  {
    std::vector<CandidateBlock> mine;
#pragma omp for collapse(2) schedule(dynamic, 4) nowait
    for (int z = first.z(); z <= last.z(); ++z) {
      for (int y = first.y(); y <= last.y(); ++y) {
        for (int x = first.x(); x <= last.x(); ++x) {
          const BlockIndex block(x, y, z);
          if (const std::optional<CandidateBlock> candidate = classify(block)) {
            mine.push_back(*candidate);
          }
        }
      }
    }
#pragma omp critical
    blocks.insert(blocks.end(), mine.begin(), mine.end());
  }
  return blocks;
}

}  // namespace occupancy_fusion
