#include "occupancy_fusion/tools/map_outputs.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "occupancy_fusion/map/layer_files.h"
#include "occupancy_fusion/map/map_files.h"

namespace occupancy_fusion {
namespace {

// Each raster cell is about 5 px wide in the picture, but no picture exceeds ~4000 px a side.
int pictureScale(const OccupancyRaster& grid) {
  const int longest = std::max(grid.width, grid.height);
  return std::clamp(4000 / std::max(longest, 1), 1, 5);
}

}  // namespace

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

MapOutputs writeMapOutputs(const MappingSession& mapper, const std::string& dir,
                           const std::string& name) {
  const std::string prefix = (std::filesystem::path(dir) / name).string();
  MapOutputs outputs;
  const VoxelMap& map = mapper.map();
  outputs.octomap_skipped_voxels = writeBt(map, prefix + ".bt");
  outputs.files.push_back(prefix + ".bt");
  writeOt(map, prefix + ".ot");
  outputs.files.push_back(prefix + ".ot");
  writePcd(map, prefix + ".pcd");
  outputs.files.push_back(prefix + ".pcd");
  const LayerFilePaths layer_paths = writeLayerFiles(mapper.laserLayer().toLogOddsRaster(), prefix);
  outputs.files.push_back(layer_paths.npy);
  outputs.files.push_back(layer_paths.yaml);

  const OccupancyRaster grid = mapper.fusedGrid();
  if (grid.empty()) return outputs;
  outputs.grid_width = grid.width;
  outputs.grid_height = grid.height;
  writeMapServerFiles(grid, prefix);
  outputs.files.push_back(prefix + ".pgm");
  outputs.files.push_back(prefix + ".yaml");
  writeNpy(fusedLogOdds(map, &mapper.laserLayer(), mapper.config().fused_grid, grid),
           prefix + ".npy");
  outputs.files.push_back(prefix + ".npy");
  writePng(grid, prefix + ".png", pictureScale(grid));
  outputs.files.push_back(prefix + ".png");
  return outputs;
}

void SingleScanGridConfig::validate() const {
  if (!(resolution > 0.0) || !std::isfinite(resolution)) {
    throw std::invalid_argument("single scan grid: resolution must be > 0");
  }
  if (!(length >= resolution) || !std::isfinite(length)) {
    throw std::invalid_argument("single scan grid: length must be at least one cell");
  }
  if (!(depth >= resolution) || !std::isfinite(depth)) {
    throw std::invalid_argument("single scan grid: depth must be at least one cell");
  }
}

LogOddsRaster singleScanGrid(const LaserScan& scan, const PolarLaserIntegratorConfig& config,
                             const SingleScanGridConfig& grid) {
  grid.validate();
  LogOddsRaster raster;
  raster.resolution = grid.resolution;
  raster.width = static_cast<int>(std::lround(grid.length / grid.resolution));
  raster.height = static_cast<int>(std::lround(grid.depth / grid.resolution));
  raster.origin_cell = CellIndex(-raster.width / 2, 0);
  raster.data.assign(static_cast<std::size_t>(raster.width) * raster.height,
                     std::numeric_limits<float>::quiet_NaN());
  PolarLaserIntegrator integrator(config);
  integrator.integrate(scan, Pose2D{0.0, 0.0, 0.5 * M_PI}, &raster);
  return raster;
}

std::vector<std::string> writeSingleScanOutputs(const LogOddsRaster& grid, float threshold_log_odds,
                                                const std::string& prefix) {
  OccupancyRaster classified;
  classified.resolution = grid.resolution;
  classified.origin_x = grid.origin_cell.x() * grid.resolution;
  classified.origin_y = grid.origin_cell.y() * grid.resolution;
  classified.width = grid.width;
  classified.height = grid.height;
  classified.data.resize(grid.data.size());
  for (std::size_t i = 0; i < grid.data.size(); ++i) {
    const float value = grid.data[i];
    classified.data[i] = std::isnan(value)            ? OccupancyRaster::kUnknown
                         : value > threshold_log_odds ? OccupancyRaster::kOccupied
                                                      : OccupancyRaster::kFree;
  }
  writeNpy(grid, prefix + ".npy");
  writeMapServerFiles(classified, prefix);
  writePng(classified, prefix + ".png", 1);
  return {prefix + ".npy", prefix + ".pgm", prefix + ".yaml", prefix + ".png"};
}

}  // namespace occupancy_fusion
