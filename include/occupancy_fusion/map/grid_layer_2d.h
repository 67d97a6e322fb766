// Sparse, tile-allocated 2D log-odds grid with an explicit unknown state: the 2D counterpart of
// VoxelMap, written by the laser integrator and read by the fused 2D view.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <shared_mutex>
#include <vector>

#include "occupancy_fusion/map/block_change_log.h"
#include "occupancy_fusion/map/log_odds_cells.h"
#include "occupancy_fusion/map/occupancy_model.h"
#include "occupancy_fusion/map/spatial_key.h"

namespace occupancy_fusion {

using CellIndex = Eigen::Vector2i;  // floor(p / resolution), per axis
using TileIndex = Eigen::Vector2i;  // floor(cell index / GridTile::kSide), per axis

// A dense square of kSide^2 cells. NaN log-odds marks a cell that was never observed; version is
// maintained by GridLayer2D.
struct GridTile : LogOddsCells<32 * 32> {
  static constexpr int kSideLog2 = 5;
  static constexpr int kSide = 1 << kSideLog2;
  static constexpr int kArea = kSide * kSide;
  static_assert(kArea == kCellCount, "kSide^2 cells");

  // x fastest, so a sweep along x walks memory in order.
  static int linearIndex(int x, int y) { return x + kSide * y; }
  static Eigen::Vector2i localIndex(int linear) {
    return {linear & (kSide - 1), linear >> kSideLog2};
  }
};

struct GridLayer2DConfig {
  double resolution = 0.05;  // m, edge of a cell
  OccupancyModel model;      // hit/miss/clamping, as the 3D map's

  void validate() const;  // throws std::invalid_argument naming the bad field
};

struct CellUpdate {
  CellIndex index;
  float delta;  // log-odds increment
};

// Tiles written or removed after a given layer version (same contract as MapChanges).
struct GridChanges {
  std::uint64_t version = 0;       // pass this to the next changesSince()
  bool full_rebuild = false;       // the log no longer reaches back: rebuild from scratch
  std::vector<TileIndex> changed;  // written since. Tiles are only removed by reset(), which
                                   // makes every older version a full rebuild.
};

// Inclusive range of cell indices.
struct CellBox {
  CellIndex min;
  CellIndex max;
  int width() const { return max.x() - min.x() + 1; }
  int height() const { return max.y() - min.y() + 1; }
};

// A dense window of log-odds, NaN = unknown. Row-major, row 0 is the lowest y (the origin's row),
// x fastest: data[x + width * y] is cell origin_cell + (x, y).
struct LogOddsRaster {
  double resolution = 0.0;
  CellIndex origin_cell = CellIndex::Zero();  // its corner is (origin_cell * resolution)
  int width = 0;
  int height = 0;
  std::vector<float> data;

  float at(int x, int y) const { return data[static_cast<std::size_t>(x + width * y)]; }
};

// Thread safety: as VoxelMap. Every public member function may be called from any thread; reads
// take a shared lock and writes an exclusive one held for the whole call, so one call (a scan's
// addRaster) is atomic for readers. Callbacks of forEach* run under the shared lock and must not
// call the layer's write functions.
class GridLayer2D {
 public:
  explicit GridLayer2D(const GridLayer2DConfig& config);  // validates config

  const GridLayer2DConfig& config() const { return config_; }
  double resolution() const { return config_.resolution; }
  const OccupancyModel& model() const { return config_.model; }
  float minLogOdds() const { return min_log_odds_; }
  float maxLogOdds() const { return max_log_odds_; }
  Occupancy classify(float log_odds) const {
    return log_odds > threshold_log_odds_ ? Occupancy::kOccupied : Occupancy::kFree;
  }

  // Coordinates. Indices are valid for |coordinate| < kMaxCoordinateCells * resolution.
  static constexpr int kMaxCoordinateCells = 1 << 30;
  CellIndex indexOf(const Eigen::Vector2d& point) const;
  Eigen::Vector2d centerOf(const CellIndex& index) const;
  bool isInRange(const Eigen::Vector2d& point) const;  // finite and representable
  static TileIndex tileOf(const CellIndex& index);
  static int linearIndexInTile(const CellIndex& index);
  static CellIndex cellIndex(const TileIndex& tile, int linear);

  // Point queries.
  std::optional<float> logOdds(const CellIndex& index) const;  // nullopt: unknown
  Occupancy occupancy(const CellIndex& index) const;
  Occupancy occupancyAt(const Eigen::Vector2d& point) const { return occupancy(indexOf(point)); }

  // Writes. Every increment is clamped to the model's [min, max].
  void updateCell(const CellIndex& index, float delta);
  void applyUpdates(const std::vector<CellUpdate>& updates);
  // Adds a dense window of increments, row-major from origin_cell (x fastest, row 0 = lowest y),
  // width * height values. A NaN increment means "no information": the cell is left as it is.
  void addRaster(const CellIndex& origin_cell, int width, int height, const float* log_odds_delta);
  void setLogOdds(const CellIndex& index, float log_odds);  // unclamped, for import
  // Sets every known (non-NaN) cell of the raster to its value, unclamped, in one write: what a
  // saved layer resumes with. The raster's unknown cells leave the layer's cells as they are.
  // Throws std::invalid_argument for another resolution or a data size not width x height.
  void importRaster(const LogOddsRaster& raster);
  // Replaces a whole tile's cells as they are (unclamped; NaN unknown): what a checkpoint resumes.
  void restoreTile(const TileIndex& tile, const GridTile& cells);
  // As VoxelMap::clearBox: every known cell whose centre lies in [min, max] becomes free at the
  // lower clamping bound. Returns the number of cells changed.
  std::size_t clearBox(const Eigen::Vector2d& min, const Eigen::Vector2d& max);
  void reset();

  // Iteration (under the shared lock). fn(cell index, log-odds).
  using CellFn = std::function<void(const CellIndex&, float)>;
  void forEachKnownCell(const CellFn& fn) const;
  void forEachTile(const std::function<void(const TileIndex&, const GridTile&)>& fn) const;
  bool copyTile(const TileIndex& tile, GridTile* out) const;  // false if not allocated
  // Dense copy of a window (layout of LogOddsRaster::data), NaN where unknown.
  std::vector<float> window(const CellIndex& origin_cell, int width, int height) const;
  std::optional<CellBox> knownBounds() const;  // nullopt when nothing is known
  LogOddsRaster toLogOddsRaster() const;       // over knownBounds(); empty when nothing is known

  // Change log for incremental consumers. Start with version 0 (a full rebuild).
  GridChanges changesSince(std::uint64_t version) const;
  std::uint64_t version() const;

  // Accounting.
  std::size_t tileCount() const;
  std::size_t knownCellCount() const;
  std::size_t memoryBytes() const;  // tiles, hash table and change log

 private:
  using TileTable = SpatialKeyMap<std::unique_ptr<GridTile>>;  // keyed by packKey(tile)

  GridTile& tileForWrite(const TileIndex& tile);  // allocates, logs; caller holds unique lock
  const GridTile* findTile(const TileIndex& tile) const;
  void markWritten(std::uint64_t key, GridTile* tile);
  void finishWrite();  // trims the change log, bumps the version
  // Calls write_cell(tile, linear index in tile, value) for each non-NaN value of a dense window
  // (LogOddsRaster's layout), allocating tiles as needed. Caller holds the unique lock.
  template <typename WriteCell>
  void forEachWindowValue(const CellIndex& origin_cell, int width, int height, const float* values,
                          WriteCell write_cell);
  std::optional<CellBox> knownBoundsLocked() const;
  std::vector<float> windowLocked(const CellIndex& origin_cell, int width, int height) const;

  GridLayer2DConfig config_;
  float min_log_odds_;
  float max_log_odds_;
  float threshold_log_odds_;

  mutable std::shared_mutex mutex_;
  TileTable tiles_;
  std::uint64_t version_ = 1;
  BlockChangeLog change_log_;
};

}  // namespace occupancy_fusion
