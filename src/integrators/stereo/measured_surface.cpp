#include "occupancy_fusion/integrators/stereo/measured_surface.h"

#include <omp.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "float_quads.h"
#include "occupancy_fusion/integrators/stereo/median_network.h"

namespace occupancy_fusion {

void MeasuredSurfaceConfig::validate() const {
  if (window_px < 1) throw std::invalid_argument("MeasuredSurfaceConfig.window_px must be >= 1");
  if (local_window_px < 0 || local_window_px > window_px) {
    throw std::invalid_argument("MeasuredSurfaceConfig.local_window_px must be in [0, window_px]");
  }
  if (!(inlier_px > 0))
    throw std::invalid_argument("MeasuredSurfaceConfig.inlier_px must be positive");
  if (sample_step_px < 1 || sample_step_px > window_px) {
    throw std::invalid_argument("MeasuredSurfaceConfig.sample_step_px must be in [1, window_px]");
  }
  if (grid_step_px < 1 || grid_step_px > window_px) {
    throw std::invalid_argument("MeasuredSurfaceConfig.grid_step_px must be in [1, window_px]");
  }
  if (window_px >= 32 * sample_step_px) {
    // (window_px / 2 / sample_step_px) samples each side: at most 31^2 samples to a median.
    throw std::invalid_argument(
        "MeasuredSurfaceConfig.window_px must be below 32 * sample_step_px (a median takes at "
        "most " +
        std::to_string(MedianNetwork::kMaxSlots) + " samples)");
  }
  if (grid_step_px % sample_step_px != 0) {
    throw std::invalid_argument(
        "MeasuredSurfaceConfig.grid_step_px must be a multiple of sample_step_px");
  }
  if (grid_max_step_px != 0 && (grid_max_step_px < grid_step_px || grid_max_step_px > window_px ||
                                grid_max_step_px % sample_step_px != 0)) {
    throw std::invalid_argument(
        "MeasuredSurfaceConfig.grid_max_step_px must be 0 or a multiple of sample_step_px in "
        "[grid_step_px, window_px]");
  }
  if (!(step_px >= 0)) throw std::invalid_argument("MeasuredSurfaceConfig.step_px must be >= 0");
  if (!(min_valid > 0 && min_valid <= 1)) {
    throw std::invalid_argument("MeasuredSurfaceConfig.min_valid must be in (0, 1]");
  }
  if (!(grid_footprint_fraction >= 0 && grid_footprint_fraction <= 1)) {
    throw std::invalid_argument("MeasuredSurfaceConfig.grid_footprint_fraction must be in [0, 1]");
  }
}

namespace {

constexpr float kNoSurface = std::numeric_limits<float>::quiet_NaN();
constexpr float kInfinity = std::numeric_limits<float>::infinity();
constexpr int kMinLocalPairs = 4;  // fewer inliers in the small window: the wide median stands

// Finite and positive, without a call: false for NaN and +inf as for 0 and negative values.
inline bool isValidDisparity(float d) { return d > 0 && d <= std::numeric_limits<float>::max(); }

}  // namespace

namespace {

// The point-symmetric pixel pairs about a node within `reach` px whose pixels are both valid,
// and the centre pixel if it is: how many there are, how many of them lie within `limit` of
// `reference` (both pixels), and the mean of those. On a plane, whose disparity is linear in u
// and v, every pair mean is the centre's disparity, whatever the slope and also where invalid
// pixels (the range limit, an image border, a matcher's holes) lie on one side only.
struct LocalPairs {
  int valid = 0;
  int inliers = 0;
  float mean = 0;
};

// The vectors of Width lanes: floats, their comparisons' masks, and doubles for half of them.
template <int Width>
struct LaneVectors;
template <>
struct LaneVectors<4> {
  using Float = FloatQuad;
  using Int = int __attribute__((vector_size(4 * sizeof(int))));
  using DoubleHalf = double __attribute__((vector_size(2 * sizeof(double))));  // two lanes
};
template <>
struct LaneVectors<8> {
  using Float = FloatOctet;
  using Int = int __attribute__((vector_size(8 * sizeof(int))));
  using DoubleHalf = double __attribute__((vector_size(4 * sizeof(double))));  // four lanes
};

// Adds the lanes of `term` in double, the first half of them to *low, the rest to *high (a
// vector of Width doubles would live in memory).
template <typename Vector, typename DoubleHalf, std::size_t... Lane>
inline __attribute__((always_inline)) void addInDouble(const Vector& term, DoubleHalf* low,
                                                       DoubleHalf* high,
                                                       std::index_sequence<Lane...>) {
  constexpr std::size_t kHalf = sizeof...(Lane);
  *low += DoubleHalf{static_cast<double>(term[Lane])...};
  *high += DoubleHalf{static_cast<double>(term[kHalf + Lane])...};
}

// The pixels `step` apart from p on, one a lane, written to `lanes` (returned through a
// reference: a function built for the baseline must not return an AVX vector).
template <typename Vector, std::size_t... Lane>
inline __attribute__((always_inline)) void gatherLanes(const float* p, int step, Vector* lanes,
                                                       std::index_sequence<Lane...>) {
  *lanes = Vector{p[static_cast<std::ptrdiff_t>(Lane) * step]...};
}

// The LocalPairs of the nodes (u + l * step, v) of kLanes lanes at once, each against its own
// reference, Width lanes to a Vector, without a branch on the pixels' values (noise makes them
// unpredictable): NaN and +inf fail the comparisons. Every node's window must lie inside the
// image (windowsOfLanes makes one that does). The mean is summed in double, pair by pair in
// the window's row order, then the centre: the same operations on every lane whatever the
// width, so both widths give the same bits. Inlined into each caller so that the vectors take
// the caller's instruction set.
template <int Width>
inline __attribute__((always_inline)) void localPairsOfWidth(const DisparityImageView& image, int u,
                                                             int step, int v, int reach,
                                                             const float* references, float limit,
                                                             LocalPairs* pairs) {
  using Vector = typename LaneVectors<Width>::Float;
  using IntVector = typename LaneVectors<Width>::Int;
  using DoubleHalf = typename LaneVectors<Width>::DoubleHalf;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const std::ptrdiff_t stride = image.row_stride > 0 ? image.row_stride : image.width;
  const Vector no_term = {};
  const IntVector magnitude = IntVector{} + 0x7fffffff;  // all bits but the sign
  for (int part = 0; part < MedianNetwork::kLanes / Width; ++part) {
    const float* centre = image.disparity + v * stride + u + Width * part * step;
    Vector reference;
    std::memcpy(&reference, references + Width * part, sizeof(reference));
    IntVector valid_count = {}, inlier_count = {};
    // The pairs' float sums added in double and halved once before the centre: halving is exact,
    // so this is the sum of the pair means, bit for bit. A term left out adds 0.0 (the sums
    // start at +0). valid: NaN and +inf fail; inlier: |d - reference| <= limit (NaN fails).
    DoubleHalf low = {}, high = {};  // lanes [0, Width / 2) and [Width / 2, Width)
    for (int dv = -reach; dv <= 0; ++dv) {
      const int last = dv == 0 ? -1 : reach;
      for (int du = -reach; du <= last; ++du) {
        Vector first, second;
        gatherLanes(centre + dv * stride + du, step, &first, std::make_index_sequence<Width>());
        gatherLanes(centre - dv * stride - du, step, &second, std::make_index_sequence<Width>());
        const IntVector both = (first > 0) & (first < kInf) & (second > 0) & (second < kInf);
        const IntVector inlier = both &
                                 ((Vector)((IntVector)(first - reference) & magnitude) <= limit) &
                                 ((Vector)((IntVector)(second - reference) & magnitude) <= limit);
        addInDouble(inlier ? first + second : no_term, &low, &high,
                    std::make_index_sequence<Width / 2>());
        valid_count -= both;  // masks are -1
        inlier_count -= inlier;
      }
    }
    low *= 0.5;
    high *= 0.5;
    Vector middle;
    gatherLanes(centre, step, &middle, std::make_index_sequence<Width>());
    const IntVector middle_valid = (middle > 0) & (middle < kInf);
    const IntVector middle_inlier =
        middle_valid & ((Vector)((IntVector)(middle - reference) & magnitude) <= limit);
    addInDouble(middle_inlier ? middle : no_term, &low, &high,
                std::make_index_sequence<Width / 2>());
    valid_count -= middle_valid;
    inlier_count -= middle_inlier;
    for (int l = 0; l < Width; ++l) {
      LocalPairs& lane = pairs[Width * part + l];
      lane.valid = valid_count[l];
      lane.inliers = inlier_count[l];
      const double sum = l < Width / 2 ? low[l] : high[l - Width / 2];
      lane.mean = lane.inliers > 0 ? static_cast<float>(sum / lane.inliers) : 0.0f;
    }
  }
}

#ifdef OCCUPANCY_FUSION_HAS_AVX2_PATH
// With AVX2 (chosen at run time): one octet, half the instructions.
__attribute__((target("avx2"))) void localPairsOnOctets(const DisparityImageView& image, int u,
                                                        int step, int v, int reach,
                                                        const float* references, float limit,
                                                        LocalPairs* pairs) {
  localPairsOfWidth<8>(image, u, step, v, reach, references, limit, pairs);
}
#endif

void localPairsOfLanes(const DisparityImageView& image, int u, int step, int v, int reach,
                       const float* references, float limit,
                       MedianNetwork::Instructions instructions, LocalPairs* pairs) {
#ifdef OCCUPANCY_FUSION_HAS_AVX2_PATH
  if (instructions == MedianNetwork::Instructions::kWidest && processorHasAvx2()) {
    localPairsOnOctets(image, u, step, v, reach, references, limit, pairs);
    return;
  }
#endif
  localPairsOfWidth<4>(image, u, step, v, reach, references, limit, pairs);
}

// The pixels that the small windows of a row's kLanes nodes from (u, v) on (`step` px apart)
// read, NaN outside the image, as an image of its own in which those nodes lie at (reach, reach)
// on: for localPairsOfLanes where a window is cut by the image's border (a pair with a pixel
// outside is invalid, as a pair with a hole) or a lane lies past the row's last node.
DisparityImageView windowsOfLanes(const DisparityImageView& image, int u, int step, int v,
                                  int reach, std::vector<float>* patch) {
  DisparityImageView windows;
  windows.width = (MedianNetwork::kLanes - 1) * step + 2 * reach + 1;
  windows.height = 2 * reach + 1;
  patch->assign(static_cast<std::size_t>(windows.width) * windows.height, kNoSurface);
  for (int y = 0; y < windows.height; ++y) {
    const int image_v = v - reach + y;
    if (image_v < 0 || image_v >= image.height) continue;
    const int first = std::max(0, reach - u),
              last = std::min(windows.width, image.width - u + reach);
    if (first >= last) continue;
    std::copy(image.row(image_v) + (u - reach + first), image.row(image_v) + (u - reach + last),
              patch->data() + static_cast<std::size_t>(y) * windows.width + first);
  }
  windows.disparity = patch->data();
  return windows;
}

}  // namespace

int MeasuredSurface::gridStepForSmallest(float smallest, const StereoCamera& camera,
                                         const MeasuredSurfaceConfig& config,
                                         const SurfaceGridScale& scale) {
  // smallest: the smallest disparity the rays use, on the wide windows' sample lattice: the
  // farthest depth, where a voxel's image is smallest: f r / z = r d / b px for z = f b / d.
  if (!(config.grid_footprint_fraction > 0 && scale.voxel_size_m > 0)) return config.grid_step_px;
  if (!std::isfinite(smallest)) return config.grid_step_px;
  const int sample = config.sample_step_px;
  const double focal_baseline = camera.fx * camera.baseline;
  if (scale.max_range_m > 0)
    smallest = std::max<float>(smallest, focal_baseline / scale.max_range_m);
  const double footprint_px = scale.voxel_size_m * smallest / camera.baseline;
  int widest = config.window_px / sample * sample;
  if (config.grid_max_step_px > 0) widest = std::min(widest, config.grid_max_step_px);
  const int step =
      static_cast<int>(config.grid_footprint_fraction * footprint_px / sample) * sample;
  return std::max(config.grid_step_px, std::min(widest, step));
}

// The pixels every sample_step px, with `pad` NaN samples around, so that a window reaching past
// the image needs no bounds checks: the wide windows of all grid nodes read this one lattice.
class MeasuredSurface::SampleLattice {
 public:
  // extra: lattice points past the image's last column that a read may reach (the lanes past
  // the last grid point), NaN as the padding. smallest(): the smallest sample at least
  // `least` (gridStepFor's scan, in the same pass).
  SampleLattice(const DisparityImageView& image, int step, int pad, int extra, double least)
      : pad_(pad), columns_((image.width - 1) / step + 1 + 2 * pad + extra) {
    const int rows = (image.height - 1) / step + 1 + 2 * pad;
    samples_.assign(static_cast<std::size_t>(columns_) * rows, kNoSurface);
    const int width = (image.width - 1) / step + 1;
    // The smallest float at least `least`, so that the float comparison below is the double one.
    float least_f = static_cast<float>(least);
    if (static_cast<double>(least_f) < least) least_f = std::nextafter(least_f, kInfinity);
    for (int j = 0; j * step < image.height; ++j) {
      // Selects, not branches: holes and the range limit come in no order a predictor learns.
      const float* pixels = image.row(j * step);
      float* samples = &samples_[index(0, j)];
      float smallest = smallest_;
      for (int i = 0; i < width; ++i) {
        const float d = pixels[i * step];
        const bool valid = isValidDisparity(d);
        samples[i] = valid ? d : kNoSurface;
        smallest = std::min(smallest, valid && d >= least_f ? d : kInfinity);
      }
      smallest_ = smallest;
    }
  }
  float smallest() const { return smallest_; }  // +inf: none
  // The means of the point-symmetric sample pairs within `reach` samples, and the centre
  // sample, about the lattice points (i + l * stride, j) of the lanes l: NaN where a sample is
  // missing, one row of `rows` (2 reach (reach + 1) + 1 of them) a pair.
  void pairMeans(int i, int j, int stride, int reach, MedianNetwork::Lanes* rows) const {
    constexpr int kLanes = MedianNetwork::kLanes;
    int slot = 0;
    for (int dj = -reach; dj <= 0; ++dj) {
      const float* row = &samples_[index(i, j + dj)];
      const float* mirrored = &samples_[index(i, j - dj)];
      const int last = dj == 0 ? -1 : reach;
      for (int di = -reach; di <= last; ++di, ++slot) {
        for (int q = 0; q < kLanes; q += 4) {
          const FloatQuad first = lanes(row + q * stride + di, stride);
          const FloatQuad second = lanes(mirrored + q * stride - di, stride);
          storeQuad(0.5f * (first + second), rows[slot].data() + q);
        }
      }
    }
    const float* centre = &samples_[index(i, j)];
    for (int q = 0; q < kLanes; q += 4) {
      storeQuad(lanes(centre + q * stride, stride), rows[slot].data() + q);
    }
  }
  // The samples within `reach` of the lattice points (i + l * stride, j) themselves, not pair
  // means, on a checkerboard (offsets whose sum is even: half of them, as evenly spread over the
  // window): NaN where missing, one row of `rows` (((2 reach + 1)^2 + 1) / 2) an offset.
  void samples(int i, int j, int stride, int reach, MedianNetwork::Lanes* rows) const {
    constexpr int kLanes = MedianNetwork::kLanes;
    int slot = 0;
    for (int dj = -reach; dj <= reach; ++dj) {
      const float* row = &samples_[index(i, j + dj)];
      for (int di = -reach + (reach + dj) % 2; di <= reach; di += 2, ++slot) {
        for (int q = 0; q < kLanes; q += 4) {
          storeQuad(lanes(row + q * stride + di, stride), rows[slot].data() + q);
        }
      }
    }
  }

 private:
  // Four samples `stride` apart, written to the median network's rows as one quad: it reads
  // them back as vectors, which wait for smaller stores (one per lane) to leave the store buffer.
  static FloatQuad lanes(const float* first, int stride) {
    if (stride == 1) return loadQuad(first);
    return FloatQuad{first[0], first[stride], first[2 * stride], first[3 * stride]};
  }
  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j + pad_) * columns_ + (i + pad_);
  }
  int pad_, columns_;
  std::vector<float> samples_;
  float smallest_ = std::numeric_limits<float>::infinity();
};

int MeasuredSurface::gridStepFor(const DisparityImageView& disparity, const StereoCamera& camera,
                                 const MeasuredSurfaceConfig& config,
                                 const SurfaceGridScale& scale) {
  const SampleLattice lattice(disparity, config.sample_step_px, 0, 0, scale.min_disparity_px);
  return gridStepForSmallest(lattice.smallest(), camera, config, scale);
}

MeasuredSurface::MeasuredSurface(const DisparityImageView& disparity, const StereoCamera& camera,
                                 const Eigen::Isometry3d& T_map_camera,
                                 const MeasuredSurfaceConfig& config, const SurfaceGridScale& scale)
    : T_camera_map_(T_map_camera.inverse()),
      fx_(camera.fx),
      fy_(camera.fy),
      cx_(camera.cx),
      cy_(camera.cy),
      focal_baseline_(camera.fx * camera.baseline),
      width_(disparity.width),
      height_(disparity.height) {
  config.validate();
  disparity.validate();
  // Padded for the lanes past a row's last node at the widest grid step (window_px).
  const int sample = config.sample_step_px;
  const SampleLattice lattice(disparity, sample, (config.window_px / 2) / sample,
                              (MedianNetwork::kLanes - 1) * (config.window_px / sample),
                              scale.min_disparity_px);
  step_ = gridStepForSmallest(lattice.smallest(), camera, config, scale);
  columns_ = (width_ - 1) / step_ + 1;
  rows_ = (height_ - 1) / step_ + 1;
  cells_.assign(static_cast<std::size_t>(columns_) * rows_, kNoSurface);
  // The border's band (border_from_interior), where grid points lie inside it on both axes.
  auto hasInside = [&](int size) {
    return (sample + step_ - 1) / step_ * step_ <= size - 1 - sample;
  };
  band_px_ = config.border_from_interior && hasInside(width_) && hasInside(height_) ? sample : 0;
  measureNodes(disparity, lattice, config);
  // The band's grid points that measureNodes' groups computed beside others: extrapolated below.
  // The band is narrower than a grid step (band_px_ = sample <= step_), so it holds at most the
  // first and the last row and column: only those are visited.
  if (band_px_ > 0) {
    for (int j : {0, rows_ - 1}) {
      for (int i = 0; i < columns_; ++i) {
        if (inBand(i, j)) cells_[linear(i, j)] = kNoSurface;
      }
    }
    for (int j = 1; j + 1 < rows_; ++j) {
      for (int i : {0, columns_ - 1}) {
        if (inBand(i, j)) cells_[linear(i, j)] = kNoSurface;
      }
    }
  }
  extendByOneNode();
  // Each pass reaches one grid point further out; corners take both directions.
  for (int pass = 0; pass * step_ < band_px_; ++pass) extendByOneNode(true);
  findSteps(config.step_px);
}

namespace {

// Runs row(j) for j in [0, rows): on this thread's team when called outside a parallel region,
// as tasks of the enclosing team inside one, so that the surface's rows and other work of the
// frame (its disparity conversion) share the threads. Rows are independent, so any schedule
// gives the same grid.
template <typename Row>
void forEachRow(int rows, Row&& row) {
  if (omp_in_parallel()) {
#pragma omp taskloop grainsize(4)
    for (int j = 0; j < rows; ++j) row(j);
  } else {
#pragma omp parallel for schedule(static)
    for (int j = 0; j < rows; ++j) row(j);
  }
}

}  // namespace

void MeasuredSurface::measureNodes(const DisparityImageView& disparity,
                                   const SampleLattice& lattice,
                                   const MeasuredSurfaceConfig& config) {
  constexpr int kLanes = MedianNetwork::kLanes;
  const int reach = (config.window_px / 2) / config.sample_step_px;
  const int stride = step_ / config.sample_step_px;  // lattice points from one node to the next
  const int per_side = 2 * reach + 1;
  const int pairs = 2 * reach * (reach + 1) + 1;  // pair means and the centre
  const int needed = static_cast<int>(std::ceil(config.min_valid * (per_side * per_side + 1) / 2));
  const MedianNetwork pair_network(pairs, config.instructions),
      sample_network((per_side * per_side + 1) / 2, config.instructions);
  const int local_reach = config.local_window_px / 2;
  const float limit = static_cast<float>(config.inlier_px);
  forEachRow(rows_, [&](int j) {
    if (inBand(columns_ / 2, j)) return;  // a row of the border's band: extrapolated
    std::vector<MedianNetwork::Lanes> rows(per_side * per_side);
    std::vector<float> patch;  // a border group's windows (windowsOfLanes)
    int counts[kLanes], sample_counts[kLanes];
    float robust[kLanes], one_side[kLanes];
    LocalPairs local[kLanes], side[kLanes];
    const int v = j * step_;
    for (int first = 0; first < columns_; first += kLanes) {
      const int lanes_used = std::min(kLanes, columns_ - first);
      // Groups wholly in the band's columns are skipped (its lanes in others are cleared after).
      if ((first + lanes_used - 1) * step_ < band_px_) continue;
      if (first * step_ > width_ - 1 - band_px_) break;
      // 1. The wide windows' medians, kLanes nodes of the row at once: robust while a patch
      //    spoils fewer than half a window's pairs, but on a kink of the surface (a corner, an
      //    object's edge) biased by the window's size.
      lattice.pairMeans(first * stride, j * stride, stride, reach, rows.data());
      pair_network.medians(rows.data(), counts, robust);
      if (local_reach == 0) {
        for (int l = 0; l < lanes_used; ++l) {
          if (counts[l] >= needed) cells_[linear(first + l, j)] = robust[l];
        }
        continue;
      }
      // 2. The small window's mean over the pixels within inlier_px of it: the patches' pixels
      //    left out, and a kink's bias that of the small window. Where the small window has
      //    enough valid pairs but too few of them near the median, it straddles a step (an
      //    object's outline): pairs across it have means between the two sides, and their
      //    median is a surface in the gap that no pixel sees. There the median of the wide
      //    window's samples themselves (every other one), which lies on one side, takes its
      //    place.
      const int u = first * step_;
      const bool inside = u >= local_reach && u + (kLanes - 1) * step_ + local_reach < width_ &&
                          v >= local_reach && v + local_reach < height_;
      DisparityImageView windows = disparity;
      int window_u = u, window_v = v;
      if (!inside) {
        windows = windowsOfLanes(disparity, u, step_, v, local_reach, &patch);
        window_u = window_v = local_reach;
      }
      auto localPairsOfRow = [&](const float* references, LocalPairs* pairs) {
        localPairsOfLanes(windows, window_u, step_, window_v, local_reach, references, limit,
                          config.instructions, pairs);
      };
      localPairsOfRow(robust, local);
      bool straddles = false;
      for (int l = 0; l < lanes_used; ++l) {
        straddles |= counts[l] >= needed && local[l].inliers < kMinLocalPairs &&
                     local[l].valid >= kMinLocalPairs;
      }
      if (straddles) {
        lattice.samples(first * stride, j * stride, stride, reach, rows.data());
        sample_network.medians(rows.data(), sample_counts, one_side);
        localPairsOfRow(one_side, side);
      }
      for (int l = 0; l < lanes_used; ++l) {
        if (counts[l] < needed) continue;  // needed >= 1: min_valid > 0
        float surface = robust[l];
        if (local[l].inliers >= kMinLocalPairs) {
          surface = local[l].mean;
        } else if (local[l].valid >= kMinLocalPairs && sample_counts[l] > 0) {
          // (Without a valid sample the samples' median is +inf: the wide median stands.)
          surface = side[l].inliers >= kMinLocalPairs ? side[l].mean : one_side[l];
        }
        cells_[linear(first + l, j)] = surface;
      }
    }
  });
}

void MeasuredSurface::extendByOneNode(bool band_only) {
  // A node without a surface next to ones that have (the range limit, the edge of a hole, the
  // image's border): the mean of the linear extrapolations along its row and column from the two
  // nodes on each side that have, exact on a plane. Without it the pixels between the last
  // surface and the range limit read no surface (two of their cell's corners missing), and their
  // rays meet the paper's prior all along their line of sight: the far end of a corridor was
  // mapped frames late.
  constexpr int kDirections[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  std::vector<float> extended = cells_;
  forEachRow(rows_, [&](int j) {
    for (int i = 0; i < columns_; ++i) {
      if (!std::isnan(cellAt(i, j)) || (band_only && !inBand(i, j))) continue;
      double sum = 0;
      int count = 0;
      for (const auto& [di, dj] : kDirections) {
        const int i2 = i + 2 * di, j2 = j + 2 * dj;
        if (i2 < 0 || i2 >= columns_ || j2 < 0 || j2 >= rows_) continue;
        const float near = cellAt(i + di, j + dj), far = cellAt(i2, j2);
        if (std::isnan(near) || std::isnan(far)) continue;
        sum += 2.0 * near - far;
        ++count;
      }
      if (count > 0 && sum > 0) extended[linear(i, j)] = static_cast<float>(sum / count);
    }
  });
  cells_ = std::move(extended);
}

namespace {

// The grid edge from `first` to `second` against the edges before and after it along its line:
// a step where it differs from every one of them that has both ends, and at least one has.
// Without branches on the cells (holes and steps come in no order a predictor could learn), so
// that a line's edges vectorise. A missing node is NaN: an edge without both ends is no step
// and compares with nothing.
inline std::uint8_t stepBetween(double before, double first, double second, double after,
                                double step_px) {
  const double change = second - first;
  const bool before_compared = before == before, after_compared = after == after;  // not NaN
  const bool differs_before = std::abs(change - (first - before)) > step_px;
  const bool differs_after = std::abs(change - (after - second)) > step_px;
  return (before_compared | after_compared) & (!before_compared | differs_before) &
         (!after_compared | differs_after);
}

}  // namespace

void MeasuredSurface::findSteps(double step_px) {
  steps_.assign(cells_.size(), 0);
  if (!(step_px > 0) || rows_ < 2) return;
  const int rows = rows_;
  const std::vector<float> missing_row(columns_, kNoSurface);
  auto row = [&](int j) { return j >= 0 && j < rows ? &cells_[linear(0, j)] : missing_row.data(); };
  // Each cell (i, j) in one pass over its row: the edges along its two rows and its two columns,
  // each row's edges found for both cells they border.
  forEachRow(rows - 1, [&](int j) {
    // A local, not the member: the byte stores below may alias any memory, and a loop bound
    // re-read after every store does not vectorise.
    const int columns = columns_;
    std::vector<float> padded(columns + 3, kNoSurface);  // a row with a missing node each side
    std::vector<std::uint8_t> along_rows(2 * columns), along_columns(columns);
    for (int k = 0; k < 2; ++k) {
      std::copy(row(j + k), row(j + k) + columns, padded.begin() + 1);
      const float* line = padded.data();
      std::uint8_t* edges = along_rows.data() + k * columns;
      for (int i = 0; i + 1 < columns; ++i) {
        edges[i] = stepBetween(line[i], line[i + 1], line[i + 2], line[i + 3], step_px);
      }
    }
    const float *before = row(j - 1), *first = row(j), *second = row(j + 1), *after = row(j + 2);
    std::uint8_t* down = along_columns.data();
    for (int i = 0; i < columns; ++i) {
      down[i] = stepBetween(before[i], first[i], second[i], after[i], step_px);
    }
    const std::uint8_t *top = along_rows.data(), *bottom = top + columns;
    std::uint8_t* cell_steps = &steps_[linear(0, j)];
    for (int i = 0; i + 1 < columns; ++i) {
      const bool corners = (first[i] == first[i]) & (first[i + 1] == first[i + 1]) &
                           (second[i] == second[i]) & (second[i + 1] == second[i + 1]);
      cell_steps[i] = corners & (top[i] | bottom[i] | down[i] | down[i + 1]);
    }
  });
}

double MeasuredSurface::disparityAt(double u, double v) const {
  // Past the last grid column or row (the image's last pixels) the last two extrapolate.
  const double gu = u / step_, gv = v / step_;
  const int i0 = std::max(0, std::min(static_cast<int>(gu), columns_ - 2));
  const int j0 = std::max(0, std::min(static_cast<int>(gv), rows_ - 2));
  const int i1 = std::min(i0 + 1, columns_ - 1), j1 = std::min(j0 + 1, rows_ - 1);
  const double fu = i1 > i0 ? gu - i0 : 0.0, fv = j1 > j0 ? gv - j0 : 0.0;
  const double d00 = cellAt(i0, j0), d10 = cellAt(i1, j0);
  const double d01 = cellAt(i0, j1), d11 = cellAt(i1, j1);
  const int missing = std::isnan(d00) + std::isnan(d10) + std::isnan(d01) + std::isnan(d11);
  // Four corners: bilinear. Three: the plane through them, so that next to invalid pixels (the
  // range limit, a hole) a slanted surface is not read as its nearer corner's depth. Fewer: the
  // image does not say.
  if (missing == 0) {
    if (steps_[linear(i0, j0)]) return fv < 0.5 ? (fu < 0.5 ? d00 : d10) : (fu < 0.5 ? d01 : d11);
    return (1 - fv) * ((1 - fu) * d00 + fu * d10) + fv * ((1 - fu) * d01 + fu * d11);
  }
  if (missing > 1) return std::numeric_limits<double>::quiet_NaN();
  if (std::isnan(d11)) return d00 + (d10 - d00) * fu + (d01 - d00) * fv;
  if (std::isnan(d00)) return d11 + (d01 - d11) * (1 - fu) + (d10 - d11) * (1 - fv);
  if (std::isnan(d10)) return d01 + (d11 - d01) * fu + (d00 - d01) * (1 - fv);
  return d10 + (d00 - d10) * (1 - fu) + (d11 - d10) * fv;
}

double MeasuredSurface::nearestNodeWithin(double u, double v, double radius_px) const {
  // Rings of nodes about the nearest node, outwards, until a ring lies farther than the best
  // node found or than radius_px: the node nearest to (u, v) in the image.
  constexpr int kMaxRings = 64;  // a footprint of 64 nodes' radius needs no finer answer
  if (!(radius_px > 0)) return kNoSurface;
  const double gu = u / step_, gv = v / step_, radius = radius_px / step_;
  const int ci = static_cast<int>(std::lround(gu)), cj = static_cast<int>(std::lround(gv));
  double best_squared = radius * radius;
  float best = kNoSurface;
  const int rings = std::min(kMaxRings, static_cast<int>(std::ceil(radius)) + 1);
  for (int ring = 0; ring <= rings; ++ring) {
    // A node of this ring lies at least ring - 0.5 nodes from (u, v) along an axis.
    const double nearest = ring - 0.5;
    if (nearest > 0 && nearest * nearest > best_squared) break;
    for (int j = cj - ring; j <= cj + ring; ++j) {
      if (j < 0 || j >= rows_) continue;
      const bool edge_row = j == cj - ring || j == cj + ring;
      for (int i = ci - ring; i <= ci + ring; i += edge_row ? 1 : 2 * ring) {
        if (i < 0 || i >= columns_) continue;
        const float node = cellAt(i, j);
        if (std::isnan(node)) continue;
        const double squared = (i - gu) * (i - gu) + (j - gv) * (j - gv);
        if (squared < best_squared) {
          best_squared = squared;
          best = node;
        }
      }
    }
  }
  return best;
}

bool MeasuredSurface::depthAt(const Eigen::Vector3d& point_in_map, double* z, double* z_surface,
                              double reach_m) const {
  if (empty()) return false;
  const Eigen::Vector3d p = T_camera_map_ * point_in_map;
  if (!(p.z() > 0)) return false;
  const double u = fx_ * p.x() / p.z() + cx_, v = fy_ * p.y() / p.z() + cy_;
  const double reach_u = fx_ * reach_m / p.z(), reach_v = fy_ * reach_m / p.z();
  if (!(u >= -reach_u && v >= -reach_v && u <= width_ - 1 + reach_u &&
        v <= height_ - 1 + reach_v)) {
    return false;
  }
  const double inside_u = std::clamp(u, 0.0, width_ - 1.0);
  const double inside_v = std::clamp(v, 0.0, height_ - 1.0);
  double d = disparityAt(inside_u, inside_v);
  if (!(d > 0)) d = nearestNodeWithin(inside_u, inside_v, std::max(reach_u, reach_v));
  if (!(d > 0)) return false;
  *z = p.z();
  *z_surface = focal_baseline_ / d;
  return true;
}

}  // namespace occupancy_fusion
