#include "occupancy_fusion/map/grid_layer_2d.h"

#include <algorithm>
#include <mutex>
#include <stdexcept>
#include <string>

namespace occupancy_fusion {
namespace {

// Approximate heap cost of one hash-table slot (key, pointer, robin-hood bookkeeping).
constexpr std::size_t kTableSlotBytes = 24;

}  // namespace

void GridLayer2DConfig::validate() const {
  if (!(resolution > 0.0) || !std::isfinite(resolution)) {
    throw std::invalid_argument("resolution must be a positive number of metres, got " +
                                std::to_string(resolution));
  }
  model.validate();
}

GridLayer2D::GridLayer2D(const GridLayer2DConfig& config) : config_(config) {
  config_.validate();
  min_log_odds_ = config_.model.minLogOdds();
  max_log_odds_ = config_.model.maxLogOdds();
  threshold_log_odds_ = config_.model.thresholdLogOdds();
}

CellIndex GridLayer2D::indexOf(const Eigen::Vector2d& point) const {
  return (point / config_.resolution).array().floor().cast<int>();
}

Eigen::Vector2d GridLayer2D::centerOf(const CellIndex& index) const {
  return (index.cast<double>().array() + 0.5) * config_.resolution;
}

bool GridLayer2D::isInRange(const Eigen::Vector2d& point) const {
  const double limit = kMaxCoordinateCells * config_.resolution;
  return point.allFinite() && (point.array().abs() < limit).all();
}

TileIndex GridLayer2D::tileOf(const CellIndex& index) {
  // Arithmetic shift floors negative indices too.
  return {index.x() >> GridTile::kSideLog2, index.y() >> GridTile::kSideLog2};
}

int GridLayer2D::linearIndexInTile(const CellIndex& index) {
  return GridTile::linearIndex(index.x() & (GridTile::kSide - 1),
                               index.y() & (GridTile::kSide - 1));
}

CellIndex GridLayer2D::cellIndex(const TileIndex& tile, int linear) {
  return tile * GridTile::kSide + GridTile::localIndex(linear);
}

const GridTile* GridLayer2D::findTile(const TileIndex& tile) const {
  const auto it = tiles_.find(packKey(tile));
  return it == tiles_.end() ? nullptr : it->second.get();
}

void GridLayer2D::markWritten(std::uint64_t key, GridTile* tile) {
  // One log entry per tile and write call: the tile's version says whether it has one.
  if (tile->version == version_) return;
  tile->version = version_;
  change_log_.recordChange(version_, key);
}

const GridTile* GridLayer2D::readTile(std::uint64_t key, GridTile* scratch) const {
  const auto it = tiles_.find(key);
  if (it != tiles_.end()) return it->second.get();
  if (stored_.find(key) == stored_.end()) return nullptr;
  if (store_->get(key, scratch)) return scratch;
  ++store_failures_;
  return nullptr;  // unreadable: unknown, as a tile the layer never had
}

void GridLayer2D::forEachTileLocked(const TileFn& fn) const {
  for (const auto& [key, tile] : tiles_) fn(unpackKey2(key), *tile);
  GridTile scratch;
  for (const auto& entry : stored_) {
    const GridTile* tile = readTile(entry.first, &scratch);
    if (tile != nullptr) fn(unpackKey2(entry.first), *tile);
  }
}

GridTile& GridLayer2D::tileForWrite(const TileIndex& tile) {
  const std::uint64_t key = packKey(tile);
  auto it = tiles_.find(key);
  if (it == tiles_.end()) {
    auto fresh = std::make_unique<GridTile>();
    const auto stored = stored_.find(key);
    if (stored != stored_.end()) {
      stored_.erase(stored);
      if (store_->get(key, fresh.get())) {
        ++tiles_paged_in_;
      } else {
        ++store_failures_;
        *fresh = GridTile();
      }
    }
    it = tiles_.emplace(key, std::move(fresh)).first;
  }
  GridTile* found = it->second.get();
  watch(key, found);
  markWritten(key, found);
  return *found;
}

void GridLayer2D::watch(std::uint64_t key, const GridTile* tile) {
  // A tile written since the watcher was set has been seen; a paged-in one (version 0) is seen
  // again, and the watcher keeps its first sight.
  if (watcher_ == nullptr || rewriting_ || tile->version >= watch_since_) return;
  watcher_->beforeFirstWrite(unpackKey2(key), tile->known_count > 0 ? tile : nullptr);
}

void GridLayer2D::setWriteWatcher(TileWriteWatcher* watcher,
                                  const std::function<void(const TileReader&)>& on_switch) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  if (on_switch) {
    on_switch([this](const TileIndex& tile, GridTile* out) {
      const GridTile* found = readTile(packKey(tile), out);
      if (found == nullptr) return false;
      if (found != out) *out = *found;
      return true;
    });
  }
  watcher_ = watcher;
  // The next write call stamps its tiles with version_, every earlier one with less.
  watch_since_ = version_;
}

void GridLayer2D::rewriteTiles(const std::vector<TileIndex>& tiles,
                               const std::function<void(const TileIndex&, GridTile&)>& fn) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  rewriting_ = true;
  GridTile scratch;
  for (const TileIndex& tile_index : tiles) {
    const std::uint64_t key = packKey(tile_index);
    const GridTile* current = readTile(key, &scratch);
    if (current == nullptr) {
      scratch = GridTile();
    } else if (current != &scratch) {
      scratch = *current;
    }
    fn(tile_index, scratch);
    // A tile left without known cells stays, unknown: the layer's consumers only hear of changed
    // tiles (GridChanges).
    if (scratch.known_count == 0 && current == nullptr) continue;
    GridTile& target = tileForWrite(tile_index);
    target.log_odds = scratch.log_odds;
    target.known_count = scratch.known_count;
    target.version = 0;  // unwatched: the watcher's next sight is a sensor's write
  }
  rewriting_ = false;
  finishWrite();
}

void GridLayer2D::finishWrite() {
  change_log_.finishWrite();
  ++version_;
  enforceBound();
}

void GridLayer2D::enforceBound() {
  const std::size_t bound = config_.max_memory_bytes;
  if (store_ == nullptr || bound == 0 || tiles_.size() * sizeof(GridTile) <= bound) return;
  // Down to 90 % of the bound, so that the next writes do not spill at once again; the tiles
  // farthest from the last write first.
  const std::size_t keep = bound / 10 * 9 / sizeof(GridTile);
  std::vector<std::pair<std::int64_t, std::uint64_t>> by_distance;
  by_distance.reserve(tiles_.size());
  const TileIndex focus = tileOf(focus_);
  for (const auto& entry : tiles_) {
    const Eigen::Matrix<std::int64_t, 2, 1> offset =
        (unpackKey2(entry.first) - focus).cast<std::int64_t>();
    by_distance.emplace_back(offset.squaredNorm(), entry.first);
  }
  const std::size_t leaving = tiles_.size() - std::min(keep, tiles_.size());
  std::nth_element(by_distance.begin(), by_distance.begin() + leaving, by_distance.end(),
                   [](const auto& a, const auto& b) { return a > b; });
  std::vector<std::pair<std::uint64_t, const GridTile*>> out;
  out.reserve(leaving);
  for (std::size_t i = 0; i < leaving; ++i) {
    const std::uint64_t key = by_distance[i].second;
    out.emplace_back(key, tiles_.find(key)->second.get());
  }
  if (!store_->put(out)) {
    ++store_failures_;  // the tiles stay: nothing is lost, the bound is exceeded
    return;
  }
  for (const auto& [key, tile] : out) {
    stored_[key] = tile->known_count;
    tiles_.erase(key);
  }
  tiles_written_ += out.size();
}

void GridLayer2D::setTileStore(std::unique_ptr<TileStore> store) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  store_ = std::move(store);
  enforceBound();
}

TileSpillStatus GridLayer2D::spillStatus() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  TileSpillStatus status;
  status.enabled = store_ != nullptr && config_.max_memory_bytes > 0;
  status.spilled_tiles = stored_.size();
  status.tiles_written = tiles_written_;
  status.tiles_paged_in = tiles_paged_in_;
  status.failures = store_failures_;
  return status;
}

GridChanges GridLayer2D::visitChangedTiles(
    std::uint64_t version, const TileFn& tile,
    const std::function<void(const GridChanges&)>& commit) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  const GridChanges changes = changesSinceLocked(version);
  if (changes.full_rebuild) {
    forEachTileLocked(tile);
  } else {
    GridTile scratch;
    for (const TileIndex& index : changes.changed) {
      const GridTile* found = readTile(packKey(index), &scratch);
      if (found != nullptr) tile(index, *found);
    }
  }
  commit(changes);
  return changes;
}

std::optional<float> GridLayer2D::logOdds(const CellIndex& index) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  GridTile scratch;
  const GridTile* tile = readTile(packKey(tileOf(index)), &scratch);
  if (tile == nullptr) return std::nullopt;
  const float value = tile->log_odds[linearIndexInTile(index)];
  if (!GridTile::isKnown(value)) return std::nullopt;
  return value;
}

Occupancy GridLayer2D::occupancy(const CellIndex& index) const {
  const std::optional<float> value = logOdds(index);
  return value ? classify(*value) : Occupancy::kUnknown;
}

void GridLayer2D::updateCell(const CellIndex& index, float delta) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  focus_ = index;
  tileForWrite(tileOf(index)).update(linearIndexInTile(index), delta, min_log_odds_, max_log_odds_);
  finishWrite();
}

void GridLayer2D::applyUpdates(const std::vector<CellUpdate>& updates) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  TileIndex last_tile(0, 0);
  GridTile* tile = nullptr;
  for (const CellUpdate& update : updates) {
    const TileIndex tile_index = tileOf(update.index);
    if (tile == nullptr || tile_index != last_tile) {
      tile = &tileForWrite(tile_index);
      last_tile = tile_index;
    }
    tile->update(linearIndexInTile(update.index), update.delta, min_log_odds_, max_log_odds_);
  }
  if (!updates.empty()) focus_ = updates.back().index;
  finishWrite();
}

void GridLayer2D::addRaster(const CellIndex& origin_cell, int width, int height,
                            const float* log_odds_delta) {
  if (width < 0 || height < 0) {
    throw std::invalid_argument("GridLayer2D::addRaster: negative window size");
  }
  std::unique_lock<std::shared_mutex> lock(mutex_);
  focus_ = origin_cell + CellIndex(width / 2, height / 2);
  forEachWindowValue(origin_cell, width, height, log_odds_delta,
                     [this](GridTile* tile, int linear, float delta) {
                       tile->update(linear, delta, min_log_odds_, max_log_odds_);
                     });
  finishWrite();
}

void GridLayer2D::restoreTile(const TileIndex& tile, const GridTile& cells) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  GridTile& target = tileForWrite(tile);
  for (int linear = 0; linear < GridTile::kArea; ++linear) {
    target.set(linear, cells.log_odds[linear]);
  }
  finishWrite();
}

void GridLayer2D::importRaster(const LogOddsRaster& raster) {
  if (std::abs(raster.resolution - config_.resolution) > 1e-9 * config_.resolution) {
    throw std::invalid_argument("GridLayer2D::importRaster: the raster's resolution " +
                                std::to_string(raster.resolution) + " m differs from the layer's " +
                                std::to_string(config_.resolution) + " m");
  }
  if (raster.width < 0 || raster.height < 0 ||
      raster.data.size() != static_cast<std::size_t>(raster.width) * raster.height) {
    throw std::invalid_argument("GridLayer2D::importRaster: data size does not match the window");
  }
  std::unique_lock<std::shared_mutex> lock(mutex_);
  focus_ = raster.origin_cell + CellIndex(raster.width / 2, raster.height / 2);
  forEachWindowValue(raster.origin_cell, raster.width, raster.height, raster.data.data(),
                     [](GridTile* tile, int linear, float value) { tile->set(linear, value); });
  finishWrite();
}

template <typename WriteCell>
void GridLayer2D::forEachWindowValue(const CellIndex& origin_cell, int width, int height,
                                     const float* values, WriteCell write_cell) {
  if (width == 0 || height == 0) return;
  // Walk the window tile by tile, so each tile is looked up once.
  const CellIndex end = origin_cell + CellIndex(width, height);
  const TileIndex first_tile = tileOf(origin_cell);
  const TileIndex last_tile = tileOf(end - CellIndex::Ones());
  for (int ty = first_tile.y(); ty <= last_tile.y(); ++ty) {
    for (int tx = first_tile.x(); tx <= last_tile.x(); ++tx) {
      const CellIndex tile_min = TileIndex(tx, ty) * GridTile::kSide;
      const CellIndex lo = tile_min.cwiseMax(origin_cell);
      const CellIndex hi = (tile_min + CellIndex::Constant(GridTile::kSide)).cwiseMin(end);
      GridTile* tile = nullptr;
      for (int y = lo.y(); y < hi.y(); ++y) {
        const float* row = values + static_cast<std::size_t>(y - origin_cell.y()) * width;
        for (int x = lo.x(); x < hi.x(); ++x) {
          const float value = row[x - origin_cell.x()];
          if (std::isnan(value)) continue;
          if (tile == nullptr) tile = &tileForWrite({tx, ty});
          write_cell(tile, linearIndexInTile({x, y}), value);
        }
      }
    }
  }
}

void GridLayer2D::setLogOdds(const CellIndex& index, float log_odds) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  focus_ = index;
  tileForWrite(tileOf(index)).set(linearIndexInTile(index), log_odds);
  finishWrite();
}

std::size_t GridLayer2D::clearBox(const Eigen::Vector2d& min, const Eigen::Vector2d& max) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  const TileIndex tile_lo = tileOf(indexOf(min));
  const TileIndex tile_hi = tileOf(indexOf(max));
  auto in_range = [&](const TileIndex& tile) {
    return (tile.array() >= tile_lo.array()).all() && (tile.array() <= tile_hi.array()).all();
  };
  std::vector<TileIndex> stored_in_range;
  for (const auto& entry : stored_) {
    if (in_range(unpackKey2(entry.first))) stored_in_range.push_back(unpackKey2(entry.first));
  }
  for (const TileIndex& tile : stored_in_range) tileForWrite(tile);  // back into memory
  focus_ = indexOf(0.5 * (min + max));
  std::size_t changed = 0;
  for (auto it = tiles_.begin(); it != tiles_.end(); ++it) {
    const TileIndex tile_index = unpackKey2(it->first);
    if ((tile_index.array() < tile_lo.array()).any() ||
        (tile_index.array() > tile_hi.array()).any()) {
      continue;
    }
    GridTile* tile = it.value().get();
    for (int linear = 0; linear < GridTile::kArea; ++linear) {
      if (!GridTile::isKnown(tile->log_odds[linear])) continue;
      const Eigen::Vector2d center = centerOf(cellIndex(tile_index, linear));
      if ((center.array() < min.array()).any() || (center.array() > max.array()).any()) continue;
      watch(it->first, tile);
      tile->log_odds[linear] = min_log_odds_;
      markWritten(it->first, tile);
      ++changed;
    }
  }
  finishWrite();
  return changed;
}

void GridLayer2D::reset() {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  tiles_.clear();
  stored_.clear();
  // Consumers holding older versions must rebuild from scratch.
  change_log_.clear(version_ + 1);
  ++version_;
}

void GridLayer2D::forEachKnownCell(const CellFn& fn) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  forEachTileLocked([&](const TileIndex& tile_index, const GridTile& tile) {
    for (int linear = 0; linear < GridTile::kArea; ++linear) {
      const float value = tile.log_odds[linear];
      if (GridTile::isKnown(value)) fn(cellIndex(tile_index, linear), value);
    }
  });
}

void GridLayer2D::forEachTile(
    const std::function<void(const TileIndex&, const GridTile&)>& fn) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  forEachTileLocked(fn);
}

bool GridLayer2D::copyTile(const TileIndex& tile, GridTile* out) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  GridTile scratch;
  const GridTile* found = readTile(packKey(tile), &scratch);
  if (found == nullptr) return false;
  *out = *found;
  return true;
}

std::vector<float> GridLayer2D::windowLocked(const CellIndex& origin_cell, int width,
                                             int height) const {
  std::vector<float> out(static_cast<std::size_t>(std::max(width, 0)) * std::max(height, 0),
                         GridTile::kUnknown);
  if (out.empty()) return out;
  const CellIndex end = origin_cell + CellIndex(width, height);
  const TileIndex first_tile = tileOf(origin_cell);
  const TileIndex last_tile = tileOf(end - CellIndex::Ones());
  GridTile scratch;
  for (int ty = first_tile.y(); ty <= last_tile.y(); ++ty) {
    for (int tx = first_tile.x(); tx <= last_tile.x(); ++tx) {
      const GridTile* tile = readTile(packKey(TileIndex(tx, ty)), &scratch);
      if (tile == nullptr) continue;
      const CellIndex tile_min = TileIndex(tx, ty) * GridTile::kSide;
      const CellIndex lo = tile_min.cwiseMax(origin_cell);
      const CellIndex hi = (tile_min + CellIndex::Constant(GridTile::kSide)).cwiseMin(end);
      for (int y = lo.y(); y < hi.y(); ++y) {
        for (int x = lo.x(); x < hi.x(); ++x) {
          out[static_cast<std::size_t>(y - origin_cell.y()) * width + (x - origin_cell.x())] =
              tile->log_odds[linearIndexInTile({x, y})];
        }
      }
    }
  }
  return out;
}

std::vector<float> GridLayer2D::window(const CellIndex& origin_cell, int width, int height) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return windowLocked(origin_cell, width, height);
}

std::optional<CellBox> GridLayer2D::knownBoundsLocked() const {
  std::optional<CellBox> box;
  forEachTileLocked([&](const TileIndex& tile_index, const GridTile& tile) {
    if (tile.known_count == 0) return;
    for (int linear = 0; linear < GridTile::kArea; ++linear) {
      if (!GridTile::isKnown(tile.log_odds[linear])) continue;
      const CellIndex cell = cellIndex(tile_index, linear);
      if (!box) {
        box = CellBox{cell, cell};
      } else {
        box->min = box->min.cwiseMin(cell);
        box->max = box->max.cwiseMax(cell);
      }
    }
  });
  return box;
}

std::optional<CellBox> GridLayer2D::knownBounds() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return knownBoundsLocked();
}

LogOddsRaster GridLayer2D::toLogOddsRaster() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  LogOddsRaster raster;
  raster.resolution = config_.resolution;
  const std::optional<CellBox> box = knownBoundsLocked();
  if (!box) return raster;
  raster.origin_cell = box->min;
  raster.width = box->width();
  raster.height = box->height();
  raster.data = windowLocked(box->min, raster.width, raster.height);
  return raster;
}

GridChanges GridLayer2D::changesSince(std::uint64_t version) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return changesSinceLocked(version);
}

GridChanges GridLayer2D::changesSinceLocked(std::uint64_t version) const {
  GridChanges changes;
  changes.version = version_;
  std::vector<std::uint64_t> changed;
  if (!change_log_.collectSince(version, &changed, nullptr)) {
    changes.full_rebuild = true;
    return changes;
  }
  for (std::uint64_t key : changed) changes.changed.push_back(unpackKey2(key));
  return changes;
}

std::uint64_t GridLayer2D::version() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return version_;
}

std::size_t GridLayer2D::tileCount() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return tiles_.size() + stored_.size();
}

std::size_t GridLayer2D::knownCellCount() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  std::size_t count = 0;
  for (const auto& entry : tiles_) count += static_cast<std::size_t>(entry.second->known_count);
  for (const auto& entry : stored_) count += static_cast<std::size_t>(entry.second);
  return count;
}

std::size_t GridLayer2D::memoryBytes() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return tiles_.size() * sizeof(GridTile) + tiles_.bucket_count() * kTableSlotBytes +
         stored_.bucket_count() * kTableSlotBytes + change_log_.memoryBytes();
}

}  // namespace occupancy_fusion
