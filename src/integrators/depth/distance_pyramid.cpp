// Eq. 6, 10, 11: the distance image and its pyramid of layers.
#include "occupancy_fusion/integrators/depth/distance_pyramid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "depth_detail.h"

namespace occupancy_fusion {

using depth_detail::kInfinity;
using depth_detail::kNaN;
using depth_detail::kParallelPixels;

namespace {

// Layers 1 .. kScannedLevels - 1 (cells of 2 x 2 and 4 x 4 pixels) are scanned from M directly;
// the coarser ones are merged level by level from per-cell distance buckets (see
// DistanceBuckets), which costs one pass over M for all of them.
constexpr int kScannedLevels = 3;

}  // namespace

// The two largest and two smallest distinct distances of a cell that fall into one bucket.
struct BucketExtremes {
  float max1 = -kInfinity, max2 = -kInfinity;
  float min1 = kInfinity, min2 = kInfinity;

  void addMax(float x) {
    if (x > max1) {
      max2 = max1;
      max1 = x;
    } else if (x < max1 && x > max2) {
      max2 = x;
    }
  }
  void addMin(float x) {
    if (x < min1) {
      min2 = min1;
      min1 = x;
    } else if (x > min1 && x < min2) {
      min2 = x;
    }
  }
  void add(float x) {
    addMax(x);
    addMin(x);
  }
  // The union's two largest and two smallest distinct values, without a branch (the coarse
  // layers merge thousands of cells per frame, in no predictable pattern): of each side's pair
  // (max1 > max2, or max2 = -inf) the largest value below the union's maximum m is max1 if that
  // is below m, else max2; likewise for the minima.
  void merge(const BucketExtremes& other) {
    const float top = std::max(max1, other.max1);
    const float ours_below = max1 < top ? max1 : max2;
    const float theirs_below = other.max1 < top ? other.max1 : other.max2;
    max2 = std::max(ours_below, theirs_below);
    max1 = top;
    const float bottom = std::min(min1, other.min1);
    const float ours_above = min1 > bottom ? min1 : min2;
    const float theirs_above = other.min1 > bottom ? other.min1 : other.min2;
    min2 = std::min(ours_above, theirs_above);
    min1 = bottom;
  }
};

// Eq. 10 for all coarse layers at once. "Closest to t_j" is the largest distance <= t_j or the
// smallest >= t_j, and both compose over sub-blocks by max / min. The thresholds t_0 > ... >
// t_{L-1} cut the distances into L + 1 buckets (bucket k: t_k <= d < t_{k-1}); a cell keeps,
// per bucket, its two largest and two smallest distinct distances, which merge over 2 x 2
// children exactly. The second values decide whether the float score |d - t_j| of the winner is
// shared by another distance of the cell (rounding, or one on each side of t_j): the scan would
// then keep the first such pixel in its order, so such a cell is scanned instead.
// A cell's distances fall into one or two of the (up to 25) buckets: a bit mask per cell says
// which hold any, so that merges and reads touch only those, and a resize clears only the masks.
class DistanceBuckets {
 public:
  // Kept from frame to frame (thread_local in buildClosestLayers): at 8 x 8 px cells the table of
  // extremes is about 1 MB, which a fresh allocation would fill (and fault in) every frame.
  void setThresholds(const std::vector<float>& thresholds) {
    thresholds_ = thresholds;
    buckets_ = static_cast<int>(thresholds.size()) + 1;
  }

  void resize(int width, int height) {
    width_ = width;
    height_ = height;
    const std::size_t cells = static_cast<std::size_t>(width) * height;
    masks_.assign(cells, 0);
    // Stale extremes stay: a bucket is read only once its bit is set, which overwrites them.
    if (extremes_.size() < cells * buckets_) extremes_.resize(cells * buckets_);
  }
  int width() const { return width_; }
  int height() const { return height_; }
  std::size_t cellIndex(int u, int v) const { return static_cast<std::size_t>(v) * width_ + u; }
  int bucketOf(float distance) const {
    int bucket = 0;
    for (float threshold : thresholds_) bucket += threshold > distance;
    return bucket;
  }
  void set(std::size_t cell, int bucket, const BucketExtremes& extremes) {
    masks_[cell] |= 1u << bucket;
    extremes_[cell * buckets_ + bucket] = extremes;
  }
  void add(std::size_t cell, float distance) {
    const int bucket = bucketOf(distance);
    BucketExtremes& extremes = extremes_[cell * buckets_ + bucket];
    if (!(masks_[cell] >> bucket & 1u)) {
      masks_[cell] |= 1u << bucket;
      extremes = BucketExtremes();
    }
    extremes.add(distance);
  }
  // The child cell's buckets into the parent cell of `parent` (which has as many buckets).
  void mergeInto(std::size_t child, DistanceBuckets* parent, std::size_t parent_cell) const {
    for (std::uint32_t mask = masks_[child]; mask != 0; mask &= mask - 1) {
      const int k = __builtin_ctz(mask);
      const BucketExtremes& theirs = extremes_[child * buckets_ + k];
      if (parent->masks_[parent_cell] >> k & 1u) {
        parent->extremes_[parent_cell * buckets_ + k].merge(theirs);
      } else {
        // Merging into an empty bucket copies (max2 < max1 and min2 > min1 hold in every cell).
        parent->set(parent_cell, k, theirs);
      }
    }
  }
  // The distance of the cell closest to t_level as the scan keeps it (NaN: no valid one);
  // false when another distance of the cell has the same score, i.e. the scan order decides.
  bool closest(std::size_t cell, int level, float* kept) const;

 private:
  bool has(std::size_t cell, int bucket) const { return masks_[cell] >> bucket & 1u; }
  const BucketExtremes& at(std::size_t cell, int bucket) const {
    return extremes_[cell * buckets_ + bucket];
  }

  std::vector<float> thresholds_;
  int buckets_ = 1;
  int width_ = 0;
  int height_ = 0;
  std::vector<std::uint32_t> masks_;      // per cell: bit k set when bucket k holds a distance
  std::vector<BucketExtremes> extremes_;  // per cell and bucket; valid where the bit is set
};

namespace {
// Work of one pass over a bucket layer: cells x buckets.
long cellBucketCount(const DistanceBuckets& buckets, int levels) {
  return static_cast<long>(buckets.width()) * buckets.height() * (levels + 1);
}
// From this many cell-buckets a bucket layer is merged and read on all threads. A cell-bucket
// costs several pixels' work, so the bar is a quarter of the pixel passes' (kParallelPixels):
// the 16 x 16 px layer of a 640 x 480 image (1200 cells, 12-14k cell-buckets) then runs on both
// threads (the coarse layers 0.10-0.11 against 0.14-0.15 ms a frame at 0.08-0.16 m, medians).
constexpr long kParallelCellBuckets = kParallelPixels / 4;
}  // namespace

bool DistanceBuckets::closest(std::size_t cell, int level, float* kept) const {
  const float target = thresholds_[static_cast<std::size_t>(level)];
  if (has(cell, level) && at(cell, level).min1 == target) {
    // score 0, and only t_level itself scores 0
    *kept = target;
    return true;
  }
  // Below t_level: buckets level + 1 ... L; at or above: buckets level ... 0.
  float below = -kInfinity, below_next = -kInfinity;
  for (int k = level + 1; k < buckets_ && below_next == -kInfinity; ++k) {
    if (!has(cell, k)) continue;
    if (below == -kInfinity) {
      below = at(cell, k).max1;
      below_next = at(cell, k).max2;
    } else {
      below_next = at(cell, k).max1;
    }
  }
  float above = kInfinity, above_next = kInfinity;
  for (int k = level; k >= 0 && above_next == kInfinity; --k) {
    if (!has(cell, k)) continue;
    if (above == kInfinity) {
      above = at(cell, k).min1;
      above_next = at(cell, k).min2;
    } else {
      above_next = at(cell, k).min1;
    }
  }
  const float below_score = std::abs(below - target);  // the scan's score, same float steps
  const float above_score = std::abs(above - target);
  if (below == -kInfinity && above == kInfinity) {
    *kept = kNaN;
    return true;
  }
  if (below_score == above_score) return false;
  const bool take_below = below_score < above_score;
  const float winner = take_below ? below : above;
  const float runner_up = take_below ? below_next : above_next;
  *kept = winner;
  return std::abs(runner_up - target) != std::abs(winner - target);
}

namespace {

// The reach of `farthest` rounded up to a float (-inf stays: no valid cell informs anything), so
// that a voxel farther than the float is farther than the reach.
float reachAtLeast(const MeasurementReach& reach, float farthest) {
  if (farthest == -kInfinity) return farthest;
  const double exact = reach.of(farthest);
  const float rounded = static_cast<float>(exact);
  return static_cast<double>(rounded) < exact ? std::nextafter(rounded, kInfinity) : rounded;
}

// The layers' storage of the frames a thread built before: M alone is 1.2 MB at 640 x 480, and
// glibc maps a block that large anew for each allocation, so every frame would fault its pages
// in again (a page fault per 4 KiB).
constexpr std::size_t kMaxSpareLayers = 32;
std::vector<std::vector<float>>& spareLayers() {
  thread_local std::vector<std::vector<float>> spare;
  return spare;
}

// A spare buffer of at least `size` floats if there is one (the smallest such), else a new one;
// its contents are left as they were.
std::vector<float> takeLayerBuffer(std::size_t size) {
  std::vector<std::vector<float>>& spare = spareLayers();
  auto best = spare.end();
  for (auto it = spare.begin(); it != spare.end(); ++it) {
    if (it->capacity() >= size && (best == spare.end() || it->capacity() < best->capacity())) {
      best = it;
    }
  }
  if (best == spare.end()) return {};
  std::vector<float> buffer = std::move(*best);
  spare.erase(best);
  return buffer;
}

}  // namespace

DistancePyramid::~DistancePyramid() {
  std::vector<std::vector<float>>& spare = spareLayers();
  for (std::vector<Layer>* layers : {&layers_, &squares_}) {
    for (Layer& layer : *layers) {
      if (layer.cells.capacity() > 0 && spare.size() < kMaxSpareLayers) {
        spare.push_back(std::move(layer.cells));
      }
    }
  }
}

DistancePyramid::DistancePyramid(const DepthImageView& depth, const CameraIntrinsics& camera,
                                 double t0, int levels, double max_range,
                                 PyramidSelection selection, const MeasurementReach* reach)
    : thresholds_(std::max(levels, 1)),
      scales_(thresholds_.size()),
      inverse_gaps_(thresholds_.size(), 0.0),
      layers_(thresholds_.size()),
      squares_(thresholds_.size()) {
  for (std::size_t level = 0; level < thresholds_.size(); ++level) {
    thresholds_[level] = t0 / static_cast<double>(1 << level);
    scales_[level] = 1.0 / static_cast<double>(1 << level);
  }
  for (std::size_t level = 0; level + 1 < thresholds_.size(); ++level) {
    inverse_gaps_[level] = 1.0 / (thresholds_[level + 1] - thresholds_[level]);
  }
  camera.validate();
  depth.validateAgainst(camera);
  Layer& distances = layers_[0];
  distances.width = camera.width;
  distances.height = camera.height;
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
  distances.cells = takeLayerBuffer(pixels);
  distances.cells.resize(pixels);  // every cell is written below
  // Eq. 6: distance = z |pixelRay(u, v)|, the ray's squared x and y per column and row, so the
  // loop over pixels is branch-free and vectorises (one sqrt per pixel, no division).
  std::vector<double> ray_x2(static_cast<std::size_t>(camera.width));
  for (int u = 0; u < camera.width; ++u)
    ray_x2[u] = camera.pixelRay(u, 0).x() * camera.pixelRay(u, 0).x();
  const int stride = depth.row_stride > 0 ? depth.row_stride : depth.width;
  const bool parallel = static_cast<long>(camera.width) * camera.height >= kParallelPixels;
  float farthest = 0.0f;  // valid distances are > 0
#pragma omp parallel if (parallel) reduction(max : farthest)
  {
    // The farthest distance (firstReadLevel) in the same pass, per column while the row is in
    // cache (elementwise, so it vectorises), instead of a second pass over M.
    std::vector<float> column_farthest(static_cast<std::size_t>(camera.width), 0.0f);
#pragma omp for schedule(static)
    for (int v = 0; v < camera.height; ++v) {
      const double ray_y = camera.pixelRay(0, v).y();
      const double ray_y2 = ray_y * ray_y;
      const float* depth_row = depth.depth + static_cast<std::size_t>(v) * stride;
      float* row = &distances.cells[static_cast<std::size_t>(v) * camera.width];
      for (int u = 0; u < camera.width; ++u) {
        const float z = depth_row[u];
        const double measured = z * std::sqrt(ray_x2[u] + ray_y2 + 1.0);
        // Invalid: z <= 0, NaN, infinite, or beyond max_range (NaN compares false). `&`, not
        // `&&`: no branch, so the loop vectorises.
        const bool valid = (z > 0.0f) & (measured <= max_range);
        row[u] = valid ? static_cast<float>(measured) : kNaN;
      }
      for (int u = 0; u < camera.width; ++u) {
        column_farthest[u] = row[u] > column_farthest[u] ? row[u] : column_farthest[u];
      }
    }
    for (float value : column_farthest) farthest = std::max(farthest, value);
  }
  farthest_ = farthest;
  for (int level = 1; level < this->levels(); ++level) sizeLayer(level);
  if (selection == PyramidSelection::kMinimum) {
    buildMinimumLayers();
  } else {
    const int first_read_level = firstReadLevel(reach);
    buildClosestLayers(first_read_level);
    if (reach != nullptr) buildSquareReaches(first_read_level, *reach);
  }
}

void DistancePyramid::buildSquareReaches(int first_level, const MeasurementReach& reach) {
  // A voxel that reaches the layers lies within the reach of the frame's farthest measurement,
  // so it reads no layer finer than first_level (firstReadLevel): those get no table.
  for (int level = std::max(first_level, 0); level < levels(); ++level) {
    const Layer& layer = layers_[level];
    Layer& squares = squares_[level];
    squares.width = layer.width + 1;
    squares.height = layer.height + 1;
    const std::size_t size = static_cast<std::size_t>(squares.width) * squares.height;
    squares.cells = takeLayerBuffer(size);
    squares.cells.resize(size);  // every cell is written below
    const bool parallel = static_cast<long>(size) >= kParallelPixels;
#pragma omp parallel if (parallel)
    {
      // Row r of the table covers the layer's rows r - 1 and r: their larger value per column,
      // then the larger of two neighbouring columns. NaN never compares larger; -inf pads.
      std::vector<float> columns(static_cast<std::size_t>(layer.width) + 2, -kInfinity);
#pragma omp for schedule(static)
      for (int r = 0; r < squares.height; ++r) {
        const float* above =
            r >= 1 ? &layer.cells[static_cast<std::size_t>(r - 1) * layer.width] : nullptr;
        const float* below =
            r < layer.height ? &layer.cells[static_cast<std::size_t>(r) * layer.width] : nullptr;
        for (int u = 0; u < layer.width; ++u) {
          float farthest = -kInfinity;
          if (above != nullptr) farthest = above[u] > farthest ? above[u] : farthest;
          if (below != nullptr) farthest = below[u] > farthest ? below[u] : farthest;
          columns[u + 1] = farthest;
        }
        float* row = &squares.cells[static_cast<std::size_t>(r) * squares.width];
        for (int c = 0; c < squares.width; ++c) {
          row[c] = reachAtLeast(reach, std::max(columns[c], columns[c + 1]));
        }
      }
    }
  }
}

int DistancePyramid::levelCount(const CameraIntrinsics& camera, double t0, double min_range,
                                int max_levels) {
  const int longest_side = std::max(camera.width, camera.height);
  int levels = 1;
  while (levels < max_levels && (1 << (levels - 1)) < longest_side &&
         t0 / static_cast<double>(1 << (levels - 1)) > min_range) {
    ++levels;
  }
  return levels;
}

void DistancePyramid::sizeLayer(int level) {
  const Layer& full = layers_[0];
  Layer& layer = layers_[level];
  const int side = 1 << level;
  layer.width = (full.width + side - 1) / side;
  layer.height = (full.height + side - 1) / side;
  const std::size_t cells = static_cast<std::size_t>(layer.width) * layer.height;
  layer.cells = takeLayerBuffer(cells);
  layer.cells.assign(cells, kNaN);
}

void DistancePyramid::buildMinimumLayers() {
  // The minimum of a block is the minimum of its 2 x 2 sub-blocks' minima (equal values are
  // the same value, so which pixel a scan would keep does not matter).
  for (int level = 1; level < levels(); ++level) {
    const Layer& finer = layers_[level - 1];
    Layer& layer = layers_[level];
    const bool parallel = 4L * layer.width * layer.height >= kParallelPixels;
#pragma omp parallel for schedule(static) if (parallel)
    for (int v = 0; v < layer.height; ++v) {
      for (int u = 0; u < layer.width; ++u) {
        float best = kInfinity;
        for (int child_v = 2 * v; child_v < std::min(finer.height, 2 * v + 2); ++child_v) {
          for (int child_u = 2 * u; child_u < std::min(finer.width, 2 * u + 2); ++child_u) {
            const float value =
                finer.cells[static_cast<std::size_t>(child_v) * finer.width + child_u];
            if (value < best) best = value;  // NaN never compares smaller
          }
        }
        if (best < kInfinity) layer.cells[static_cast<std::size_t>(v) * layer.width + u] = best;
      }
    }
  }
}

int DistancePyramid::firstReadLevel(const MeasurementReach* reach_model) const {
  if (reach_model == nullptr) return 0;
  if (farthest_ == 0.0f) return levels();  // no valid pixel: no layer is read
  // A voxel is read at its bracketing level i (t_{i+1} < distance <= t_i) and i + 1; no voxel
  // farther than the reach is informed, so the nearest informed voxels decide (Eq. 12).
  const double reach = reach_model->of(farthest_);
  int level = 0;
  while (level + 1 < levels() && reach <= threshold(level + 1)) ++level;
  return level;
}

void DistancePyramid::buildClosestLayers(int first_read_level) {
  // The fine layers have few pixels per cell: scanning M is cheaper than bucket bookkeeping.
  // Those finer than any voxel reads stay invalid (at coarse resolutions the 2 x 2 and 4 x 4
  // layers are read only by voxels tens of metres away).
  const int scanned = std::min(kScannedLevels, levels());
  const int first_scanned = std::max(1, first_read_level);
  // One level after the other, each on all threads (fillLayer): at most resolutions only one of
  // them is read, and one level per thread left the other threads idle (a third of the pyramid's
  // time at 0.04 m on 7-Scenes).
  for (int level = first_scanned; level < scanned; ++level) {
    const float target = static_cast<float>(threshold(level));
    fillLayer(
        layers_[0], level, [target](float value) { return std::abs(value - target); },
        &layers_[level]);
  }
  if (levels() <= kScannedLevels) return;
  std::vector<float> targets(static_cast<std::size_t>(levels()));
  for (int level = 0; level < levels(); ++level) {
    targets[level] = static_cast<float>(threshold(level));
  }
  thread_local DistanceBuckets kept_coarse, kept_finer;
  // Used through pointers: inside the parallel loop below, a thread_local's name would mean each
  // thread's own (empty) tables, not this thread's.
  DistanceBuckets* coarse = &kept_coarse;
  DistanceBuckets* finer = &kept_finer;
  coarse->setThresholds(targets);
  finer->setThresholds(targets);
  fillBuckets(kScannedLevels, coarse);
  takeClosest(*coarse, kScannedLevels);
  for (int level = kScannedLevels + 1; level < levels(); ++level) {
    std::swap(coarse, finer);
    coarse->resize(layers_[level].width, layers_[level].height);
    const bool parallel = cellBucketCount(*coarse, levels()) >= kParallelCellBuckets;
#pragma omp parallel for schedule(static) if (parallel)
    for (int v = 0; v < coarse->height(); ++v) {
      for (int u = 0; u < coarse->width(); ++u) {
        const std::size_t parent = coarse->cellIndex(u, v);
        for (int child_v = 2 * v; child_v < std::min(finer->height(), 2 * v + 2); ++child_v) {
          for (int child_u = 2 * u; child_u < std::min(finer->width(), 2 * u + 2); ++child_u) {
            finer->mergeInto(finer->cellIndex(child_u, child_v), coarse, parent);
          }
        }
      }
    }
    takeClosest(*coarse, level);
  }
}

namespace {

// Per pixel column of a strip of rows: the smallest and largest valid value, then the smallest
// above and the largest below the column's cell's own extremes. Each pass is elementwise over
// whole rows with branch-free selects, so it vectorises; NaN never compares, so invalid pixels
// drop out, as in BucketExtremes::add.
class StripExtremes {
 public:
  // Rows [v_begin, v_end) of M, `side` px cells.
  void measure(const float* cells, int width, int v_begin, int v_end, int side) {
    resize(width);
    std::fill(min1_.begin(), min1_.end(), kInfinity);
    std::fill(max1_.begin(), max1_.end(), -kInfinity);
    for (int v = v_begin; v < v_end; ++v) {
      const float* row = cells + static_cast<std::size_t>(v) * width;
      for (int u = 0; u < width; ++u) {
        min1_[u] = row[u] < min1_[u] ? row[u] : min1_[u];
        max1_[u] = row[u] > max1_[u] ? row[u] : max1_[u];
      }
    }
    // The cells' extremes, written back to each of their columns for the second pass.
    for (int first = 0; first < width; first += side) {
      const int last = std::min(width, first + side);
      float low = kInfinity, high = -kInfinity;
      for (int u = first; u < last; ++u) {
        low = min1_[u] < low ? min1_[u] : low;
        high = max1_[u] > high ? max1_[u] : high;
      }
      std::fill(min1_.data() + first, min1_.data() + last, low);
      std::fill(max1_.data() + first, max1_.data() + last, high);
    }
    std::fill(min2_.begin(), min2_.end(), kInfinity);
    std::fill(max2_.begin(), max2_.end(), -kInfinity);
    for (int v = v_begin; v < v_end; ++v) {
      const float* row = cells + static_cast<std::size_t>(v) * width;
      for (int u = 0; u < width; ++u) {
        const float above = row[u] > min1_[u] ? row[u] : kInfinity;
        const float below = row[u] < max1_[u] ? row[u] : -kInfinity;
        min2_[u] = above < min2_[u] ? above : min2_[u];
        max2_[u] = below > max2_[u] ? below : max2_[u];
      }
    }
  }
  // The extremes of the cell of columns [first, last): its two smallest and two largest
  // distinct values.
  BucketExtremes cell(int first, int last) const {
    BucketExtremes extremes;
    extremes.min1 = min1_[first];
    extremes.max1 = max1_[first];
    for (int u = first; u < last; ++u) {
      extremes.min2 = min2_[u] < extremes.min2 ? min2_[u] : extremes.min2;
      extremes.max2 = max2_[u] > extremes.max2 ? max2_[u] : extremes.max2;
    }
    return extremes;
  }

 private:
  void resize(int width) {
    min1_.resize(width);
    min2_.resize(width);
    max1_.resize(width);
    max2_.resize(width);
  }
  std::vector<float> min1_, min2_, max1_, max2_;
};

}  // namespace

void DistancePyramid::fillBuckets(int level, DistanceBuckets* buckets) const {
  const Layer& full = layers_[0];
  buckets->resize(layers_[level].width, layers_[level].height);
  const int side = 1 << level;
#pragma omp parallel
  {
    StripExtremes strip;
#pragma omp for schedule(static)
    for (int cell_v = 0; cell_v < buckets->height(); ++cell_v) {
      const int v_begin = cell_v * side;
      const int v_end = std::min(full.height, v_begin + side);
      strip.measure(full.cells.data(), full.width, v_begin, v_end, side);
      for (int cell_u = 0; cell_u < buckets->width(); ++cell_u) {
        const int u_begin = cell_u * side;
        const int u_end = std::min(full.width, u_begin + side);
        const BucketExtremes extremes = strip.cell(u_begin, u_end);
        if (extremes.max1 == -kInfinity) continue;  // no valid pixel
        const std::size_t cell = buckets->cellIndex(cell_u, cell_v);
        // Most cells lie within one bucket: then its extremes are the cell's.
        const int bucket = buckets->bucketOf(extremes.min1);
        if (bucket == buckets->bucketOf(extremes.max1)) {
          buckets->set(cell, bucket, extremes);
          continue;
        }
        for (int v = v_begin; v < v_end; ++v) {
          const float* row = &full.cells[static_cast<std::size_t>(v) * full.width];
          for (int u = u_begin; u < u_end; ++u) {
            if (!std::isnan(row[u])) buckets->add(cell, row[u]);
          }
        }
      }
    }
  }
}

void DistancePyramid::takeClosest(const DistanceBuckets& buckets, int level) {
  Layer& layer = layers_[level];
  const float target = static_cast<float>(threshold(level));
  const bool parallel = cellBucketCount(buckets, levels()) >= kParallelCellBuckets;
#pragma omp parallel for schedule(dynamic, 1) if (parallel)
  for (int v = 0; v < layer.height; ++v) {
    for (int u = 0; u < layer.width; ++u) {
      float& kept = layer.cells[static_cast<std::size_t>(v) * layer.width + u];
      if (!buckets.closest(buckets.cellIndex(u, v), level, &kept)) {
        kept = scanCell(level, u, v, target);  // a tie: the scan order decides
      }
    }
  }
}

float DistancePyramid::scanCell(int level, int cell_u, int cell_v, float target) const {
  const Layer& full = layers_[0];
  const int side = 1 << level;
  float best_score = kInfinity;
  float kept = kNaN;
  for (int v = cell_v * side; v < std::min(full.height, (cell_v + 1) * side); ++v) {
    for (int u = cell_u * side; u < std::min(full.width, (cell_u + 1) * side); ++u) {
      const float value = full.cells[static_cast<std::size_t>(v) * full.width + u];
      const float candidate = std::abs(value - target);
      if (candidate < best_score) {
        best_score = candidate;
        kept = value;
      }
    }
  }
  return kept;
}

template <class Score>
void DistancePyramid::fillLayer(const Layer& full, int level, Score score, Layer* layer) {
  // Row by row through M, keeping each cell's best so far: the same candidates in the same
  // order (rows of a cell top to bottom, each left to right) as a cell-by-cell scan, so ties go
  // to the same measurement. NaN scores never compare smaller, so invalid pixels drop out.
  // Within a row the best of the cell's run of pixels is kept in registers and merged once
  // (strictly smaller wins, so the earlier row keeps ties): no store-to-load chain per pixel.
  // Rows of cells are independent: they are shared among the threads.
  const int side = 1 << level;
  const bool parallel = static_cast<long>(full.width) * full.height >= kParallelPixels;
#pragma omp parallel if (parallel)
  {
    std::vector<float> best_score(static_cast<std::size_t>(layer->width));
#pragma omp for schedule(static)
    for (int cell_v = 0; cell_v < layer->height; ++cell_v) {
      float* best = &layer->cells[static_cast<std::size_t>(cell_v) * layer->width];
      std::fill(best_score.begin(), best_score.end(), std::numeric_limits<float>::infinity());
      const int v_end = std::min(full.height, (cell_v + 1) * side);
      for (int v = cell_v * side; v < v_end; ++v) {
        const float* row = &full.cells[static_cast<std::size_t>(v) * full.width];
        for (int cell_u = 0; cell_u < layer->width; ++cell_u) {
          const int u_end = std::min(full.width, (cell_u + 1) * side);
          float run_score = best_score[cell_u];
          float run_value = best[cell_u];
          for (int u = cell_u * side; u < u_end; ++u) {
            const float candidate = score(row[u]);
            if (candidate < run_score) {
              run_score = candidate;
              run_value = row[u];
            }
          }
          best_score[cell_u] = run_score;
          best[cell_u] = run_value;
        }
      }
    }
  }
}

}  // namespace occupancy_fusion
