#include "occupancy_fusion/map/fused_grid.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

namespace occupancy_fusion {
namespace {

// Column states, ordered so that max() applies the fusion rule (occupied wins, then free).
constexpr std::int8_t kStateUnknown = -1;
constexpr std::int8_t kStateFree = 0;
constexpr std::int8_t kStateOccupied = 1;

// Tolerance, in cells, for deciding that two squares overlap: shared edges that differ only by
// rounding (equal resolutions, aligned grids) must not count as overlap.
constexpr double kOverlapEpsilon = 1e-6;

struct Range {
  int first;
  int last;  // inclusive; empty when last < first
};

// Cells of unit size overlapping [lo, hi) with a positive length.
Range overlappingCells(double lo, double hi) {
  return {static_cast<int>(std::floor(lo + kOverlapEpsilon)),
          static_cast<int>(std::ceil(hi - kOverlapEpsilon)) - 1};
}

// Columns (edge column_resolution) that layer cell `cell` (edge cell_resolution) overlaps, along
// one axis. Both the reference and the incremental view use exactly this mapping.
Range columnsOfLayerCell(int cell, double cell_resolution, double column_resolution) {
  return overlappingCells(cell * cell_resolution / column_resolution,
                          (cell + 1) * cell_resolution / column_resolution);
}

std::int8_t stateOf(Occupancy occupancy) {
  return occupancy == Occupancy::kOccupied ? kStateOccupied : kStateFree;
}

std::int8_t rasterValue(std::int8_t state) {
  if (state == kStateOccupied) return OccupancyRaster::kOccupied;
  if (state == kStateFree) return OccupancyRaster::kFree;
  return OccupancyRaster::kUnknown;
}

bool centerInBand(const VoxelMap& map, int voxel_z, const FusedGridConfig& config) {
  const double z = map.centerOf(VoxelIndex(0, 0, voxel_z)).z();
  return z >= config.min_z && z <= config.max_z;
}

// Bit lz set when the voxel layer lz of block row block_z has its centres inside the band.
unsigned bandMask(const VoxelMap& map, int block_z, const FusedGridConfig& config) {
  unsigned mask = 0;
  for (int lz = 0; lz < VoxelBlock::kSide; ++lz) {
    if (centerInBand(map, block_z * VoxelBlock::kSide + lz, config)) mask |= 1u << lz;
  }
  return mask;
}

// Key of a column tile (x, y block coordinates) or of a single column (x, y cell coordinates).
std::uint64_t packColumnTile(int x, int y) { return packKey(Eigen::Vector2i(x, y)); }

// Sparse column states keyed by column index, for the reference.
using ColumnStates = SpatialKeyMap<std::int8_t>;

void raiseState(ColumnStates* states, int x, int y, std::int8_t state) {
  auto [it, inserted] = states->try_emplace(packColumnTile(x, y), state);
  if (!inserted && it->second < state) it.value() = state;
}

// Inclusive bounding box of columns, grown one column at a time; empty while lo.x() > hi.x().
struct ColumnBox {
  Eigen::Vector2i lo = Eigen::Vector2i::Constant(std::numeric_limits<int>::max());
  Eigen::Vector2i hi = Eigen::Vector2i::Constant(std::numeric_limits<int>::min());
  void extend(const Eigen::Vector2i& column) {
    lo = lo.cwiseMin(column);
    hi = hi.cwiseMax(column);
  }
};

// An all-unknown raster over the box (no cells when the box is empty).
OccupancyRaster unknownRaster(const ColumnBox& box, double resolution) {
  OccupancyRaster raster;
  raster.resolution = resolution;
  if (box.lo.x() > box.hi.x()) return raster;
  raster.origin_x = box.lo.x() * resolution;
  raster.origin_y = box.lo.y() * resolution;
  raster.width = box.hi.x() - box.lo.x() + 1;
  raster.height = box.hi.y() - box.lo.y() + 1;
  raster.data.assign(static_cast<std::size_t>(raster.width) * raster.height,
                     OccupancyRaster::kUnknown);
  return raster;
}

// Writes a known state into the raster made by unknownRaster(box, ...); column lies in box.
void setColumn(const ColumnBox& box, const Eigen::Vector2i& column, std::int8_t state,
               OccupancyRaster* raster) {
  const Eigen::Vector2i cell = column - box.lo;
  raster->data[static_cast<std::size_t>(cell.x()) +
               static_cast<std::size_t>(raster->width) * cell.y()] = rasterValue(state);
}

OccupancyRaster rasterFromStates(const ColumnStates& states, double resolution) {
  ColumnBox box;
  for (const auto& [key, state] : states) box.extend(unpackKey2(key));
  OccupancyRaster raster = unknownRaster(box, resolution);
  for (const auto& [key, state] : states) setColumn(box, unpackKey2(key), state, &raster);
  return raster;
}

}  // namespace

void FusedGridConfig::validate() const {
  if (std::isnan(min_z)) throw std::invalid_argument("occupancy_min_z must be a number");
  if (std::isnan(max_z)) throw std::invalid_argument("occupancy_max_z must be a number");
  if (min_z > max_z) {
    throw std::invalid_argument("occupancy_min_z (" + std::to_string(min_z) +
                                ") must not exceed occupancy_max_z (" + std::to_string(max_z) +
                                ")");
  }
}

OccupancyRaster projectToRaster(const VoxelMap& map, const GridLayer2D* layer,
                                const FusedGridConfig& config) {
  config.validate();
  ColumnStates states;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    const double z = map.centerOf(index).z();
    if (z < config.min_z || z > config.max_z) return;
    raiseState(&states, index.x(), index.y(), stateOf(map.classify(log_odds)));
  });
  if (layer != nullptr) {
    const double cell_resolution = layer->resolution();
    layer->forEachKnownCell([&](const CellIndex& cell, float log_odds) {
      const std::int8_t state = stateOf(layer->classify(log_odds));
      const Range xs = columnsOfLayerCell(cell.x(), cell_resolution, map.resolution());
      const Range ys = columnsOfLayerCell(cell.y(), cell_resolution, map.resolution());
      for (int y = ys.first; y <= ys.last; ++y) {
        for (int x = xs.first; x <= xs.last; ++x) raiseState(&states, x, y, state);
      }
    });
  }
  return rasterFromStates(states, map.resolution());
}

FusedGridView::FusedGridView(const FusedGridConfig& config) : config_(config) {
  config_.validate();
}

void FusedGridView::reset() {
  std::lock_guard<std::mutex> lock(mutex_);
  map_ = nullptr;
  layer_ = nullptr;
  layer_valid_ = false;
  shares_.clear();
  columns_.clear();
}

OccupancyRaster FusedGridView::update(const VoxelMap& map, const GridLayer2D* layer) {
  std::lock_guard<std::mutex> lock(mutex_);
  stats_ = UpdateStats();
  if (&map != map_ || map.resolution() != resolution_) {
    // Columns depend on the map's resolution: start over, the layer's part included.
    map_ = &map;
    resolution_ = map.resolution();
    map_version_ = 0;
    shares_.clear();
    columns_.clear();
    layer_valid_ = false;
  }
  updateFromMap(map);
  updateFromLayer(layer);
  dropEmptyColumnTiles();
  return compose();
}

void FusedGridView::updateFromMap(const VoxelMap& map) {
  // Read the log before the blocks: a write racing with this update is reported again next time.
  const MapChanges changes = map.changesSince(map_version_);
  map_version_ = changes.version;
  if (changes.full_rebuild) {
    rebuildFromMap(map);
    return;
  }
  SpatialKeySet seen;
  for (const auto* list : {&changes.changed, &changes.removed}) {
    for (const BlockIndex& block : *list) {
      if (seen.insert(packKey(block)).second) refreshBlock(map, block);
    }
  }
  stats_.map_blocks_processed = seen.size();
}

void FusedGridView::rebuildFromMap(const VoxelMap& map) {
  stats_.map_rebuilt = true;
  shares_.clear();
  for (auto it = columns_.begin(); it != columns_.end(); ++it) {
    it.value().occupied.fill(0);
    it.value().free.fill(0);
  }
  map.forEachBlock([&](const BlockIndex& block_index, const VoxelBlock& block) {
    ++stats_.map_blocks_processed;
    BlockShare share;
    if (!computeShare(map, block_index, block, &share)) return;
    applyShare(block_index, share, +1);
    shares_.emplace(packKey(block_index), share);
  });
}

void FusedGridView::refreshBlock(const VoxelMap& map, const BlockIndex& block_index) {
  const std::uint64_t key = packKey(block_index);
  const auto old = shares_.find(key);
  if (old != shares_.end()) {
    applyShare(block_index, old->second, -1);
    shares_.erase(old);
  }
  if (bandMask(map, block_index.z(), config_) == 0) return;
  VoxelBlock block;
  if (!map.copyBlock(block_index, &block)) return;  // removed
  BlockShare share;
  if (!computeShare(map, block_index, block, &share)) return;
  applyShare(block_index, share, +1);
  shares_.emplace(key, share);
}

bool FusedGridView::computeShare(const VoxelMap& map, const BlockIndex& block_index,
                                 const VoxelBlock& block, BlockShare* share) const {
  const unsigned mask = bandMask(map, block_index.z(), config_);
  if (mask == 0 || block.known_count == 0) return false;
  bool any = false;
  for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
    const float value = block.log_odds[linear];
    if (!VoxelBlock::isKnown(value)) continue;
    const Eigen::Vector3i local = VoxelBlock::localIndex(linear);
    if ((mask & (1u << local.z())) == 0) continue;
    const int column = local.x() + kSide * local.y();
    if (map.classify(value) == Occupancy::kOccupied) {
      ++share->occupied[column];
    } else {
      ++share->free[column];
    }
    any = true;
  }
  return any;
}

void FusedGridView::applyShare(const BlockIndex& block, const BlockShare& share, int sign) {
  ColumnTile& tile = columns_[packColumnTile(block.x(), block.y())];
  for (int column = 0; column < kArea; ++column) {
    tile.occupied[column] += sign * static_cast<int>(share.occupied[column]);
    tile.free[column] += sign * static_cast<int>(share.free[column]);
  }
}

void FusedGridView::updateFromLayer(const GridLayer2D* layer) {
  const bool rebuild = !layer_valid_ || layer != layer_;
  layer_valid_ = true;
  layer_ = layer;
  if (rebuild) {
    for (auto it = columns_.begin(); it != columns_.end(); ++it) it.value().layer.fill(-1);
    layer_version_ = 0;
  }
  if (layer == nullptr) return;
  const GridChanges changes = layer->changesSince(layer_version_);
  layer_version_ = changes.version;
  std::vector<TileIndex> tiles;
  if (changes.full_rebuild) {
    if (!rebuild) {
      for (auto it = columns_.begin(); it != columns_.end(); ++it) it.value().layer.fill(-1);
    }
    stats_.layer_rebuilt = true;
    layer->forEachTile([&](const TileIndex& tile, const GridTile&) { tiles.push_back(tile); });
  } else {
    SpatialKeySet seen;
    for (const TileIndex& tile : changes.changed) {
      if (seen.insert(packColumnTile(tile.x(), tile.y())).second) tiles.push_back(tile);
    }
  }
  for (const TileIndex& tile : tiles) refreshLayerTile(*layer, tile);
  stats_.layer_tiles_processed = tiles.size();
}

void FusedGridView::refreshLayerTile(const GridLayer2D& layer, const TileIndex& tile) {
  const double cell_resolution = layer.resolution();
  // Columns the tile's square overlaps: their 2D state is recomputed from every layer cell that
  // overlaps them, including cells of neighbouring tiles.
  const CellIndex tile_min = tile * GridTile::kSide;
  const Range xs =
      overlappingCells(tile_min.x() * cell_resolution / resolution_,
                       (tile_min.x() + GridTile::kSide) * cell_resolution / resolution_);
  const Range ys =
      overlappingCells(tile_min.y() * cell_resolution / resolution_,
                       (tile_min.y() + GridTile::kSide) * cell_resolution / resolution_);
  for (int ty = ys.first >> VoxelBlock::kSideLog2; ty <= ys.last >> VoxelBlock::kSideLog2; ++ty) {
    for (int tx = xs.first >> VoxelBlock::kSideLog2; tx <= xs.last >> VoxelBlock::kSideLog2; ++tx) {
      auto it = columns_.find(packColumnTile(tx, ty));
      if (it == columns_.end()) continue;
      for (int y = std::max(ys.first, ty * kSide); y <= std::min(ys.last, ty * kSide + kSide - 1);
           ++y) {
        for (int x = std::max(xs.first, tx * kSide); x <= std::min(xs.last, tx * kSide + kSide - 1);
             ++x) {
          it.value().layer[(x - tx * kSide) + kSide * (y - ty * kSide)] = kStateUnknown;
        }
      }
    }
  }
  // Layer cells that may overlap those columns, with one cell of margin against rounding.
  const CellIndex first(static_cast<int>(std::floor(xs.first * resolution_ / cell_resolution)) - 1,
                        static_cast<int>(std::floor(ys.first * resolution_ / cell_resolution)) - 1);
  const CellIndex last(
      static_cast<int>(std::ceil((xs.last + 1) * resolution_ / cell_resolution)) + 1,
      static_cast<int>(std::ceil((ys.last + 1) * resolution_ / cell_resolution)) + 1);
  const int width = last.x() - first.x() + 1;
  const int height = last.y() - first.y() + 1;
  const std::vector<float> cells = layer.window(first, width, height);
  for (int cy = 0; cy < height; ++cy) {
    for (int cx = 0; cx < width; ++cx) {
      const float value =
          cells[static_cast<std::size_t>(cx) + static_cast<std::size_t>(width) * cy];
      if (!GridTile::isKnown(value)) continue;
      const std::int8_t state = stateOf(layer.classify(value));
      const Range cell_xs = columnsOfLayerCell(first.x() + cx, cell_resolution, resolution_);
      const Range cell_ys = columnsOfLayerCell(first.y() + cy, cell_resolution, resolution_);
      for (int y = std::max(cell_ys.first, ys.first); y <= std::min(cell_ys.last, ys.last); ++y) {
        for (int x = std::max(cell_xs.first, xs.first); x <= std::min(cell_xs.last, xs.last); ++x) {
          ColumnTile& column_tile =
              columns_[packColumnTile(x >> VoxelBlock::kSideLog2, y >> VoxelBlock::kSideLog2)];
          std::int8_t& target = column_tile.layer[(x & (kSide - 1)) + kSide * (y & (kSide - 1))];
          target = std::max(target, state);
        }
      }
    }
  }
}

void FusedGridView::dropEmptyColumnTiles() {
  for (auto it = columns_.begin(); it != columns_.end();) {
    const ColumnTile& tile = it->second;
    bool empty = true;
    for (int column = 0; column < kArea && empty; ++column) {
      empty = tile.occupied[column] == 0 && tile.free[column] == 0 && tile.layer[column] < 0;
    }
    it = empty ? columns_.erase(it) : std::next(it);
  }
}

OccupancyRaster FusedGridView::compose() const {
  auto state_of = [](const ColumnTile& tile, int column) {
    if (tile.occupied[column] > 0) return kStateOccupied;
    if (tile.free[column] > 0) return std::max(tile.layer[column], kStateFree);
    return tile.layer[column];
  };
  auto column_of = [](const Eigen::Vector2i& tile_index, int column) {
    return Eigen::Vector2i(tile_index.x() * kSide + (column & (kSide - 1)),
                           tile_index.y() * kSide + (column >> VoxelBlock::kSideLog2));
  };
  // Bounding box of the known columns first, then the raster in one pass.
  ColumnBox box;
  for (const auto& [key, tile] : columns_) {
    const Eigen::Vector2i tile_index = unpackKey2(key);
    for (int column = 0; column < kArea; ++column) {
      if (state_of(tile, column) != kStateUnknown) box.extend(column_of(tile_index, column));
    }
  }
  OccupancyRaster raster = unknownRaster(box, resolution_);
  for (const auto& [key, tile] : columns_) {
    const Eigen::Vector2i tile_index = unpackKey2(key);
    for (int column = 0; column < kArea; ++column) {
      const std::int8_t state = state_of(tile, column);
      if (state != kStateUnknown) setColumn(box, column_of(tile_index, column), state, &raster);
    }
  }
  return raster;
}

}  // namespace occupancy_fusion
