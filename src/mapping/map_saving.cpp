#include "occupancy_fusion/mapping/map_saving.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include "occupancy_fusion/map/layer_files.h"
#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/map/octree_files.h"

namespace occupancy_fusion {
namespace {

// Runs `read` and reports how long it took to `timer` as `what`.
template <class Read>
auto timed(const MapReadTimer& timer, const char* what, Read read) {
  const auto start = std::chrono::steady_clock::now();
  auto result = read();
  if (timer) {
    timer(what, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                    .count());
  }
  return result;
}

// Each raster cell is about 5 px wide in the picture, but no picture exceeds ~4000 px a side.
int pictureScale(const OccupancyRaster& grid) {
  const int longest = std::max(grid.width, grid.height);
  return std::clamp(4000 / std::max(longest, 1), 1, 5);
}

}  // namespace

SavedMapFiles saveMap(const VoxelMap& voxels, const GridLayer2D& layer, const std::string& prefix,
                      const MapSaveOptions& options, std::vector<std::string>* written,
                      const MapReadTimer& timer) {
  // Every read before the first file is touched: a map that cannot be saved leaves the previous
  // files of this prefix as they were.
  FusedGridView view(options.band);
  const OccupancyRaster raster =
      timed(timer, "~save_map 2D view", [&] { return view.update(voxels, &layer); });
  if (voxels.knownVoxelCount() == 0 && layer.knownCellCount() == 0) {
    throw std::runtime_error(
        "the map has no known voxel and no 2D cell: nothing written, "
        "existing files of " +
        prefix + " kept");
  }
  SavedMapFiles saved;
  // The blocks are read one at a time (each under the map's shared lock for a microsecond, so
  // not reported to the timer, or from its spill store): a map larger than memory is saved
  // without holding it.
  const OctreeFilePaths paths{prefix + ".ot", prefix + ".bt"};
  saved.octomap_skipped_voxels =
      writeOctreeFiles(blockSourceOf(voxels), voxels.resolution(), voxels.model(), paths)
          .skipped_voxels;
  written->push_back(paths.ot);
  written->push_back(paths.bt);
  if (!raster.empty()) {
    saved.grid_width = raster.width;
    saved.grid_height = raster.height;
    writeMapServerFiles(raster, prefix);
    written->push_back(prefix + ".pgm");
    written->push_back(prefix + ".yaml");
  }
  const LayerFilePaths layer_paths = writeLayerFiles(layer, prefix);  // a strip at a time
  written->push_back(layer_paths.npy);
  written->push_back(layer_paths.yaml);
  if (!options.inspection_files) return saved;
  writePcd(voxels, prefix + ".pcd");
  written->push_back(prefix + ".pcd");
  if (!raster.empty()) {
    writeNpy(fusedLogOdds(voxels, &layer, options.band, raster), prefix + ".npy");
    written->push_back(prefix + ".npy");
    writePng(raster, prefix + ".png", pictureScale(raster));
    written->push_back(prefix + ".png");
  }
  return saved;
}

LogOddsRaster fusedLogOdds(const VoxelMap& map, const GridLayer2D* layer,
                           const FusedGridConfig& config, const OccupancyRaster& grid) {
  if (layer != nullptr && std::abs(layer->resolution() - map.resolution()) > 1e-9) {
    throw std::invalid_argument("fusedLogOdds: the layer's resolution differs from the map's");
  }
  LogOddsRaster raster;
  raster.resolution = grid.resolution;
  raster.origin_cell = CellIndex(static_cast<int>(std::lround(grid.origin_x / grid.resolution)),
                                 static_cast<int>(std::lround(grid.origin_y / grid.resolution)));
  raster.width = grid.width;
  raster.height = grid.height;
  raster.data.assign(static_cast<std::size_t>(grid.width) * grid.height,
                     std::numeric_limits<float>::quiet_NaN());
  const auto raise = [&](int column_x, int column_y, float log_odds) {
    const int x = column_x - raster.origin_cell.x();
    const int y = column_y - raster.origin_cell.y();
    if (x < 0 || y < 0 || x >= raster.width || y >= raster.height) return;
    float& cell = raster.data[static_cast<std::size_t>(x + raster.width * y)];
    if (std::isnan(cell) || log_odds > cell) cell = log_odds;
  };
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    const double z = map.centerOf(index).z();
    if (z >= config.min_z && z <= config.max_z) raise(index.x(), index.y(), log_odds);
  });
  if (layer != nullptr) {
    layer->forEachKnownCell(
        [&](const CellIndex& index, float log_odds) { raise(index.x(), index.y(), log_odds); });
  }
  return raster;
}

}  // namespace occupancy_fusion
