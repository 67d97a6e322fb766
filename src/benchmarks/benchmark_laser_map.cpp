// benchmark laser-map: a whole CARMEN log mapped into the world frame. Every FLASER scan goes
// through the polar laser integrator at its corrected pose into one GridLayer2D (the shared
// map's 2D layer, clamped as the map's model says); the layer is then drawn as a picture, to be
// compared with the log's reference map, and the time per scan is reported.
#include <omp.h>

#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "occupancy_fusion/benchmarks/benchmark_harness.h"
#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"
#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/sensors/carmen_log.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {

// benchmark_laser.cpp: free light, occupied dark, unknown in the given colour.
cv::Mat laserRasterImage(const LogOddsRaster& raster, const cv::Vec3b& unknown);

int runLaserMap(const CommandLine& args) {
  const std::string log = args.required("folder");  // the first positional argument
  const std::string output = args.required("output");
  CarmenReadConfig read;
  read.max_scans = static_cast<std::size_t>(args.intValue("scans", 0));
  read.range_max = args.doubleValue("range_max", read.range_max);
  const std::vector<CarmenLaserScan> scans = readCarmenLog(log, read);
  if (scans.empty()) throw std::runtime_error("no FLASER scans in " + log);

  PolarLaserIntegratorConfig config;
  config.method = parsePolarToCartesianMethod(args.value("method", "mipmap"));
  config.model.ranges.above_range_max_is_no_return = true;
  config.model.no_return_free_length = args.doubleValue("free_length", 0.0);
  config.model.range_sigma = args.doubleValue("sigma", config.model.range_sigma);
  config.model.range_resolution = args.doubleValue("range_resolution", 0.05);
  PolarLaserIntegrator integrator(config);
  GridLayer2DConfig layer_config;
  layer_config.resolution = args.doubleValue("resolution", 0.05);
  GridLayer2D layer(layer_config);

  const bench::Clock::time_point start = bench::Clock::now();
  for (const CarmenLaserScan& record : scans) {
    integrator.integrateIntoLayer(record.scan, {record.x, record.y, record.theta}, &layer);
  }
  const double total_ms = bench::millisecondsSince(start);

  const LogOddsRaster raster = layer.toLogOddsRaster();
  if (raster.data.empty()) throw std::runtime_error("nothing observed in " + log);
  if (!cv::imwrite(output, laserRasterImage(raster, cv::Vec3b(205, 205, 205)))) {
    throw std::runtime_error("cannot write " + output);
  }
  std::size_t occupied = 0;
  for (float value : raster.data) {
    if (!std::isnan(value) && layer.classify(value) == Occupancy::kOccupied) ++occupied;
  }
  std::printf(
      "laser_map log=%s scans=%zu method=%s threads=%d ms_per_scan=%.3f known_cells=%zu "
      "occupied_cells=%zu extent_m=%.1fx%.1f output=%s\n",
      log.c_str(), scans.size(), methodName(config.method), omp_get_max_threads(),
      total_ms / static_cast<double>(scans.size()), layer.knownCellCount(), occupied,
      raster.width * raster.resolution, raster.height * raster.resolution, output.c_str());
  return 0;
}

}  // namespace occupancy_fusion
