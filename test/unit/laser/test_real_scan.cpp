// The polar-to-cartesian methods on real scans: an excerpt of the MIT CSAIL CARMEN log (361
// beams, test/data/README.md), in the geometry of Yguel et al.'s Table I (the sensor at the
// middle of a long edge of the grid, facing into it), at a range_max of 25 m to keep the test
// fast.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"
#include "occupancy_fusion/integrators/laser/polar_to_cartesian.h"
#include "occupancy_fusion/sensors/carmen_log.h"

namespace occupancy_fusion {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::string excerptPath() {
  return std::string(OCCUPANCY_FUSION_SOURCE_DIR) + "/test/data/carmen_csail_excerpt.log";
}

std::vector<CarmenLaserScan> excerpt() {
  CarmenReadConfig read;
  read.range_max = 25.0;
  return readCarmenLog(excerptPath(), read);
}

LaserSensorModelConfig model() {
  LaserSensorModelConfig config;
  config.ranges.above_range_max_is_no_return = true;
  return config;
}

// 50 m x 25 m of 5 cm cells; the sensor at the middle of the lower edge looking along +y.
LogOddsRaster tableGrid() {
  LogOddsRaster raster;
  raster.resolution = 0.05;
  raster.width = 1000;
  raster.height = 500;
  raster.origin_cell = CellIndex(-500, 0);
  raster.data.assign(static_cast<std::size_t>(raster.width) * raster.height, kNaN);
  return raster;
}
const Pose2D kSensor{0.0, 0.0, 0.5 * kPi};

TEST(RealScans, ExcerptHoldsCsailScans) {
  const std::vector<CarmenLaserScan> scans = excerpt();
  ASSERT_EQ(scans.size(), 41u);
  for (const CarmenLaserScan& s : scans) EXPECT_EQ(s.scan.beamCount(), 361);
}

// Reusing the previous scan's buffers gives exactly the field built from scratch, whatever the
// previous scan observed (longer or shorter beams, hits and no-returns).
TEST(RealScans, ReusedPolarFieldEqualsFreshOne) {
  const std::vector<CarmenLaserScan> scans = excerpt();
  LaserSensorModelConfig config = model();
  config.no_return_free_length = 4.0;
  PolarField reused;
  for (const CarmenLaserScan& s : scans) {
    buildPolarField(s.scan, config, &reused);
    const PolarField fresh = buildPolarField(s.scan, config);
    ASSERT_EQ(reused.beams, fresh.beams);
    ASSERT_EQ(reused.cells, fresh.cells);
    ASSERT_EQ(reused.observed_cells, fresh.observed_cells);
    ASSERT_EQ(reused.value, fresh.value);
    ASSERT_EQ(reused.observed, fresh.observed);
  }
}

// The exact overlay's application skips the tiles no observed polar cell reaches; the result
// equals Eq. 5 gathered over every cell of the grid from the overlay's entries.
TEST(RealScans, SparseExactEqualsDenseGather) {
  const std::vector<CarmenLaserScan> scans = excerpt();
  const LaserSensorModelConfig config = model();
  PolarField field = buildPolarField(scans.front().scan, config);
  LogOddsRaster raster = tableGrid();
  const ExactOverlay overlay(OverlayGeometry::of(field, kSensor, raster));
  for (std::size_t i : {std::size_t{0}, std::size_t{20}, std::size_t{40}}) {
    buildPolarField(scans[i].scan, config, &field);
    std::fill(raster.data.begin(), raster.data.end(), kNaN);
    overlay.apply(field, &raster);
    std::size_t written = 0;
    for (int cell = 0; cell < raster.width * raster.height; ++cell) {
      double sum = 0.0;
      double coverage = 0.0;
      for (auto e = overlay.entriesBegin(cell); e != overlay.entriesEnd(cell); ++e) {
        sum += e->weight * field.value[static_cast<std::size_t>(e->polar_index)];
        coverage += e->weight * field.observed[static_cast<std::size_t>(e->polar_index)];
      }
      const float got = raster.data[static_cast<std::size_t>(cell)];
      if (coverage == 0.0) {
        ASSERT_TRUE(std::isnan(got)) << "scan " << i << " cell " << cell;
        continue;
      }
      ++written;
      ASSERT_NEAR(got, sum, 1e-5) << "scan " << i << " cell " << cell;
    }
    EXPECT_GT(written, 5000u);  // a real scan observes more than 12 m^2
  }
}

// Table I's relations on real scans: sampling and mipmap are far closer to exact than the lines
// are (the paper: sampling mean 0.11x, max 0.05x of the lines'; GPU mean 0.15x, max 0.07x), and
// exact sees the walls occupied.
TEST(RealScans, SamplingAndMipmapFarCloserToExactThanLines) {
  const std::vector<CarmenLaserScan> scans = excerpt();
  const LaserSensorModelConfig config = model();
  PolarLaserIntegratorConfig integrator_config;
  integrator_config.model = config;
  PolarLaserIntegrator integrator(integrator_config);
  PolarField field;
  LogOddsRaster exact = tableGrid();
  LogOddsRaster other = tableGrid();
  const PolarToCartesianMethod methods[] = {PolarToCartesianMethod::kLines,
                                            PolarToCartesianMethod::kSampling,
                                            PolarToCartesianMethod::kMipmap};
  double mean[3] = {0, 0, 0};
  double max[3] = {0, 0, 0};
  int occupied_cells = 0;
  const std::size_t used[] = {0, 10, 20, 30, 40};
  for (std::size_t i : used) {
    buildPolarField(scans[i].scan, config, &field);
    std::fill(exact.data.begin(), exact.data.end(), kNaN);
    integrator.project(field, kSensor, PolarToCartesianMethod::kExact, &exact);
    for (float v : exact.data) occupied_cells += !std::isnan(v) && v > 0.2f;
    for (int m = 0; m < 3; ++m) {
      std::fill(other.data.begin(), other.data.end(), kNaN);
      integrator.project(field, kSensor, methods[m], &other);
      double sum = 0.0;
      for (std::size_t c = 0; c < exact.data.size(); ++c) {
        const double a = std::isnan(exact.data[c]) ? 0.0 : exact.data[c];
        const double b = std::isnan(other.data[c]) ? 0.0 : other.data[c];
        sum += std::abs(a - b);
        max[m] = std::max(max[m], std::abs(a - b));
      }
      mean[m] += sum / static_cast<double>(exact.data.size()) / std::size(used);
    }
  }
  std::printf("mean / max |delta|: lines %.4f / %.2f sampling %.4f / %.2f mipmap %.4f / %.2f\n",
              mean[0], max[0], mean[1], max[1], mean[2], max[2]);
  EXPECT_GT(occupied_cells, 1000);
  EXPECT_LT(mean[1], 0.11 * mean[0]);
  EXPECT_LT(max[1], 0.05 * max[0]);
  EXPECT_LT(mean[2], 0.15 * mean[0]);
  EXPECT_LT(max[2], 0.07 * max[0]);
  // Absolute: within the sensor model's range of one scan's values, [-2, 3.5].
  EXPECT_LT(max[1], 5.5);
  EXPECT_LT(max[2], 5.5);
}

}  // namespace
}  // namespace occupancy_fusion
