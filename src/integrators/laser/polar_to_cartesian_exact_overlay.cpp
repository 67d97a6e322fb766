// Eq. 5 / Algorithm 1: the map overlay of the polar mesh's convex approximation
// with the raster.
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include <omp.h>

#include "occupancy_fusion/integrators/laser/polar_to_cartesian.h"

namespace occupancy_fusion {

namespace {

// A convex polygon small enough to live on the stack: a quad cut by two pairs
// of parallel lines has at most 8 corners.
struct ConvexPolygon {
  std::array<double, 16> x{};
  std::array<double, 16> y{};
  int size = 0;

  void push(double px, double py) {
    x[static_cast<std::size_t>(size)] = px;
    y[static_cast<std::size_t>(size)] = py;
    ++size;
  }
  double coordinate(int axis, int i) const {
    return axis == 0 ? x[static_cast<std::size_t>(i)] : y[static_cast<std::size_t>(i)];
  }
  double area() const {  // shoelace
    double twice = 0.0;
    for (int i = 0; i < size; ++i) {
      const int j = i + 1 == size ? 0 : i + 1;
      twice += x[static_cast<std::size_t>(i)] * y[static_cast<std::size_t>(j)] -
               x[static_cast<std::size_t>(j)] * y[static_cast<std::size_t>(i)];
    }
    return 0.5 * std::abs(twice);
  }
};

// Cuts a convex polygon along the line {axis coordinate = c} into the part
// below and above it.
void cut(const ConvexPolygon& in, int axis, double c, ConvexPolygon* below, ConvexPolygon* above) {
  below->size = 0;
  above->size = 0;
  for (int i = 0; i < in.size; ++i) {
    const int j = i + 1 == in.size ? 0 : i + 1;
    const double xi = in.x[static_cast<std::size_t>(i)];
    const double yi = in.y[static_cast<std::size_t>(i)];
    const double di = in.coordinate(axis, i) - c;
    const double dj = in.coordinate(axis, j) - c;
    if (di <= 0.0) below->push(xi, yi);
    if (di >= 0.0) above->push(xi, yi);
    if ((di < 0.0 && dj > 0.0) || (di > 0.0 && dj < 0.0)) {
      const double t = di / (di - dj);
      double px = xi + t * (in.x[static_cast<std::size_t>(j)] - xi);
      double py = yi + t * (in.y[static_cast<std::size_t>(j)] - yi);
      (axis == 0 ? px : py) = c;  // exactly on the line
      below->push(px, py);
      above->push(px, py);
    }
  }
}

double minOf(const ConvexPolygon& p, int axis) {
  double m = p.coordinate(axis, 0);
  for (int i = 1; i < p.size; ++i) m = std::min(m, p.coordinate(axis, i));
  return m;
}
double maxOf(const ConvexPolygon& p, int axis) {
  double m = p.coordinate(axis, 0);
  for (int i = 1; i < p.size; ++i) m = std::max(m, p.coordinate(axis, i));
  return m;
}

struct Piece {
  std::int32_t cell;
  std::int32_t polar_index;
  float weight;
};

constexpr double kNegligibleArea = 1e-12;  // in cell areas: pieces of a vertex or an edge

// Cuts `polygon` (in cell units) into its parts inside cells [0, count) along
// `axis`; calls emit(index, part) for each part with a positive area.
template <typename Emit>
void slice(const ConvexPolygon& polygon, int axis, int count, Emit&& emit) {
  const int first = std::max(0, static_cast<int>(std::floor(minOf(polygon, axis))));
  const int last = std::min(count - 1, static_cast<int>(std::floor(maxOf(polygon, axis))));
  if (first > last) return;
  ConvexPolygon rest = polygon;
  ConvexPolygon below;
  ConvexPolygon above;
  if (first > 0 || minOf(polygon, axis) < 0.0) {
    cut(rest, axis, first, &below, &above);
    rest = above;
  }
  for (int i = first; i <= last && rest.size >= 3; ++i) {
    cut(rest, axis, i + 1, &below, &above);
    if (below.size >= 3) emit(i, below);
    rest = above;
  }
}

// Algorithm 1, lines 3-7, for one polar cell: the faces of the overlay inside
// it.
void overlayQuad(const ConvexPolygon& quad, std::int32_t polar_index, const OverlayGeometry& g,
                 std::vector<Piece>* pieces) {
  slice(quad, 0, g.width, [&](int column, const ConvexPolygon& strip) {
    slice(strip, 1, g.height, [&](int row, const ConvexPolygon& face) {
      const double area = face.area();  // the cell's area is 1 in cell units: s = area (line 6)
      if (area > kNegligibleArea) {
        pieces->push_back({column + g.width * row, polar_index, static_cast<float>(area)});
      }
    });
  });
}

}  // namespace

bool OverlayGeometry::operator==(const OverlayGeometry& o) const {
  return beams == o.beams && cells == o.cells && range_resolution == o.range_resolution &&
         angle_min == o.angle_min && angle_increment == o.angle_increment &&
         sensor.x == o.sensor.x && sensor.y == o.sensor.y && sensor.yaw == o.sensor.yaw &&
         resolution == o.resolution && origin_cell == o.origin_cell && width == o.width &&
         height == o.height;
}

OverlayGeometry OverlayGeometry::of(const PolarField& field, const Pose2D& sensor,
                                    const LogOddsRaster& raster) {
  OverlayGeometry g;
  g.beams = field.beams;
  g.cells = field.cells;
  g.range_resolution = field.range_resolution;
  g.angle_min = field.angle_min;
  g.angle_increment = field.angle_increment;
  g.sensor = sensor;
  g.resolution = raster.resolution;
  g.origin_cell = raster.origin_cell;
  g.width = raster.width;
  g.height = raster.height;
  return g;
}

ExactOverlay::ExactOverlay(const OverlayGeometry& g) : geometry_(g) {
  if (g.beams <= 0 || g.cells <= 0) throw std::invalid_argument("ExactOverlay: empty polar grid");
  if (!(g.angle_increment > 0.0 && g.angle_increment < 3.0)) {
    throw std::invalid_argument("ExactOverlay: angle_increment must be in (0, 3) rad");
  }
  if (!(g.resolution > 0.0) || g.width <= 0 || g.height <= 0) {
    throw std::invalid_argument("ExactOverlay: empty raster");
  }
  const int threads = omp_get_max_threads();
  std::vector<std::vector<Piece>> per_thread(static_cast<std::size_t>(threads));
  const double inverse = 1.0 / g.resolution;
  const double sx = g.sensor.x * inverse - g.origin_cell.x();
  const double sy = g.sensor.y * inverse - g.origin_cell.y();
  const double dr = g.range_resolution * inverse;

#pragma omp parallel for schedule(dynamic, 4)
  for (int b = 0; b < g.beams; ++b) {
    std::vector<Piece>& pieces = per_thread[static_cast<std::size_t>(omp_get_thread_num())];
    const double centre = g.sensor.yaw + g.angle_min + b * g.angle_increment;
    const double c0 = std::cos(centre - 0.5 * g.angle_increment);
    const double s0 = std::sin(centre - 0.5 * g.angle_increment);
    const double c1 = std::cos(centre + 0.5 * g.angle_increment);
    const double s1 = std::sin(centre + 0.5 * g.angle_increment);
    for (int k = 0; k < g.cells; ++k) {
      const double r0 = k * dr;
      const double r1 = (k + 1) * dr;
      ConvexPolygon quad;  // counter-clockwise
      quad.push(sx + r0 * c0, sy + r0 * s0);
      quad.push(sx + r1 * c0, sy + r1 * s0);
      quad.push(sx + r1 * c1, sy + r1 * s1);
      quad.push(sx + r0 * c1, sy + r0 * s1);
      overlayQuad(quad, b * g.cells + k, g, &pieces);
    }
  }

  // Group the faces by raster cell (counting sort), so apply() gathers per cell
  // in parallel.
  const std::size_t cell_count = static_cast<std::size_t>(g.width) * g.height;
  cell_start_.assign(cell_count + 1, 0);
  for (const auto& pieces : per_thread) {
    for (const Piece& p : pieces) ++cell_start_[static_cast<std::size_t>(p.cell) + 1];
  }
  for (std::size_t i = 0; i < cell_count; ++i) cell_start_[i + 1] += cell_start_[i];
  entries_.resize(static_cast<std::size_t>(cell_start_[cell_count]));
  std::vector<std::int64_t> next(cell_start_.begin(), cell_start_.end() - 1);
  const int block_rows = (g.height + kBlock - 1) / kBlock;
  block_reach_.assign(static_cast<std::size_t>(blockColumns()) * block_rows, BlockReach());
  for (const auto& pieces : per_thread) {
    for (const Piece& p : pieces) {
      entries_[static_cast<std::size_t>(next[static_cast<std::size_t>(p.cell)]++)] = {p.polar_index,
                                                                                      p.weight};
      const int block =
          (p.cell % g.width) / kBlock + blockColumns() * ((p.cell / g.width) / kBlock);
      BlockReach& reach = block_reach_[static_cast<std::size_t>(block)];
      const std::int32_t beam = p.polar_index / g.cells;
      reach.nearest_cell = std::min(reach.nearest_cell, p.polar_index - beam * g.cells);
      reach.first_beam = std::min(reach.first_beam, beam);
      reach.last_beam = std::max(reach.last_beam, beam);
    }
  }
}

// Conservative: a block holding an entry (b, k) with k < observed_cells[b] has b in the span and
// nearest_cell <= k, so it passes; near the sensor the first beam usually answers.
bool ExactOverlay::mayBeObserved(const BlockReach& reach, const int* observed_cells) {
  for (std::int32_t b = reach.first_beam; b <= reach.last_beam; ++b) {
    if (observed_cells[b] > reach.nearest_cell) return true;
  }
  return false;
}

void ExactOverlay::apply(const PolarField& field, LogOddsRaster* raster) const {
  const OverlayGeometry& g = geometry_;
  if (field.beams != g.beams || field.cells != g.cells ||
      field.range_resolution != g.range_resolution || field.angle_min != g.angle_min ||
      field.angle_increment != g.angle_increment) {
    throw std::invalid_argument("ExactOverlay::apply: the polar field differs from the overlay's");
  }
  if (raster->resolution != g.resolution || raster->origin_cell != g.origin_cell ||
      raster->width != g.width || raster->height != g.height) {
    throw std::invalid_argument("ExactOverlay::apply: the raster differs from the overlay's");
  }
  // Only the tiles some observed polar cell can reach are gathered: the overlay covers the whole
  // field of view, a scan indoors observes a small part of it.
  const ReachableTiles tiles(field, g.sensor, *raster);
  const std::vector<int>& list = tiles.tiles();
  const int count = static_cast<int>(list.size());
  const int* observed_cells = field.observed_cells.data();
  static_assert(ReachableTiles::kSide % kBlock == 0, "a tile holds whole blocks");
  constexpr int kBlocksPerTile = ReachableTiles::kSide / kBlock;
#pragma omp parallel for schedule(dynamic, 2)
  for (int i = 0; i < count; ++i) {
    const int column = list[static_cast<std::size_t>(i)] % tiles.columns();
    const int row = list[static_cast<std::size_t>(i)] / tiles.columns();
    const int bx_end = std::min(blockColumns(), (column + 1) * kBlocksPerTile);
    const int by_end = std::min((g.height + kBlock - 1) / kBlock, (row + 1) * kBlocksPerTile);
    for (int by = row * kBlocksPerTile; by < by_end; ++by) {
      for (int bx = column * kBlocksPerTile; bx < bx_end; ++bx) {
        const BlockReach& reach = block_reach_[static_cast<std::size_t>(bx + blockColumns() * by)];
        if (mayBeObserved(reach, observed_cells)) gatherBlock(bx, by, field, raster);
      }
    }
  }
}

// Eq. 5 over the cells of one block: g(r) = sum_i s_{i,r} f(i), written where some observed polar
// cell overlaps r.
void ExactOverlay::gatherBlock(int block_x, int block_y, const PolarField& field,
                               LogOddsRaster* raster) const {
  const OverlayGeometry& g = geometry_;
  const float* value = field.value.data();
  const float* observed = field.observed.data();
  const int x_end = std::min(g.width, (block_x + 1) * kBlock);
  const int y_end = std::min(g.height, (block_y + 1) * kBlock);
  for (int y = block_y * kBlock; y < y_end; ++y) {
    for (int x = block_x * kBlock; x < x_end; ++x) {
      const int cell = x + g.width * y;
      double sum = 0.0;
      float coverage = 0.0f;
      for (const Entry* e = entriesBegin(cell); e != entriesEnd(cell); ++e) {
        sum += static_cast<double>(e->weight) * value[e->polar_index];
        coverage += e->weight * observed[e->polar_index];
      }
      if (coverage > 0.0f) {
        float& target = raster->data[static_cast<std::size_t>(cell)];
        target = std::isnan(target) ? static_cast<float>(sum) : target + static_cast<float>(sum);
      }
    }
  }
}

ExactOverlayCache::ExactOverlayCache(std::size_t capacity) : capacity_(capacity) {
  if (capacity_ == 0) throw std::invalid_argument("ExactOverlayCache: capacity must be >= 1");
}

const ExactOverlay& ExactOverlayCache::get(const OverlayGeometry& geometry) {
  for (auto it = overlays_.begin(); it != overlays_.end(); ++it) {
    if ((*it)->geometry() == geometry) {
      overlays_.splice(overlays_.begin(), overlays_,
                       it);  // most recently used first
      return *overlays_.front();
    }
  }
  overlays_.push_front(std::make_unique<ExactOverlay>(geometry));
  ++builds_;
  if (overlays_.size() > capacity_) overlays_.pop_back();
  return *overlays_.front();
}

}  // namespace occupancy_fusion
