// Yguel et al. 2006, Sec. III-IV: changing a scan's polar log-ratio grid (the
// Z-grid) into a cartesian grid, four ways. Every method adds into a
// LogOddsRaster: a cell that receives information gets raster + delta (NaN
// counts as 0), a cell that receives none is left as it is, so several scanners
// fuse by summing their log-ratios (Eq. 1-2, 8) simply by projecting each into
// the same raster through its own pose.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <list>
#include <memory>
#include <string>
#include <vector>

#include "occupancy_fusion/integrators/laser/laser_sensor_model.h"
#include "occupancy_fusion/map/grid_layer_2d.h"

namespace occupancy_fusion {

// The sensor's pose in the raster's frame: position (m) and heading (rad,
// counter-clockwise from +x) of the scan plane's x axis. The scanner must look
// up (its z axis along the frame's z).
struct Pose2D {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
};

enum class PolarToCartesianMethod {
  kExact,     // Eq. 5 / Algorithm 1: area-weighted overlay, precomputed per
              // geometry
  kSampling,  // Eq. 6: adaptive sampling, ns = dx^2 / (rho d_rho d_theta)
              // samples per cell
  kMipmap,    // Sec. IV: per-cell mipmapped lookup (the paper's GPU method),
              // OpenMP
  kLines,     // Bresenham line drawing, the baseline with the Moire effect
};

const char* methodName(PolarToCartesianMethod method);  // "exact", "sampling", "mipmap", "lines"
// Parses the names above; throws std::invalid_argument otherwise.
PolarToCartesianMethod parsePolarToCartesianMethod(const std::string& name);

// atan2 to within 1e-5 rad (a polynomial in min/max ratio), several times
// faster than std::atan2; the per-cell methods call it once per cell or sample.
double fastAtan2(double y, double x);

// --- which raster cells a scan can reach
// Per square tile of the raster (kSide x kSide cells), whether any observed polar cell can reach
// it: the tile's nearest distance to the sensor against the farthest observed range of the beams
// its angular span covers (widened by a margin for the filters of sampling and mipmap). Cells in
// the other tiles get nothing from any method, so the per-cell methods skip them whole: a scan
// indoors observes a few percent of a 60 m x 30 m grid.
class ReachableTiles {
 public:
  static constexpr int kSide = 16;
  // Tiles nearer to the sensor than always_within (m) count as reachable whatever was observed
  // (the mipmap's safety radius writes its worst case there).
  ReachableTiles(const PolarField& field, const Pose2D& sensor, const LogOddsRaster& raster,
                 double always_within = 0.0);

  int columns() const { return columns_; }
  int rows() const { return rows_; }
  bool reachable(int column, int row) const {
    return reachable_[static_cast<std::size_t>(column + columns_ * row)] != 0;
  }
  // The reachable tiles, row by row: index = column + columns() * row.
  const std::vector<int>& tiles() const { return tiles_; }

 private:
  int columns_ = 0;
  int rows_ = 0;
  std::vector<std::uint8_t> reachable_;
  std::vector<int> tiles_;
};

// --- lines
// ---------------------------------------------------------------------------------
// For each beam, the cells that a Bresenham line from the sensor's cell to the
// end of the beam's observed cells visits get the log-ratio of the range cell
// at their centre's distance. A cell crossed by several beams (near the sensor)
// is updated once per beam; cells between beams (far from the sensor) get
// nothing: the Moire effect.
void projectLines(const PolarField& field, const Pose2D& sensor, LogOddsRaster* raster);

// --- adaptive sampling
// --------------------------------------------------------------------- Each
// cell is sampled on a k x k lattice, k = ceil(sqrt(ns)) with ns of Eq. 6 at
// the cell centre's range (at least 1, at most max_samples_per_axis); each
// sample takes the log-ratio of the polar cell it falls in (0 outside the field
// of view or the observed range), and the cell gets their mean. Cells with no
// observed sample get nothing.
void projectSampling(const PolarField& field, const Pose2D& sensor, int max_samples_per_axis,
                     LogOddsRaster* raster);

// --- mipmap (Sec. IV, V-A)
// ----------------------------------------------------------------- The polar
// field as a texture pyramid: level (a, r) averages 2^a beams by 2^r range
// cells (a "rip-map": the two axes have separate levels, because a cartesian
// cell near the sensor spans many beams but only about dx / d_rho range cells).
// Per cell: its centre's polar coordinates, the level from its footprint (dx /
// (rho d_theta) beams by dx / d_rho cells, log2, fractional), and a bilinear
// lookup in the two neighbouring levels of each axis blended by the fraction
// (the GPU's trilinear filtering). Within safety_radius of the sensor every
// cell in the field of view takes the worst case: the largest log-ratio
// observed by any beam within that radius.
struct MipmapConfig {
  double safety_radius = 0.3;  // m (the paper's 30 cm)

  void validate() const;  // throws std::invalid_argument naming the bad field
};

class PolarMipmap {
 public:
  // Builds the levels needed for cells of size cell_size (m).
  PolarMipmap(const PolarField& field, double cell_size);

  int angleLevels() const { return angle_levels_; }
  // Bilinear lookup at level (a, r) at base coordinates u (beams: beam b spans
  // [b, b + 1)) and v (cells: cell k spans [k, k + 1)). Returns {value,
  // observed fraction}.
  void lookup(int angle_level, int range_level, double u, double v, float* value,
              float* observed) const;
  bool hasRangeLevel(int range_level) const;

 private:
  struct Level {
    int beams = 0;
    int cells = 0;
    std::vector<float> value;
    std::vector<float> observed;
  };
  const Level& level(int angle_level, int range_level) const;

  int angle_levels_ = 0;
  int first_range_level_ = 0;
  int range_levels_ = 0;       // number of range levels kept, from first_range_level_
  std::vector<Level> levels_;  // [range level - first][angle level]
};

void projectMipmap(const PolarField& field, const Pose2D& sensor, const MipmapConfig& config,
                   LogOddsRaster* raster);

// --- exact overlay (Eq. 5, Algorithm 1)
// ----------------------------------------------------- The polar mesh's convex
// approximation: polar cell (b, k) is the quadrilateral through its four
// corners (radii k d_rho and (k + 1) d_rho, angles theta_b +- d_theta / 2);
// neighbouring cells share corners, so the quads tile the field of view as the
// annular sectors do. Each quad is cut along the raster's column lines into
// strips and each strip along its row lines into pieces (the faces of the
// overlay); a piece's area over the cell's area is s_{i,r} of Eq. 5.
struct OverlayGeometry {
  int beams = 0;
  int cells = 0;
  double range_resolution = 0.0;
  double angle_min = 0.0;
  double angle_increment = 0.0;
  Pose2D sensor;
  double resolution = 0.0;
  CellIndex origin_cell = CellIndex::Zero();
  int width = 0;
  int height = 0;

  bool operator==(const OverlayGeometry& other) const;
  static OverlayGeometry of(const PolarField& field, const Pose2D& sensor,
                            const LogOddsRaster& raster);
};

class ExactOverlay {
 public:
  explicit ExactOverlay(const OverlayGeometry& geometry);  // computes the overlay

  const OverlayGeometry& geometry() const { return geometry_; }
  // Adds g(r) = sum_i s_{i,r} f(i) (Eq. 5) into every cell some observed polar
  // cell overlaps. The field and raster must match geometry() (throws
  // std::invalid_argument otherwise).
  void apply(const PolarField& field, LogOddsRaster* raster) const;

  // The overlay itself: for raster cell `cell` (x + width * y), the polar cells
  // (beam * cells + range cell) that overlap it and the overlapped fraction of
  // the raster cell's area.
  struct Entry {
    std::int32_t polar_index;
    float weight;
  };
  const Entry* entriesBegin(int cell) const { return entries_.data() + cell_start_[cell]; }
  const Entry* entriesEnd(int cell) const { return entries_.data() + cell_start_[cell + 1]; }
  std::size_t entryCount() const { return entries_.size(); }

 private:
  // Per block of kBlock x kBlock raster cells, the beams its entries span and their nearest range
  // cell: the block can only take a value if some beam in [first_beam, last_beam] observed past
  // nearest_cell. Many blocks of the reachable tiles lie behind what the scan hit; skipping them
  // saves streaming their entries, which do not fit in any cache. Blocks keep this table small
  // (16 times fewer records than cells), so reading it costs little.
  static constexpr int kBlock = 4;  // divides ReachableTiles::kSide
  struct BlockReach {
    std::int32_t nearest_cell = std::numeric_limits<std::int32_t>::max();
    std::int32_t first_beam = std::numeric_limits<std::int32_t>::max();
    std::int32_t last_beam = -1;
  };
  static inline bool mayBeObserved(const BlockReach& reach, const int* observed_cells);
  int blockColumns() const { return (geometry_.width + kBlock - 1) / kBlock; }
  void gatherBlock(int block_x, int block_y, const PolarField& field, LogOddsRaster* raster) const;

  OverlayGeometry geometry_;
  std::vector<std::int64_t> cell_start_;  // width * height + 1 offsets into entries_
  std::vector<Entry> entries_;
  std::vector<BlockReach> block_reach_;  // blockColumns() x ceil(height / kBlock), row-major
};

// Keeps the overlays of the last `capacity` geometries (least recently used
// goes first), so a fixed sensor-to-grid geometry, as in the vehicle grid,
// computes its overlay once.
class ExactOverlayCache {
 public:
  explicit ExactOverlayCache(std::size_t capacity = 4);
  const ExactOverlay& get(const OverlayGeometry& geometry);
  std::size_t size() const { return overlays_.size(); }
  std::size_t builds() const { return builds_; }  // overlays computed so far

 private:
  std::size_t capacity_;
  std::size_t builds_ = 0;
  std::list<std::unique_ptr<ExactOverlay>> overlays_;  // most recently used first
};

}  // namespace occupancy_fusion
