// benchmark laser: Yguel et al.'s Table I on real scans. Every FLASER scan of a CARMEN log is
// projected into a 60 m x 30 m grid of 5 cm cells, the sensor at the middle of a long edge facing
// into the grid, by the four polar-to-cartesian methods; lines, sampling and mipmap are compared
// with exact, and timed (the polar grid of the scan built into reused buffers, then projected).
//
// Errors, |delta log-ratio| against exact per cell, an unknown cell counting as 0:
//   mean_err       over all cells of the grid (the paper does not say which cells it averages);
//   mean_err_seen  over the cells that exact or the method wrote (the observed cells);
//   max_err        over all cells;
//   max_err_out    over the cells farther than the 30 cm safety radius from the sensor (near the
//                  sensor the additive lines pile up one update per ray into the same cells).
// The lines baseline is the paper's: every ray updates every cell it crosses (Sec. III-B.1, "cells
// close to the origin are updated several times because several rays cross them").
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "occupancy_fusion/benchmarks/benchmark_harness.h"
#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"
#include "occupancy_fusion/sensors/carmen_log.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {

// Shared with benchmark_laser_map.cpp: a log-odds raster as a picture, y up; grey level 255 (1 -
// occupancy probability), so free is light and occupied dark; unknown cells in `unknown` (BGR,
// default 205 grey as ROS map_server).
cv::Mat laserRasterImage(const LogOddsRaster& raster,
                         const cv::Vec3b& unknown = cv::Vec3b(205, 205, 205));

namespace {

using bench::Clock;
using bench::median;
using bench::millisecondsSince;
using bench::processCpuMilliseconds;
constexpr double kPi = 3.14159265358979323846;

struct ErrorStats {
  double mean_all = 0.0;
  double mean_seen = 0.0;
  double max_all = 0.0;
  double max_outside = 0.0;
};

struct MethodStats {
  explicit MethodStats(PolarToCartesianMethod m) : method(m) {}
  PolarToCartesianMethod method;
  std::vector<double> ms;
  std::vector<double> cpu_ms;
  double sum_mean_all = 0.0;
  double sum_mean_seen = 0.0;
  double max_all = 0.0;
  double max_outside = 0.0;
};

void resetRaster(LogOddsRaster* raster) {
  std::fill(raster->data.begin(), raster->data.end(), std::numeric_limits<float>::quiet_NaN());
}

// |a - b| per cell, an unknown cell counting as log-ratio 0; `outside` marks the cells beyond the
// safety radius.
ErrorStats compare(const LogOddsRaster& a, const LogOddsRaster& b,
                   const std::vector<std::uint8_t>& outside) {
  ErrorStats stats;
  double sum = 0.0;
  std::size_t seen = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    if (std::isnan(a.data[i]) && std::isnan(b.data[i])) continue;
    const double x = std::isnan(a.data[i]) ? 0.0 : a.data[i];
    const double y = std::isnan(b.data[i]) ? 0.0 : b.data[i];
    const double error = std::abs(x - y);
    sum += error;
    ++seen;
    stats.max_all = std::max(stats.max_all, error);
    if (outside[i]) stats.max_outside = std::max(stats.max_outside, error);
  }
  stats.mean_all = sum / static_cast<double>(a.data.size());
  stats.mean_seen = seen > 0 ? sum / static_cast<double>(seen) : 0.0;
  return stats;
}

std::vector<std::uint8_t> outsideRadius(const LogOddsRaster& raster, const Pose2D& sensor,
                                        double radius) {
  std::vector<std::uint8_t> outside(raster.data.size(), 0);
  for (int y = 0; y < raster.height; ++y) {
    for (int x = 0; x < raster.width; ++x) {
      const double cx = (raster.origin_cell.x() + x + 0.5) * raster.resolution - sensor.x;
      const double cy = (raster.origin_cell.y() + y + 0.5) * raster.resolution - sensor.y;
      outside[static_cast<std::size_t>(x + raster.width * y)] = std::hypot(cx, cy) > radius;
    }
  }
  return outside;
}

// The V-grid: four scanners at the corners of a 4 m x 2 m vehicle, looking out diagonally, all
// fed each cycle (with the log's scans) into a vehicle-centred 60 m x 30 m grid by the exact
// overlays, which are computed in the first cycle and reused after.
void reportFusedVehicleGrid(const std::vector<CarmenLaserScan>& scans,
                            PolarLaserIntegratorConfig config, double resolution) {
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
    for (std::size_t s = 0; s < 4; ++s) cycle[s] = scans[(i + s) % scans.size()].scan;
  };
  fill(0);
  Clock::time_point start = Clock::now();
  grid.fuse(cycle);
  const double first_ms = millisecondsSince(start);
  const std::size_t cycles = std::min<std::size_t>(scans.size(), 100);
  std::vector<double> ms;
  std::vector<double> cpu_ms;
  for (std::size_t i = 1; i <= cycles; ++i) {
    fill(i);
    start = Clock::now();
    const double cpu_start = processCpuMilliseconds();
    grid.fuse(cycle);
    ms.push_back(millisecondsSince(start));
    cpu_ms.push_back(processCpuMilliseconds() - cpu_start);
  }
  double total = 0.0;
  for (double m : ms) total += m;
  std::printf(
      "laser fused scanners=4 method=exact cells=%d first_cycle_ms=%.1f ms_per_cycle=%.3f "
      "ms_median=%.3f cpu_ms_median=%.3f\n",
      grid.grid().width * grid.grid().height, first_ms, total / cycles, median(ms), median(cpu_ms));
}

// Two pictures side by side with a caption each.
cv::Mat sideBySide(const cv::Mat& a, const cv::Mat& b, const std::string& caption_a,
                   const std::string& caption_b) {
  const int gap = 8;
  cv::Mat both(a.rows, a.cols + gap + b.cols, CV_8UC3, cv::Scalar(255, 255, 255));
  a.copyTo(both(cv::Rect(0, 0, a.cols, a.rows)));
  b.copyTo(both(cv::Rect(a.cols + gap, 0, b.cols, b.rows)));
  cv::putText(both, caption_a, {8, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.7, {0, 0, 255}, 2);
  cv::putText(both, caption_b, {a.cols + gap + 8, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.7, {0, 0, 255},
              2);
  return both;
}

// One scan by lines and by exact side by side (unknown cells blue, so the holes show), cropped
// to what exact observed; and a 4 m x 3 m window around 70% of the farthest observed range,
// enlarged 5x, where the lines leave the cells between rays unknown (the Moire effect).
void writeMoireImages(const LogOddsRaster& lines, const LogOddsRaster& exact,
                      const std::string& prefix) {
  const cv::Vec3b blue(200, 150, 90);
  const cv::Mat a = laserRasterImage(lines, blue);
  const cv::Mat b = laserRasterImage(exact, blue);
  int min_x = exact.width, max_x = -1, min_y = exact.height, max_y = -1;
  double far = -1.0;
  cv::Point far_cell;
  for (int y = 0; y < exact.height; ++y) {
    for (int x = 0; x < exact.width; ++x) {
      if (std::isnan(exact.at(x, y))) continue;
      min_x = std::min(min_x, x);
      max_x = std::max(max_x, x);
      min_y = std::min(min_y, y);
      max_y = std::max(max_y, y);
      const double cx = (exact.origin_cell.x() + x + 0.5) * exact.resolution;
      const double cy = (exact.origin_cell.y() + y + 0.5) * exact.resolution;
      if (std::hypot(cx, cy) > far) {
        far = std::hypot(cx, cy);
        far_cell = {x, y};
      }
    }
  }
  if (max_x < 0) return;
  const cv::Rect frame(0, 0, a.cols, a.rows);
  const int margin = 10;
  const cv::Rect known = cv::Rect(min_x - margin, a.rows - 1 - max_y - margin,
                                  max_x - min_x + 1 + 2 * margin, max_y - min_y + 1 + 2 * margin) &
                         frame;
  cv::imwrite(prefix + "_side_by_side.png",
              sideBySide(a(known), b(known), "lines (Bresenham)", "exact (Eq. 5)"));
  // The sensor sits at cell (-origin x, 0); the window is centred at 70% of the way out.
  const double sx = -exact.origin_cell.x();
  const cv::Point centre(static_cast<int>(sx + 0.7 * (far_cell.x - sx)),
                         a.rows - 1 - static_cast<int>(0.7 * far_cell.y));
  const int w = static_cast<int>(std::round(4.0 / exact.resolution));
  const int h = static_cast<int>(std::round(3.0 / exact.resolution));
  const cv::Rect window = cv::Rect(centre.x - w / 2, centre.y - h / 2, w, h) & frame;
  cv::Mat za;
  cv::Mat zb;
  cv::resize(a(window), za, {}, 5, 5, cv::INTER_NEAREST);
  cv::resize(b(window), zb, {}, 5, 5, cv::INTER_NEAREST);
  char range[64];
  std::snprintf(range, sizeof(range), ", 4 m x 3 m at %.1f m", 0.7 * far);
  cv::imwrite(prefix + "_zoom.png",
              sideBySide(za, zb, std::string("lines") + range, std::string("exact") + range));
}

}  // namespace

cv::Mat laserRasterImage(const LogOddsRaster& raster, const cv::Vec3b& unknown) {
  cv::Mat image(raster.height, raster.width, CV_8UC3);
  for (int y = 0; y < raster.height; ++y) {
    cv::Vec3b* row = image.ptr<cv::Vec3b>(raster.height - 1 - y);  // y up
    for (int x = 0; x < raster.width; ++x) {
      const float value = raster.at(x, y);
      if (std::isnan(value)) {
        row[x] = unknown;
        continue;
      }
      const double occupancy = 1.0 / (1.0 + std::exp(-static_cast<double>(value)));
      const auto grey = static_cast<unsigned char>(std::lround(255.0 * (1.0 - occupancy)));
      row[x] = cv::Vec3b(grey, grey, grey);
    }
  }
  return image;
}

int runLaser(const CommandLine& args) {
  const std::string log = args.required("folder");  // the first positional argument
  CarmenReadConfig read;
  read.max_scans = static_cast<std::size_t>(args.intValue("scans", 200));
  read.range_max = args.doubleValue("range_max", read.range_max);
  const std::vector<CarmenLaserScan> scans = readCarmenLog(log, read);
  if (scans.empty()) throw std::runtime_error("no FLASER scans in " + log);

  PolarLaserIntegratorConfig config;
  config.model.ranges.above_range_max_is_no_return = true;
  config.model.no_return_free_length = args.doubleValue("free_length", 0.0);
  config.model.range_sigma = args.doubleValue("sigma", config.model.range_sigma);
  config.model.range_resolution = args.doubleValue("range_resolution", 0.05);
  PolarLaserIntegrator integrator(config);

  // The grid of Table I: 1200 x 600 cells of 5 cm; the sensor at the middle of the lower long
  // edge, looking along +y into the grid.
  const double resolution = args.doubleValue("resolution", 0.05);
  LogOddsRaster exact;
  exact.resolution = resolution;
  exact.width = static_cast<int>(std::round(60.0 / resolution));
  exact.height = static_cast<int>(std::round(30.0 / resolution));
  exact.origin_cell = CellIndex(-exact.width / 2, 0);
  exact.data.assign(static_cast<std::size_t>(exact.width) * exact.height, 0.0f);
  LogOddsRaster other = exact;
  const Pose2D sensor{0.0, 0.0, 0.5 * kPi};
  const std::vector<std::uint8_t> outside =
      outsideRadius(exact, sensor, config.mipmap.safety_radius);

  reportFusedVehicleGrid(scans, config, resolution);

  // The exact overlay is computed once for this fixed geometry (timed apart) and reused.
  PolarField field = buildPolarField(scans.front().scan, config.model);
  ExactOverlayCache cache(1);
  Clock::time_point start = Clock::now();
  const ExactOverlay& overlay = cache.get(OverlayGeometry::of(field, sensor, exact));
  std::printf("laser overlay_build_ms=%.1f overlay_entries=%zu polar_cells=%d threads=%d\n",
              millisecondsSince(start), overlay.entryCount(), field.beams * field.cells,
              omp_get_max_threads());

  std::vector<MethodStats> stats;
  for (PolarToCartesianMethod method :
       {PolarToCartesianMethod::kExact, PolarToCartesianMethod::kLines,
        PolarToCartesianMethod::kSampling, PolarToCartesianMethod::kMipmap}) {
    stats.emplace_back(method);
  }
  const int image_scan = args.intValue("image_scan", 0);
  const std::string image_prefix = args.value("images", "");
  LogOddsRaster lines_image;
  int beams = 0;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const LaserScan& scan = scans[i].scan;
    beams = scan.beamCount();
    for (MethodStats& s : stats) {
      const bool is_exact = s.method == PolarToCartesianMethod::kExact;
      LogOddsRaster* target = is_exact ? &exact : &other;
      resetRaster(target);
      start = Clock::now();
      const double cpu_start = processCpuMilliseconds();
      buildPolarField(scan, config.model, &field);
      if (is_exact) {
        overlay.apply(field, target);
      } else {
        integrator.project(field, sensor, s.method, target);
      }
      s.ms.push_back(millisecondsSince(start));
      s.cpu_ms.push_back(processCpuMilliseconds() - cpu_start);
      if (is_exact) continue;
      const ErrorStats e = compare(other, exact, outside);
      s.sum_mean_all += e.mean_all;
      s.sum_mean_seen += e.mean_seen;
      s.max_all = std::max(s.max_all, e.max_all);
      s.max_outside = std::max(s.max_outside, e.max_outside);
      if (s.method == PolarToCartesianMethod::kLines && static_cast<int>(i) == image_scan) {
        lines_image = other;
      }
    }
    if (!image_prefix.empty() && static_cast<int>(i) == image_scan) {
      writeMoireImages(lines_image, exact, image_prefix);
    }
  }
  const double n = static_cast<double>(scans.size());
  std::printf("laser log=%s scans=%zu grid=%dx%d resolution=%.3f threads=%d\n", log.c_str(),
              scans.size(), exact.width, exact.height, resolution, omp_get_max_threads());
  for (const MethodStats& s : stats) {
    double total = 0.0;
    for (double m : s.ms) total += m;
    std::printf(
        "laser method=%s cells=%d beams=%d ms_per_scan=%.3f mean_err=%.4f max_err=%.3f "
        "ms_median=%.3f cpu_ms_median=%.3f mean_err_seen=%.4f max_err_out=%.3f\n",
        methodName(s.method), exact.width * exact.height, beams, total / n, s.sum_mean_all / n,
        s.max_all, median(s.ms), median(s.cpu_ms), s.sum_mean_seen / n, s.max_outside);
  }
  return 0;
}

}  // namespace occupancy_fusion
