// benchmark laser: Yguel et al.'s Table I on real scans. Every FLASER scan of a
// CARMEN log is projected into a 60 m x 30 m grid of 5 cm cells, the sensor at
// the middle of a long edge facing into the grid, by the four
// polar-to-cartesian methods; lines, sampling and mipmap are compared with
// exact (mean and max |delta log-ratio| over all cells, unknown counting as 0),
// and timed.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "occupancy_fusion/integrators/polar_laser_integrator.h"
#include "occupancy_fusion/sensors/carmen_log.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kPi = 3.14159265358979323846;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start)
      .count();
}

struct MethodStats {
  PolarToCartesianMethod method;
  double total_ms = 0.0;
  double sum_of_means = 0.0;
  double max_error = 0.0;
};

void resetRaster(LogOddsRaster *raster) {
  std::fill(raster->data.begin(), raster->data.end(),
            std::numeric_limits<float>::quiet_NaN());
}

// Mean and max |a - b| over all cells, an unknown cell counting as log-ratio 0.
void compare(const LogOddsRaster &a, const LogOddsRaster &b, double *mean,
             double *max) {
  double sum = 0.0;
  double worst = 0.0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    const double x = std::isnan(a.data[i]) ? 0.0 : a.data[i];
    const double y = std::isnan(b.data[i]) ? 0.0 : b.data[i];
    sum += std::abs(x - y);
    worst = std::max(worst, std::abs(x - y));
  }
  *mean = sum / static_cast<double>(a.data.size());
  *max = worst;
}

// The V-grid: four scanners at the corners of a 4 m x 2 m vehicle, looking out
// diagonally, all fed each cycle (with the log's scans) into a vehicle-centred
// 60 m x 30 m grid by the exact overlays, which are computed in the first cycle
// and reused after.
void reportFusedVehicleGrid(const std::vector<CarmenLaserScan> &scans,
                            PolarLaserIntegratorConfig config,
                            double resolution) {
  config.method = PolarToCartesianMethod::kExact;
  LocalLaserGridConfig grid_config;
  grid_config.resolution = resolution;
  grid_config.size_x = 60.0;
  grid_config.size_y = 30.0;
  LocalLaserGrid grid(grid_config, config);
  grid.addScanner({2.0, 1.0, 0.25 * kPi});
  grid.addScanner({-2.0, 1.0, 0.75 * kPi});
  grid.addScanner({-2.0, -1.0, -0.75 * kPi});
  grid.addScanner({2.0, -1.0, -0.25 * kPi});
  std::vector<LaserScan> cycle(4);
  auto fill = [&](std::size_t i) {
    for (std::size_t s = 0; s < 4; ++s)
      cycle[s] = scans[(i + s) % scans.size()].scan;
  };
  fill(0);
  Clock::time_point start = Clock::now();
  grid.fuse(cycle);
  const double first_ms = millisecondsSince(start);
  const std::size_t cycles = std::min<std::size_t>(scans.size(), 50);
  double total_ms = 0.0;
  for (std::size_t i = 1; i <= cycles; ++i) {
    fill(i);
    start = Clock::now();
    grid.fuse(cycle);
    total_ms += millisecondsSince(start);
  }
  std::printf("laser fused scanners=4 method=exact cells=%d "
              "first_cycle_ms=%.1f ms_per_cycle=%.3f\n",
              grid.grid().width * grid.grid().height, first_ms,
              total_ms / cycles);
}

} // namespace

int runLaser(const CommandLine &args) {
  const std::string log =
      args.required("folder"); // the first positional argument
  CarmenReadConfig read;
  read.max_scans = static_cast<std::size_t>(args.intValue("scans", 200));
  read.range_max = args.doubleValue("range_max", read.range_max);
  const std::vector<CarmenLaserScan> scans = readCarmenLog(log, read);
  if (scans.empty())
    throw std::runtime_error("no FLASER scans in " + log);

  PolarLaserIntegratorConfig config;
  config.model.ranges.above_range_max_is_no_return = true;
  config.model.no_return_free_length = args.doubleValue("free_length", 0.0);
  config.model.range_sigma =
      args.doubleValue("sigma", config.model.range_sigma);
  config.model.range_resolution = args.doubleValue("range_resolution", 0.05);
  PolarLaserIntegrator integrator(config);

  // The grid of Table I: 1200 x 600 cells of 5 cm; the sensor at the middle of
  // the lower long edge, looking along +y into the grid.
  const double resolution = args.doubleValue("resolution", 0.05);
  LogOddsRaster exact;
  exact.resolution = resolution;
  exact.width = static_cast<int>(std::round(60.0 / resolution));
  exact.height = static_cast<int>(std::round(30.0 / resolution));
  exact.origin_cell = CellIndex(-exact.width / 2, 0);
  exact.data.assign(static_cast<std::size_t>(exact.width) * exact.height, 0.0f);
  LogOddsRaster other = exact;
  const Pose2D sensor{0.0, 0.0, 0.5 * kPi};

  // The exact overlay is computed once for this fixed geometry (timed apart)
  // and reused.
  const PolarField first = buildPolarField(scans.front().scan, config.model);
  ExactOverlayCache cache(1);
  Clock::time_point start = Clock::now();
  const ExactOverlay &overlay =
      cache.get(OverlayGeometry::of(first, sensor, exact));
  std::printf(
      "laser overlay_build_ms=%.1f overlay_entries=%zu polar_cells=%d\n",
      millisecondsSince(start), overlay.entryCount(),
      first.beams * first.cells);

  std::vector<MethodStats> stats = {{PolarToCartesianMethod::kExact},
                                    {PolarToCartesianMethod::kLines},
                                    {PolarToCartesianMethod::kSampling},
                                    {PolarToCartesianMethod::kMipmap}};
  int beams = 0;
  for (const CarmenLaserScan &record : scans) {
    beams = record.scan.beamCount();
    for (MethodStats &s : stats) {
      LogOddsRaster *target =
          s.method == PolarToCartesianMethod::kExact ? &exact : &other;
      resetRaster(target);
      start = Clock::now();
      const PolarField field = buildPolarField(record.scan, config.model);
      if (s.method == PolarToCartesianMethod::kExact) {
        overlay.apply(field, target);
      } else {
        integrator.project(field, sensor, s.method, target);
      }
      s.total_ms += millisecondsSince(start);
      if (s.method == PolarToCartesianMethod::kExact)
        continue;
      double mean = 0.0;
      double max = 0.0;
      compare(other, exact, &mean, &max);
      s.sum_of_means += mean;
      s.max_error = std::max(s.max_error, max);
    }
  }
  const double n = static_cast<double>(scans.size());
  std::printf("laser log=%s scans=%zu grid=%dx%d resolution=%.3f\n",
              log.c_str(), scans.size(), exact.width, exact.height, resolution);
  for (const MethodStats &s : stats) {
    std::printf("laser method=%s cells=%d beams=%d ms_per_scan=%.3f "
                "mean_err=%.4f max_err=%.3f\n",
                methodName(s.method), exact.width * exact.height, beams,
                s.total_ms / n, s.sum_of_means / n, s.max_error);
  }
  reportFusedVehicleGrid(scans, config, resolution);
  return 0;
}

} // namespace occupancy_fusion
