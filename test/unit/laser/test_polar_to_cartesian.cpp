#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"
#include "occupancy_fusion/integrators/laser/polar_to_cartesian.h"
#include "occupancy_fusion/sim/laser_scanner.h"
#include "occupancy_fusion/sim/scenes.h"

namespace occupancy_fusion {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

LogOddsRaster emptyRaster(CellIndex origin, int width, int height,
                          double resolution) {
  LogOddsRaster r;
  r.resolution = resolution;
  r.origin_cell = origin;
  r.width = width;
  r.height = height;
  r.data.assign(static_cast<std::size_t>(width) * height, kNaN);
  return r;
}

// --- independent area computation: Sutherland-Hodgman
// -----------------------------------------
using Point = std::pair<double, double>;

double cross(const Point &o, const Point &a, const Point &b) {
  return (a.first - o.first) * (b.second - o.second) -
         (a.second - o.second) * (b.first - o.first);
}

// Clips `subject` by every edge of the counter-clockwise convex polygon `clip`.
std::vector<Point> sutherlandHodgman(std::vector<Point> subject,
                                     const std::vector<Point> &clip) {
  for (std::size_t e = 0; e < clip.size() && !subject.empty(); ++e) {
    const Point &a = clip[e];
    const Point &b = clip[(e + 1) % clip.size()];
    if (std::hypot(b.first - a.first, b.second - a.second) == 0.0)
      continue; // degenerate edge
    std::vector<Point> out;
    for (std::size_t i = 0; i < subject.size(); ++i) {
      const Point &s = subject[i];
      const Point &t = subject[(i + 1) % subject.size()];
      const double ds = cross(a, b, s);
      const double dt = cross(a, b, t);
      if (ds >= 0)
        out.push_back(s);
      if ((ds >= 0) != (dt >= 0)) {
        const double f = ds / (ds - dt);
        out.push_back({s.first + f * (t.first - s.first),
                       s.second + f * (t.second - s.second)});
      }
    }
    subject = out;
  }
  return subject;
}

double polygonArea(const std::vector<Point> &p) {
  double twice = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Point &a = p[i];
    const Point &b = p[(i + 1) % p.size()];
    twice += a.first * b.second - b.first * a.second;
  }
  return 0.5 * std::abs(twice);
}

// (cell, polar index) -> overlapped fraction of the cell, in world coordinates.
std::map<std::pair<int, int>, double>
independentOverlay(const OverlayGeometry &g) {
  std::map<std::pair<int, int>, double> areas;
  const double res = g.resolution;
  for (int b = 0; b < g.beams; ++b) {
    const double a0 =
        g.sensor.yaw + g.angle_min + (b - 0.5) * g.angle_increment;
    const double a1 = a0 + g.angle_increment;
    for (int k = 0; k < g.cells; ++k) {
      const double r0 = k * g.range_resolution;
      const double r1 = r0 + g.range_resolution;
      const std::vector<Point> quad = {
          {g.sensor.x + r0 * std::cos(a0), g.sensor.y + r0 * std::sin(a0)},
          {g.sensor.x + r1 * std::cos(a0), g.sensor.y + r1 * std::sin(a0)},
          {g.sensor.x + r1 * std::cos(a1), g.sensor.y + r1 * std::sin(a1)},
          {g.sensor.x + r0 * std::cos(a1), g.sensor.y + r0 * std::sin(a1)}};
      for (int y = 0; y < g.height; ++y) {
        for (int x = 0; x < g.width; ++x) {
          const double x0 = (g.origin_cell.x() + x) * res;
          const double y0 = (g.origin_cell.y() + y) * res;
          const std::vector<Point> square = {
              {x0, y0}, {x0 + res, y0}, {x0 + res, y0 + res}, {x0, y0 + res}};
          const double area =
              polygonArea(sutherlandHodgman(square, quad)) / (res * res);
          if (area > 1e-9)
            areas[{x + g.width * y, b * g.cells + k}] = area;
        }
      }
    }
  }
  return areas;
}

OverlayGeometry smallGeometry() {
  OverlayGeometry g;
  g.beams = 12;
  g.cells = 14;
  g.range_resolution = 0.07;
  g.angle_min = -0.5;
  g.angle_increment = 0.09;
  g.sensor = {0.013, -0.021, 0.3};
  g.resolution = 0.05;
  g.origin_cell = CellIndex(-6, -8);
  g.width = 26;
  g.height = 26;
  return g;
}

TEST(ExactOverlay, EqualsSutherlandHodgmanAreas) {
  const OverlayGeometry g = smallGeometry();
  const ExactOverlay overlay(g);
  const auto expected = independentOverlay(g);
  std::map<std::pair<int, int>, double> actual;
  for (int cell = 0; cell < g.width * g.height; ++cell) {
    for (auto *e = overlay.entriesBegin(cell); e != overlay.entriesEnd(cell);
         ++e) {
      actual[{cell, e->polar_index}] += e->weight;
    }
  }
  ASSERT_GT(expected.size(), 300u);
  for (const auto &[key, area] : expected) {
    const auto it = actual.find(key);
    ASSERT_NE(it, actual.end())
        << "cell " << key.first << " polar " << key.second;
    EXPECT_NEAR(it->second, area, 1e-6);
  }
  for (const auto &[key, area] : actual) {
    if (expected.count(key) == 0) {
      EXPECT_LT(area, 1e-6) << key.first << " " << key.second;
    }
  }
}

TEST(ExactOverlay, AppliedValuesEqualIndependentSum) {
  const OverlayGeometry g = smallGeometry();
  PolarField field;
  field.beams = g.beams;
  field.cells = g.cells;
  field.range_resolution = g.range_resolution;
  field.angle_min = g.angle_min;
  field.angle_increment = g.angle_increment;
  field.observed_cells.assign(static_cast<std::size_t>(g.beams), g.cells);
  for (int b = 0; b < g.beams; ++b) {
    for (int k = 0; k < g.cells; ++k) {
      field.value.push_back(
          static_cast<float>(std::sin(0.7 * b + 1.3 * k) * 2.0));
      field.observed.push_back(1.0f);
    }
  }
  LogOddsRaster raster =
      emptyRaster(g.origin_cell, g.width, g.height, g.resolution);
  ExactOverlay(g).apply(field, &raster);
  std::vector<double> expected(raster.data.size(), 0.0);
  std::vector<bool> touched(raster.data.size(), false);
  for (const auto &[key, area] : independentOverlay(g)) {
    expected[static_cast<std::size_t>(key.first)] +=
        area * field.value[key.second]; // Eq. 5
    touched[static_cast<std::size_t>(key.first)] = true;
  }
  for (std::size_t i = 0; i < expected.size(); ++i) {
    if (!touched[i]) {
      EXPECT_TRUE(std::isnan(raster.data[i])) << i;
      continue;
    }
    EXPECT_NEAR(raster.data[i], expected[i], 1e-6) << i;
  }
}

TEST(FastAtan2, MatchesStdAtan2) {
  double worst = 0.0;
  for (int i = 0; i < 3600; ++i) {
    const double a = -kPi + i * (2 * kPi / 3600) + 1e-4;
    for (double r : {1e-3, 1.0, 70.0}) {
      worst = std::max(worst,
                       std::abs(fastAtan2(r * std::sin(a), r * std::cos(a)) -
                                std::atan2(r * std::sin(a), r * std::cos(a))));
    }
  }
  EXPECT_LT(worst, 2e-6);
}

// A simulated 1-degree scan in the demo room, projected by every method.
struct RoomCase {
  LaserScan scan;
  Pose2D sensor{0.3, -0.2, 0.4};
  PolarField field;

  RoomCase() {
    sim::LaserScanner scanner;
    scanner.angle_increment = kPi / 180.0;
    scanner.range_max = 10.0;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() << sensor.x, sensor.y, 0.5;
    pose.linear() = Eigen::AngleAxisd(sensor.yaw, Eigen::Vector3d::UnitZ())
                        .toRotationMatrix();
    scan = toLaserScan(sim::renderScan(sim::makeRoomScene(), scanner, pose));
    field = buildPolarField(scan, LaserSensorModelConfig());
  }
  LogOddsRaster project(PolarToCartesianMethod method) const {
    LogOddsRaster raster = emptyRaster(CellIndex(-90, -70), 180, 140, 0.05);
    PolarLaserIntegrator integrator;
    integrator.project(field, sensor, method, &raster);
    return raster;
  }
};

double meanAbsDifference(const LogOddsRaster &a, const LogOddsRaster &b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    const double x = std::isnan(a.data[i]) ? 0.0 : a.data[i];
    const double y = std::isnan(b.data[i]) ? 0.0 : b.data[i];
    sum += std::abs(x - y);
  }
  return sum / static_cast<double>(a.data.size());
}

TEST(PolarToCartesian, SamplingAndMipmapCloseToExactLinesFar) {
  const RoomCase room;
  const LogOddsRaster exact = room.project(PolarToCartesianMethod::kExact);
  const double sampling =
      meanAbsDifference(room.project(PolarToCartesianMethod::kSampling), exact);
  const double mipmap =
      meanAbsDifference(room.project(PolarToCartesianMethod::kMipmap), exact);
  const double lines =
      meanAbsDifference(room.project(PolarToCartesianMethod::kLines), exact);
  std::printf("mean |delta| vs exact: sampling %.4f mipmap %.4f lines %.4f\n",
              sampling, mipmap, lines);
  EXPECT_LT(sampling, 0.2 * lines);
  EXPECT_LT(mipmap, 0.3 * lines);
  EXPECT_LT(sampling, 0.05);
  EXPECT_LT(mipmap, 0.08);
  // The exact grid sees the walls as occupied and the room's middle as free.
  const auto cell = [&](double x, double y) {
    return exact.at(static_cast<int>(std::floor(x / 0.05)) + 90,
                    static_cast<int>(std::floor(y / 0.05)) + 70);
  };
  EXPECT_LT(cell(1.0, -0.5), -1.0);
  EXPECT_TRUE(std::isnan(
      cell(-3.0, -2.5))); // behind the sensor, outside its field of view
}

TEST(PolarToCartesian, InvalidScanLeavesRasterAlone) {
  RoomCase room;
  for (float &r : room.scan.ranges)
    r = std::numeric_limits<float>::quiet_NaN();
  room.field = buildPolarField(room.scan, LaserSensorModelConfig());
  for (auto method :
       {PolarToCartesianMethod::kExact, PolarToCartesianMethod::kSampling,
        PolarToCartesianMethod::kMipmap, PolarToCartesianMethod::kLines}) {
    const LogOddsRaster raster = room.project(method);
    for (float v : raster.data)
      ASSERT_TRUE(std::isnan(v)) << methodName(method);
  }
}

TEST(PolarToCartesian, TwoScannersSumTheirLogRatios) {
  const RoomCase a;
  RoomCase b;
  b.sensor = {-1.0, 0.5, 2.5};
  b.field = buildPolarField(
      a.scan, LaserSensorModelConfig()); // any scan, seen from elsewhere
  PolarLaserIntegrator integrator;
  for (auto method :
       {PolarToCartesianMethod::kExact, PolarToCartesianMethod::kMipmap,
        PolarToCartesianMethod::kSampling, PolarToCartesianMethod::kLines}) {
    LogOddsRaster only_a = emptyRaster(CellIndex(-90, -70), 180, 140, 0.05);
    LogOddsRaster only_b = only_a;
    LogOddsRaster both = only_a;
    integrator.project(a.field, a.sensor, method, &only_a);
    integrator.project(b.field, b.sensor, method, &only_b);
    integrator.project(a.field, a.sensor, method, &both);
    integrator.project(b.field, b.sensor, method, &both);
    int overlap = 0;
    for (std::size_t i = 0; i < both.data.size(); ++i) {
      const float x = only_a.data[i];
      const float y = only_b.data[i];
      if (std::isnan(x) && std::isnan(y)) {
        EXPECT_TRUE(std::isnan(both.data[i]));
        continue;
      }
      const float sum = std::isnan(x) ? y : (std::isnan(y) ? x : x + y);
      overlap += !std::isnan(x) && !std::isnan(y);
      EXPECT_NEAR(both.data[i], sum, 1e-5) << methodName(method) << " " << i;
    }
    EXPECT_GT(overlap, 500) << methodName(method);
  }
  // The exact overlays of the two fixed geometries were computed once each.
  EXPECT_EQ(integrator.exactCache().builds(), 2u);
}

TEST(LocalLaserGrid, FusesScannersEachCycleWithCachedOverlays) {
  const RoomCase a;
  PolarLaserIntegratorConfig config;
  config.method = PolarToCartesianMethod::kExact;
  LocalLaserGridConfig grid_config;
  grid_config.size_x = 9.0;
  grid_config.size_y = 7.0;
  LocalLaserGrid grid(grid_config, config);
  grid.addScanner(a.sensor);
  grid.addScanner({-1.0, 0.5, 2.5});
  LogOddsRaster expected = emptyRaster(CellIndex(-90, -70), 180, 140, 0.05);
  PolarLaserIntegrator integrator(config);
  integrator.integrate(a.scan, a.sensor, &expected);
  integrator.integrate(a.scan, {-1.0, 0.5, 2.5}, &expected);
  for (int cycle = 0; cycle < 2; ++cycle) {
    const LogOddsRaster &fused = grid.fuse({a.scan, a.scan});
    ASSERT_EQ(fused.origin_cell, expected.origin_cell);
    ASSERT_EQ(fused.width, expected.width);
    for (std::size_t i = 0; i < fused.data.size(); ++i) {
      if (std::isnan(expected.data[i])) {
        ASSERT_TRUE(std::isnan(fused.data[i]));
      } else {
        ASSERT_FLOAT_EQ(fused.data[i], expected.data[i]);
      }
    }
  }
  EXPECT_THROW(grid.fuse({a.scan}), std::invalid_argument);
}

// Scanners with settings of their own (the LaserMapper's sources): each scan goes through its
// scanner's integrator; a remounted scanner's scans land at its new pose.
TEST(LocalLaserGrid, ScannersWithTheirOwnSettingsAndRemounted) {
  const RoomCase a;
  PolarLaserIntegratorConfig exact;
  exact.method = PolarToCartesianMethod::kExact;
  PolarLaserIntegratorConfig lines;
  lines.method = PolarToCartesianMethod::kLines;
  LocalLaserGridConfig grid_config;
  grid_config.size_x = 9.0;
  grid_config.size_y = 7.0;
  LocalLaserGrid grid(grid_config, PolarLaserIntegratorConfig());
  const int first = grid.addScanner(a.sensor, exact);
  const int second = grid.addScanner({-1.0, 0.5, 2.5}, lines);
  const auto expect = [&](const Pose2D& second_pose) {
    LogOddsRaster expected = emptyRaster(CellIndex(-90, -70), 180, 140, 0.05);
    PolarLaserIntegrator(exact).integrate(a.scan, a.sensor, &expected);
    PolarLaserIntegrator(lines).integrate(a.scan, second_pose, &expected);
    return expected;
  };
  const auto same = [](const LogOddsRaster& fused, const LogOddsRaster& expected) {
    std::size_t differing = 0;
    for (std::size_t i = 0; i < fused.data.size(); ++i) {
      const float x = fused.data[i], y = expected.data[i];
      differing += std::isnan(x) != std::isnan(y) || (!std::isnan(x) && x != y) ? 1 : 0;
    }
    return differing;
  };
  EXPECT_EQ(same(grid.fuse({a.scan, a.scan}), expect({-1.0, 0.5, 2.5})), 0u);
  grid.moveScanner(second, {0.5, -0.5, 1.0});
  const LogOddsRaster& moved = grid.fuse({a.scan, a.scan});
  EXPECT_EQ(same(moved, expect({0.5, -0.5, 1.0})), 0u);
  // The test can fail: the old pose's grid differs.
  EXPECT_GT(same(moved, expect({-1.0, 0.5, 2.5})), 100u);
  EXPECT_EQ(first, 0);
  EXPECT_THROW(grid.moveScanner(2, a.sensor), std::invalid_argument);
}

TEST(PolarLaserIntegrator, AccumulatesIntoWorldLayer) {
  const RoomCase room;
  GridLayer2D layer{GridLayer2DConfig()};
  PolarLaserIntegratorConfig config;
  config.method = PolarToCartesianMethod::kSampling;
  PolarLaserIntegrator integrator(config);
  integrator.integrateIntoLayer(room.scan, room.sensor, &layer);
  LogOddsRaster raster =
      rasterAround(room.field, room.sensor, layer.resolution());
  integrator.project(room.field, room.sensor, config.method, &raster);
  std::size_t known = 0;
  for (int y = 0; y < raster.height; ++y) {
    for (int x = 0; x < raster.width; ++x) {
      const auto value = layer.logOdds(raster.origin_cell + CellIndex(x, y));
      const float expected = raster.at(x, y);
      if (std::isnan(expected)) {
        EXPECT_FALSE(value.has_value());
        continue;
      }
      ASSERT_TRUE(value.has_value());
      EXPECT_NEAR(*value, layer.model().clamp(expected), 1e-6);
      ++known;
    }
  }
  EXPECT_EQ(known, layer.knownCellCount());
  EXPECT_EQ(layer.occupancyAt({1.0, -0.5}), Occupancy::kFree);
  EXPECT_GT(known, 5000u);
}

TEST(PlanarPose, UpsideDownScannerIsMirrored) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() << 1.0, 2.0, 0.3;
  T.linear() = (Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  bool upside_down = false;
  const Pose2D pose = planarPose(T, 0.1, &upside_down);
  EXPECT_TRUE(upside_down);
  EXPECT_NEAR(pose.yaw, 0.5, 1e-12);
  EXPECT_NEAR(pose.x, 1.0, 1e-12);
  // A beam at sensor angle +a points, in the frame, at yaw - a.
  LaserScan scan;
  scan.angle_min = -0.2;
  scan.angle_increment = 0.1;
  scan.range_max = 5;
  scan.ranges = {1.0f, 2.0f, 3.0f, 4.0f}; // beams at -0.2, -0.1, 0, 0.1
  const LaserScan mirrored = mirrorScan(scan);
  EXPECT_NEAR(mirrored.angle_min, -0.1, 1e-12);
  EXPECT_EQ(mirrored.ranges.front(),
            4.0f); // the beam at sensor angle +0.1 is now at -0.1
  const Eigen::Vector3d beam =
      T.linear() * Eigen::Vector3d(std::cos(0.1), std::sin(0.1), 0);
  EXPECT_NEAR(std::atan2(beam.y(), beam.x()), pose.yaw + mirrored.angle(0),
              1e-12);
  T.linear() =
      Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_THROW(planarPose(T, 0.1, &upside_down), std::invalid_argument);
}

} // namespace
} // namespace occupancy_fusion
