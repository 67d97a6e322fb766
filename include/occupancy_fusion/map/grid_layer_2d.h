// Sparse, tile-allocated 2D log-odds grid with an explicit unknown state: the 2D counterpart of
// VoxelMap, written by the laser integrator and read by the fused 2D view.
#pragma once

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <shared_mutex>
#include <utility>
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
  // Bytes of tiles in memory; beyond it, with a TileStore (setTileStore), the tiles farthest from
  // the last write leave memory for the store (down to 90 % of it) and come back when written.
  // 0, or no store: no bound.
  std::size_t max_memory_bytes = 0;

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

// Where a layer's tiles go beyond its memory bound (map_checkpoints.h: the map's spill store).
class TileStore {
 public:
  virtual ~TileStore() = default;
  // Writes the tiles in one transaction; false: the store failed and none was written.
  virtual bool put(const std::vector<std::pair<std::uint64_t, const GridTile*>>& tiles) = 0;
  // A tile written before, by its packKey; false: missing or unreadable.
  virtual bool get(std::uint64_t key, GridTile* out) const = 0;
};

// The layer's tiles outside memory, for diagnostics.
struct TileSpillStatus {
  bool enabled = false;           // a bound and a store
  std::size_t spilled_tiles = 0;  // held by the store alone now
  std::size_t tiles_written = 0;  // to the store, since construction
  std::size_t tiles_paged_in = 0;
  std::size_t failures = 0;  // puts that failed (the tiles stayed in memory), reads that failed
                             // (the tile read as unknown)
};

using TileWriteWatcher = CellsWriteWatcher<TileIndex, GridTile>;

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
  float thresholdLogOdds() const { return threshold_log_odds_; }
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
  // The store for tiles beyond config().max_memory_bytes. Every read (point queries, forEach*,
  // copyTile, window, counts) then gives what the layer without the bound gives, reading a
  // stored tile from the store; a write brings it back into memory. Spilling is not a change
  // (changesSince). A store that fails keeps the tiles in memory (nothing is lost; the bound is
  // exceeded) and is counted in spillStatus().
  void setTileStore(std::unique_ptr<TileStore> store);
  TileSpillStatus spillStatus() const;
  // For a checkpoint with the map: `tile` gets every tile written since `version` (all of them
  // when the change log no longer reaches back: full_rebuild), wherever it is, then `commit`
  // runs with the changes, all under the layer's shared lock, so that no write (and no tile
  // leaving memory) comes between them. Returns the changes (their version for the next call).
  using TileFn = std::function<void(const TileIndex&, const GridTile&)>;
  GridChanges visitChangedTiles(std::uint64_t version, const TileFn& tile,
                                const std::function<void(const GridChanges&)>& commit) const;
  // As VoxelMap::clearBox: every known cell whose centre lies in [min, max] becomes free at the
  // lower clamping bound. Returns the number of cells changed.
  std::size_t clearBox(const Eigen::Vector2d& min, const Eigen::Vector2d& max);
  void reset();
  // As VoxelMap's: the watcher of every later write call, and whole tiles rewritten unseen by it
  // (a tile left without known cells stays, all unknown).
  using TileReader = std::function<bool(const TileIndex&, GridTile*)>;
  void setWriteWatcher(TileWriteWatcher* watcher,
                       const std::function<void(const TileReader&)>& on_switch = {});
  void rewriteTiles(const std::vector<TileIndex>& tiles,
                    const std::function<void(const TileIndex&, GridTile&)>& fn);

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
  std::size_t tileCount() const;  // in memory and stored
  std::size_t knownCellCount() const;
  std::size_t memoryBytes() const;  // tiles, hash table, change log and the stored tiles' index

 private:
  using TileTable = SpatialKeyMap<std::unique_ptr<GridTile>>;  // keyed by packKey(tile)

  GridTile& tileForWrite(const TileIndex& tile);  // allocates, logs; caller holds unique lock
  const GridTile* findTile(const TileIndex& tile) const;  // in memory only
  // In memory, or read from the store into *scratch; nullptr when the layer has no such tile.
  const GridTile* readTile(std::uint64_t key, GridTile* scratch) const;
  // Calls fn for every tile, those in memory first, then the stored ones one at a time.
  void forEachTileLocked(const TileFn& fn) const;
  void enforceBound();  // caller holds the unique lock
  GridChanges changesSinceLocked(std::uint64_t version) const;
  void markWritten(std::uint64_t key, GridTile* tile);
  void watch(std::uint64_t key, const GridTile* tile);  // the write watcher's first sight
  void finishWrite();                                   // trims the change log, bumps the version
  // Calls write_cell(tile, linear index in tile, value) for each non-NaN value of a dense window
  // (LogOddsRaster's layout), allocating tiles as needed. Caller holds the unique lock.
  template <typename WriteCell>
  void forEachWindowValue(const CellIndex& origin_cell, int width, int height, const float* values,
                          WriteCell write_cell);
  std::optional<CellBox> knownBoundsLocked() const;
  std::vector<float> windowLocked(const CellIndex& origin_cell, int width, int height) const;

  GridLayer2DConfig config_;
  TileWriteWatcher* watcher_ = nullptr;
  std::uint64_t watch_since_ = 0;  // the version the watcher was set at
  bool rewriting_ = false;         // rewriteTiles: its writes are not the watcher's
  float min_log_odds_;
  float max_log_odds_;
  float threshold_log_odds_;

  mutable std::shared_mutex mutex_;
  TileTable tiles_;
  std::uint64_t version_ = 1;
  BlockChangeLog change_log_;
  std::unique_ptr<TileStore> store_;
  SpatialKeyMap<int> stored_;            // tiles held by the store alone: their known cells
  CellIndex focus_ = CellIndex::Zero();  // the last write's centre: eviction keeps what is near
  std::size_t tiles_written_ = 0, tiles_paged_in_ = 0;
  mutable std::atomic<std::size_t> store_failures_{0};
};

}  // namespace occupancy_fusion
