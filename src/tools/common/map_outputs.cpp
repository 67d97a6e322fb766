#include "occupancy_fusion/tools/map_outputs.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "occupancy_fusion/map/map_files.h"

namespace occupancy_fusion {
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
