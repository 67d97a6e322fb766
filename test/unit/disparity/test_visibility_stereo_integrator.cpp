// The visibility-aware stereo integrator: Eq. 1-8 by hand, on hand-built maps, and the OctoMap
// mode against the OctoMap-equivalent point-cloud integrator.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "occupancy_fusion/integrators/point_cloud_integrator.h"
#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/integrators/stereo/visibility_stereo_integrator.h"

namespace occupancy_fusion {
namespace {

const VisibilityStereoConfig kTableI;  // the defaults are Table I's values

// One ray per point (bundle_rays off): the tests of the per-ray reduction and of the OctoMap
// equivalence with the per-point integrator.
VisibilityStereoConfig perRay(VisibilityStereoConfig config = {}) {
  config.bundle_rays = false;
  return config;
}

double logOddsOf(double p) { return std::log(p / (1 - p)); }

TEST(VisibilityEquationsTest, NormalCdfTableMatchesErfc) {
  const NormalCdfTable phi;
  double worst = 0;
  for (double x = -7.0; x <= 7.0; x += 0.001) {
    worst = std::max(worst, std::abs(phi(x) - 0.5 * std::erfc(-x / std::sqrt(2.0))));
  }
  EXPECT_LT(worst, 2e-6);
  EXPECT_DOUBLE_EQ(phi(0.0), 0.5);
}

TEST(VisibilityEquationsTest, Equation3WithQmaxClamp) {
  // P(V_i) = P(V_i-1) (0.2 P(C) + 1.0 (1 - P(C))).
  EXPECT_NEAR(nextVisibility(1.0, 0.5, kTableI), 0.6, 1e-12);
  EXPECT_NEAR(nextVisibility(0.6, 0.5, kTableI), 0.36, 1e-12);
  EXPECT_NEAR(nextVisibility(0.5, 0.0, kTableI), 0.5, 1e-12);
  // 1 - 0.8 * 0.2 = 0.84 >= q_max = 0.7 counts as fully visible.
  EXPECT_EQ(nextVisibility(1.0, 0.2, kTableI), 1.0);
  EXPECT_NEAR(nextVisibility(1.0, 0.971, kTableI), 1 - 0.8 * 0.971, 1e-12);
}

TEST(VisibilityEquationsTest, Equations4To6ByHand) {
  // Visible hit at P(O) = 0.5: 0.55 * 0.5 / (0.55 * 0.5 + 0.43 * 0.5) = 0.55 / 0.98.
  EXPECT_NEAR(occupancyAfterMeasurement(0.5, true, 1.0, kTableI), 0.55 / 0.98, 1e-12);
  // Visible miss at 0.3: 0.45 * 0.3 / (0.45 * 0.3 + 0.57 * 0.7) = 0.135 / 0.534.
  EXPECT_NEAR(occupancyAfterMeasurement(0.3, false, 1.0, kTableI), 0.135 / 0.534, 1e-12);
  // Half visible hit at 0.5: P(H|O) = 0.05 * 0.5 + 0.55 * 0.5 = 0.3,
  // P(H) = 0.025 + 0.5 (0.55 * 0.5 + 0.43 * 0.5) = 0.27, P(O|H) = 0.15 / 0.27.
  EXPECT_NEAR(occupancyAfterMeasurement(0.5, true, 0.5, kTableI), 0.15 / 0.27, 1e-12);
  // Visibility 0.6 miss at 0.5: P(~H|O) = 0.95 * 0.4 + 0.45 * 0.6 = 0.65,
  // P(~H) = 0.38 + 0.6 (0.225 + 0.285) = 0.686.
  EXPECT_NEAR(occupancyAfterMeasurement(0.5, false, 0.6, kTableI), 0.325 / 0.686, 1e-12);
  // Invisible: no information either way.
  EXPECT_NEAR(occupancyAfterMeasurement(0.8, true, 0.0, kTableI), 0.8, 1e-12);
  EXPECT_NEAR(occupancyAfterMeasurement(0.8, false, 0.0, kTableI), 0.8, 1e-12);
  // Eq. 8 at P(I) = 0.25: 0.25 * 0.55 / 0.98 + 0.75 * 0.45 / 1.02.
  EXPECT_NEAR(occupancyAfterInterpolatedMeasurement(0.5, 0.25, 1.0, kTableI),
              0.25 * 0.55 / 0.98 + 0.75 * 0.45 / 1.02, 1e-12);
}

TEST(VisibilityEquationsTest, FullVisibilityIsALogOddsSum) {
  // At P(V) = 1, Eq. 4-6 reduce to OctoMap's log-odds update with the hit and miss log-odds
  // log(0.55 / 0.43) and log(0.45 / 0.57).
  for (double p : {0.12, 0.3, 0.5, 0.8, 0.97}) {
    EXPECT_NEAR(logOddsOf(occupancyAfterMeasurement(p, true, 1.0, kTableI)),
                logOddsOf(p) + std::log(0.55 / 0.43), 1e-9);
    EXPECT_NEAR(logOddsOf(occupancyAfterMeasurement(p, false, 1.0, kTableI)),
                logOddsOf(p) + std::log(0.45 / 0.57), 1e-9);
  }
}

TEST(VisibilityEquationsTest, ValidationNamesTheField) {
  VisibilityStereoConfig config;
  config.visibility_min = 0.8;  // above q_max
  try {
    config.validate();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("visibility_min"), std::string::npos);
  }
  config = VisibilityStereoConfig();
  config.prob_hit_visible_free = 0.6;
  EXPECT_THROW(VisibilityStereoIntegrator{config}, std::invalid_argument);
  EXPECT_EQ(stereoIntegrationMethodFromString("octomap"), StereoIntegrationMethod::kOctomap);
  EXPECT_THROW(stereoIntegrationMethodFromString("bayes"), std::invalid_argument);
}

// A ray along +x through voxels (k, 0, 0) of a 0.1 m map, from the centre of voxel 0 to a point
// in voxel 15. The ray stays in the sensor's y and z slabs, so each voxel's only sensor-facing
// neighbour is (k - 1, 0, 0) (Eq. 1).
constexpr double kRes = 0.1;
const Eigen::Vector3d kOrigin(0.05, 0.05, 0.05);
const Eigen::Vector3f kPoint(1.52f, 0.05f, 0.05f);
constexpr float kTinySigma = 1e-4f;

VoxelMapConfig mapConfig() {
  VoxelMapConfig config;
  config.resolution = kRes;
  return config;
}

double probabilityAt(const VoxelMap& map, int k) {
  const auto value = map.logOdds(VoxelIndex(k, 0, 0));
  return value ? probabilityFromLogOdds(*value) : -1.0;  // -1: unknown
}

void integrateOnePoint(const VisibilityStereoConfig& config, VoxelMap* map) {
  VisibilityStereoIntegrator(config).integrate({kPoint}, {kTinySigma}, kOrigin, map);
}

// Known free space (P(O) = 0.3) along the ray, optionally with an occupied wall at x = 10, 11.
void fillFreeCorridor(bool wall, VoxelMap* map_pointer) {
  VoxelMap& map = *map_pointer;
  for (int k = 0; k <= 17; ++k) map.setLogOdds(VoxelIndex(k, 0, 0), logit(0.3));
  if (wall) {
    for (int k : {10, 11}) map.setLogOdds(VoxelIndex(k, 0, 0), map.maxLogOdds());
  }
}

TEST(VisibilityStereoIntegratorTest, FreeMapEverythingVisible) {
  VoxelMap map(mapConfig());
  fillFreeCorridor(false, &map);
  integrateOnePoint(kTableI, &map);
  // P(C) = 0.3 gives 1 - 0.8 * 0.3 = 0.76 >= q_max: all visible. Voxels 0..14 lie before the
  // point (their centres at s < 1.47 m along the ray): visible misses, 0.135 / 0.534.
  for (int k = 0; k <= 14; ++k) EXPECT_NEAR(probabilityAt(map, k), 0.135 / 0.534, 1e-6) << k;
  // Voxel 15's centre is past the point by 0.03 m = 300 sigma: P(I) = 1, the full hit, and the
  // ray stops: 0.55 * 0.3 / (0.165 + 0.43 * 0.7).
  EXPECT_NEAR(probabilityAt(map, 15), 0.165 / 0.466, 1e-6);
  EXPECT_NEAR(probabilityAt(map, 16), 0.3, 1e-6);
}

// clear_passed: the point lies 0.5 m behind the wall (voxels 10, 11) with a tiny sigma, so the
// ray passed the wall clearly: the wall no longer hides what is behind it, and every voxel the
// ray passed takes the passed miss, logit(0.3) (the frame saw through the place something left):
// the wall's max + logit(0.3), the free ones 2 logit(0.3), P = 0.09 / 0.58; the point's voxel
// its hit. Five such frames bring a clamped voxel to free.
TEST(VisibilityStereoIntegratorTest, ClearPassedSeesThroughWhatHasLeft) {
  VisibilityStereoConfig config = kTableI;
  config.clear_passed = true;
  VoxelMap map(mapConfig());
  fillFreeCorridor(true, &map);
  integrateOnePoint(config, &map);
  const float passed = static_cast<float>(logit(config.passed_miss_probability));
  for (int k : {10, 11}) {
    EXPECT_NEAR(*map.logOdds(VoxelIndex(k, 0, 0)), map.maxLogOdds() + passed, 1e-5) << k;
  }
  for (int k = 0; k <= 13; ++k) {
    if (k == 10 || k == 11) continue;
    EXPECT_NEAR(probabilityAt(map, k), 0.09 / 0.58, 1e-6) << k;
  }
  // Voxel 14 reaches past 1.52 m (its centre 1.45 m plus half a diagonal): Eq. 4-8's visible
  // miss; voxel 15 the hit, as before.
  EXPECT_NEAR(probabilityAt(map, 14), 0.135 / 0.534, 1e-6);
  EXPECT_NEAR(probabilityAt(map, 15), 0.165 / 0.466, 1e-6);
  for (int frame = 1; frame < 5; ++frame) integrateOnePoint(config, &map);
  EXPECT_EQ(map.occupancy(VoxelIndex(10, 0, 0)), Occupancy::kFree);
  EXPECT_EQ(map.occupancy(VoxelIndex(11, 0, 0)), Occupancy::kFree);
}

// A voxel within passed_sigmas of the point is not passed (the measurement's own uncertainty),
// nor is one that another ray of the frame ends in: a surface seen at a grazing angle stays.
TEST(VisibilityStereoIntegratorTest, ClearPassedKeepsWhatTheFrameStillMeasures) {
  VisibilityStereoConfig config = kTableI;
  config.clear_passed = true;
  {
    VoxelMap map(mapConfig());
    fillFreeCorridor(true, &map);
    // The point 0.5 m behind the wall's front but with sigma 0.2 m: the wall lies within 3 sigma.
    VisibilityStereoIntegrator(config).integrate({kPoint}, {0.2f}, kOrigin, &map);
    VoxelMap plain(mapConfig());
    fillFreeCorridor(true, &plain);
    VisibilityStereoIntegrator(kTableI).integrate({kPoint}, {0.2f}, kOrigin, &plain);
    // The wall (its far side 1.29 m out, past 1.52 - 3 * 0.2 m) and what lies behind it: as
    // without clear_passed; voxels up to 0.92 m out were passed.
    for (int k = 9; k <= 17; ++k) {
      EXPECT_EQ(map.logOdds(VoxelIndex(k, 0, 0)), plain.logOdds(VoxelIndex(k, 0, 0))) << k;
    }
    EXPECT_NEAR(probabilityAt(map, 5), 0.09 / 0.58, 1e-6);
  }
  VoxelMap map(mapConfig());
  fillFreeCorridor(true, &map);
  // A second ray ends in voxel 10: it is hit, not cleared.
  VisibilityStereoIntegrator(perRay(config))
      .integrate({kPoint, Eigen::Vector3f(1.04f, 0.05f, 0.05f)}, {kTinySigma, kTinySigma}, kOrigin,
                 &map);
  EXPECT_GT(*map.logOdds(VoxelIndex(10, 0, 0)), map.maxLogOdds() - 0.01f);
  EXPECT_NEAR(*map.logOdds(VoxelIndex(11, 0, 0)),
              map.maxLogOdds() + static_cast<float>(logit(config.passed_miss_probability)), 1e-5);
}

TEST(VisibilityStereoIntegratorTest, KnownWallHidesTheVoxelsBehindIt) {
  VoxelMap map(mapConfig());
  fillFreeCorridor(true, &map);
  integrateOnePoint(kTableI, &map);
  for (int k = 0; k <= 9; ++k) EXPECT_NEAR(probabilityAt(map, k), 0.135 / 0.534, 1e-6) << k;
  // Voxel 10 (the wall's face) is visible: a miss at P(O) = clamp_max.
  const double wall = probabilityFromLogOdds(map.maxLogOdds());
  EXPECT_NEAR(probabilityAt(map, 10), 0.45 * wall / (0.45 * wall + 0.57 * (1 - wall)), 1e-5);
  // Voxel 11 sits behind an occupied voxel: V = 1 - 0.8 * clamp_max = 0.2232, a weak miss.
  const double v11 = 1 - 0.8 * wall;
  EXPECT_NEAR(probabilityAt(map, 11), occupancyAfterMeasurement(wall, false, v11, kTableI), 1e-5);
  // Voxel 12: V = 0.2232^2 < q_min, the ray stops. The measurement at voxel 15 changes nothing.
  for (int k = 12; k <= 17; ++k) EXPECT_NEAR(probabilityAt(map, k), 0.3, 1e-6) << k;

  // OctoMap's update on the same ray clears the wall and marks voxel 15 occupied.
  VoxelMap octomap(mapConfig());
  fillFreeCorridor(true, &octomap);
  VisibilityStereoConfig octomap_config;
  octomap_config.method = StereoIntegrationMethod::kOctomap;
  integrateOnePoint(octomap_config, &octomap);
  // logit(0.3) + logit(0.7) = 0: the hit raised voxel 15 from 0.3 to 0.5.
  EXPECT_NEAR(probabilityAt(octomap, 15), 0.5, 1e-6);
  EXPECT_LT(probabilityAt(octomap, 11), probabilityFromLogOdds(octomap.maxLogOdds()));
}

TEST(VisibilityStereoIntegratorTest, UnknownMapIsMappedAFewVoxelsPerFrame) {
  // Unknown voxels count as P(O) = 0.5 (Eq. 1): V = 1 (the sensor's voxel has no facing
  // neighbour), 0.6, 0.36, 0.216, 0.1296, then 0.078 < q_min stops the ray: 5 voxels.
  VoxelMap map(mapConfig());
  VisibilityStereoIntegrator integrator(kTableI);
  const StereoIntegrationStats stats = integrator.integrate({kPoint}, {kTinySigma}, kOrigin, &map);
  EXPECT_EQ(stats.rays_invisible, 1u);
  EXPECT_EQ(stats.updated_voxels, 5u);
  EXPECT_EQ(map.knownVoxelCount(), 5u);
  EXPECT_NEAR(probabilityAt(map, 0), 0.45 / 1.02, 1e-6);
  EXPECT_NEAR(probabilityAt(map, 1), 0.325 / 0.686, 1e-6);
  EXPECT_NEAR(probabilityAt(map, 4), occupancyAfterMeasurement(0.5, false, 0.1296, kTableI), 1e-6);
  EXPECT_EQ(probabilityAt(map, 5), -1.0);
  // Repeating the frame pushes the frontier out (Fig. 5a): after enough frames the hit lands.
  int frames = 1;
  while (probabilityAt(map, 15) <= 0.5 && frames < 100) {
    integrator.integrate({kPoint}, {kTinySigma}, kOrigin, &map);
    ++frames;
  }
  EXPECT_GT(frames, 3);
  EXPECT_LT(frames, 100);
}

TEST(VisibilityStereoIntegratorTest, DepthErrorSpreadsTheHitPastThePoint) {
  // sigma = 0.1 m: voxel k's centre lies at x = ((k + 0.5) 0.1 - 0.05 - 1.47) / 0.1 sigmas past
  // the point, P(I) = Phi(x): voxel 14 at -0.7, 15 at 0.3, ..., 17 at 2.3 (Phi = 0.989 < 0.99).
  // Voxel 18 (x = 3.3) is the first at or above 0.99: it gets the full hit and the ray stops.
  VoxelMap map(mapConfig());
  fillFreeCorridor(false, &map);
  for (int k = 18; k <= 20; ++k) map.setLogOdds(VoxelIndex(k, 0, 0), logit(0.3));
  VisibilityStereoIntegrator(kTableI).integrate({kPoint}, {0.1f}, kOrigin, &map);
  const NormalCdfTable phi;
  for (int k : {13, 14, 15, 16, 17}) {
    const double x = ((k + 0.5) * kRes - 0.05 - 1.47) / 0.1;
    EXPECT_NEAR(probabilityAt(map, k),
                occupancyAfterInterpolatedMeasurement(0.3, phi(x), 1.0, kTableI), 1e-5)
        << k;
  }
  EXPECT_NEAR(probabilityAt(map, 18), 0.165 / 0.466, 1e-6);
  EXPECT_NEAR(probabilityAt(map, 19), 0.3, 1e-6);
}

// Random rays through a map with scattered occupied voxels.
struct RandomFrame {
  std::vector<Eigen::Vector3f> points;
  std::vector<float> sigmas;
};

RandomFrame randomFrame(int count, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> lateral(-1.0f, 1.0f), depth(1.0f, 3.0f), sigma(0.0f, 0.2f);
  RandomFrame frame;
  for (int i = 0; i < count; ++i) {
    frame.points.emplace_back(depth(random), lateral(random), 0.5f * lateral(random));
    frame.sigmas.push_back(sigma(random));
  }
  return frame;
}

void scatter(unsigned seed, VoxelMap* map_pointer) {
  VoxelMap& map = *map_pointer;
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> x(0, 30), y(-10, 10), z(-5, 5);
  std::uniform_real_distribution<double> p(0.05, 0.95);
  for (int i = 0; i < 3000; ++i)
    map.setLogOdds(VoxelIndex(x(random), y(random), z(random)), logit(p(random)));
}

using UpdateTable = std::map<std::tuple<int, int, int>, std::pair<float, float>>;
UpdateTable asTable(const std::vector<StereoVoxelUpdate>& updates) {
  UpdateTable table;
  for (const StereoVoxelUpdate& u : updates) {
    const auto key = std::make_tuple(u.index.x(), u.index.y(), u.index.z());
    EXPECT_EQ(table.count(key), 0u) << "one update per voxel";
    table[key] = {u.p_inside, u.visibility};
  }
  return table;
}

TEST(VisibilityStereoIntegratorTest, OneUpdatePerVoxelTakesTheLargestInsideAndVisibility) {
  // Our choice where several rays reach a voxel in one frame: the largest P(I_v) (a hit wins, as
  // in OctoMap) and the largest P(V_v) (a voxel is visible if any ray sees it). Checked against
  // each ray cast on its own.
  VoxelMap map(mapConfig());
  scatter(3, &map);
  const RandomFrame frame = randomFrame(60, 4);
  const VisibilityStereoIntegrator integrator(perRay());
  std::vector<StereoVoxelUpdate> updates;
  integrator.computeUpdates(frame.points, frame.sigmas, kOrigin, map, &updates);
  const UpdateTable together = asTable(updates);
  UpdateTable expected;
  for (std::size_t i = 0; i < frame.points.size(); ++i) {
    integrator.computeUpdates({frame.points[i]}, {frame.sigmas[i]}, kOrigin, map, &updates);
    for (const auto& [key, values] : asTable(updates)) {
      auto [it, inserted] = expected.try_emplace(key, values);
      it->second.first = std::max(it->second.first, values.first);
      it->second.second = std::max(it->second.second, values.second);
    }
  }
  ASSERT_EQ(together.size(), expected.size());
  int different_visibilities = 0;
  for (const auto& [key, values] : expected) {
    ASSERT_EQ(together.count(key), 1u);
    EXPECT_FLOAT_EQ(together.at(key).first, values.first);
    EXPECT_FLOAT_EQ(together.at(key).second, values.second);
    different_visibilities += values.second < 1.0f ? 1 : 0;
  }
  EXPECT_GT(different_visibilities, 10);  // the map does occlude some of them
}

TEST(VisibilityStereoIntegratorTest, CacheDoesNotChangeTheResult) {
  // The previous-ray cache only skips look-ups: shuffling the rays (other cache hits) gives the
  // same updates.
  VoxelMap map(mapConfig());
  scatter(5, &map);
  RandomFrame frame = randomFrame(2000, 6);
  std::vector<std::size_t> order(frame.points.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  // Sorting by direction makes neighbouring rays alike, as neighbouring pixels are.
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::atan2(frame.points[a].y(), frame.points[a].x()) <
           std::atan2(frame.points[b].y(), frame.points[b].x());
  });
  RandomFrame sorted;
  for (std::size_t i : order) {
    sorted.points.push_back(frame.points[i]);
    sorted.sigmas.push_back(frame.sigmas[i]);
  }
  const VisibilityStereoIntegrator integrator(perRay());
  std::vector<StereoVoxelUpdate> a, b;
  const StereoIntegrationStats random_stats =
      integrator.computeUpdates(frame.points, frame.sigmas, kOrigin, map, &a);
  const StereoIntegrationStats sorted_stats =
      integrator.computeUpdates(sorted.points, sorted.sigmas, kOrigin, map, &b);
  EXPECT_EQ(asTable(a), asTable(b));
  EXPECT_GT(sorted_stats.cacheHitRate(), random_stats.cacheHitRate());
  EXPECT_GT(sorted_stats.cacheHitRate(), 0.3);
  EXPECT_LE(sorted_stats.cache_hits, sorted_stats.voxel_visits);
}

// shift: added to the sensor and the points (float points, as the integrators take them).
void expectOctomapModeEqualsPointCloudIntegrator(double max_range,
                                                 const Eigen::Vector3f& shift = {0, 0, 0}) {
  VisibilityStereoConfig config = perRay();
  config.method = StereoIntegrationMethod::kOctomap;
  config.max_range = max_range;
  const VisibilityStereoIntegrator stereo(config);
  PointCloudIntegratorConfig cloud_config;
  cloud_config.max_range = max_range;
  const PointCloudIntegrator cloud(cloud_config);
  VoxelMap ours(mapConfig());
  VoxelMap reference(mapConfig());
  for (unsigned frame = 0; frame < 3; ++frame) {
    RandomFrame points = randomFrame(3000, 10 + frame);
    for (Eigen::Vector3f& point : points.points) point += shift;
    const Eigen::Vector3d origin =
        Eigen::Vector3d(0.03 * frame, -0.02 * frame, 0.01) + shift.cast<double>();
    stereo.integrate(points.points, points.sigmas, origin, &ours);
    cloud.integrate(points.points, origin, &reference);
  }
  ASSERT_EQ(ours.knownVoxelCount(), reference.knownVoxelCount());
  std::size_t compared = 0;
  reference.forEachKnownVoxel([&](const VoxelIndex& index, float value) {
    const auto mine = ours.logOdds(index);
    ASSERT_TRUE(mine.has_value());
    EXPECT_FLOAT_EQ(*mine, value);
    ++compared;
  });
  EXPECT_GT(compared, 1000u);
}

TEST(VisibilityStereoIntegratorTest, OctomapModeEqualsPointCloudIntegrator) {
  expectOctomapModeEqualsPointCloudIntegrator(-1.0);
}

TEST(VisibilityStereoIntegratorTest, OctomapModeMaxRangeEqualsPointCloudIntegrator) {
  // The points lie 1-3.4 m away: about half are beyond 2 m and clear their rays up to 2 m only.
  expectOctomapModeEqualsPointCloudIntegrator(2.0);
}

TEST(VisibilityStereoIntegratorTest, OctomapModeFarFromTheOriginEqualsPointCloudIntegrator) {
  // The frame's table keys blocks relative to the sensor's block: far out, at negative
  // coordinates and across block borders on every axis, no two voxels may share an entry.
  expectOctomapModeEqualsPointCloudIntegrator(-1.0, Eigen::Vector3f(-4000.37f, 2500.81f, -63.95f));
}

// bundle_rays: groups of points sharing a voxel at different depths and lateral positions, as the
// pixels of a far surface; some groups come back later (the hash table rather than the last
// voxel finds them) and some voxels are drawn twice.
RandomFrame crowdedFrame(unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> x(10, 29), y(-10, 10), z(-5, 5), size(1, 12);
  std::uniform_real_distribution<float> within(0.01f, 0.99f), sigma(0.0f, 0.2f);
  std::vector<VoxelIndex> voxels;
  for (int v = 0; v < 60; ++v) voxels.emplace_back(x(random), y(random), z(random));
  for (int v = 0; v < 20; ++v) voxels.push_back(voxels[v * 2]);  // a later group of a voxel
  RandomFrame frame;
  for (const VoxelIndex& voxel : voxels) {
    for (int i = size(random); i > 0; --i) {
      const Eigen::Vector3f in_voxel(within(random), within(random), within(random));
      frame.points.push_back((voxel.cast<float>() + in_voxel) * static_cast<float>(kRes));
      frame.sigmas.push_back(sigma(random));
    }
  }
  return frame;
}

// Per voxel the nearest and the farthest point (the first of equals; one point if they are the
// same), in the order of the voxels' first points; only the nearest with ends = 1.
RandomFrame endsPerVoxel(const RandomFrame& frame, const Eigen::Vector3d& origin, int ends = 2) {
  std::map<std::tuple<int, int, int>, std::pair<std::size_t, std::size_t>> ends_of_voxel;
  std::vector<std::tuple<int, int, int>> order;
  const auto range = [&](std::size_t i) {
    return (frame.points[i].cast<double>() - origin).squaredNorm();
  };
  for (std::size_t i = 0; i < frame.points.size(); ++i) {
    const VoxelIndex v = voxelIndexOf(frame.points[i].cast<double>(), kRes);
    const auto key = std::make_tuple(v.x(), v.y(), v.z());
    const auto [it, inserted] = ends_of_voxel.try_emplace(key, i, i);
    if (inserted) order.push_back(key);
    if (range(i) < range(it->second.first)) it->second.first = i;
    if (range(i) > range(it->second.second)) it->second.second = i;
  }
  RandomFrame selected;
  for (const auto& key : order) {
    const auto [nearest, farthest] = ends_of_voxel.at(key);
    selected.points.push_back(frame.points[nearest]);
    selected.sigmas.push_back(frame.sigmas[nearest]);
    if (ends == 2 && farthest != nearest) {
      selected.points.push_back(frame.points[farthest]);
      selected.sigmas.push_back(frame.sigmas[farthest]);
    }
  }
  return selected;
}

// Points at several depths on lines of sight from the origin, a few per end voxel: the rays to a
// voxel's nearest and farthest point cross the same voxels.
RandomFrame pointsOnLinesOfSight(unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> lateral(-0.8, 0.8), range(1.0, 2.8), sigma(0.0, 0.2);
  std::uniform_real_distribution<double> apart(0.0, kRes);
  std::uniform_int_distribution<int> size(1, 4);
  RandomFrame frame;
  for (int line = 0; line < 300; ++line) {
    const Eigen::Vector3d direction =
        Eigen::Vector3d(1.0, lateral(random), 0.5 * lateral(random)).normalized();
    const double first = range(random);
    for (int i = size(random); i > 0; --i) {
      frame.points.push_back((kOrigin + (first + apart(random)) * direction).cast<float>());
      frame.sigmas.push_back(static_cast<float>(sigma(random)));
    }
  }
  return frame;
}

// A frame bundled (Table I's defaults) against its voxels' nearest and farthest points cast as
// rays of their own and reduced, on a scattered map.
struct BundledAgainstTwoWalks {
  explicit BundledAgainstTwoWalks(const RandomFrame& frame) : map(mapConfig()) {
    scatter(7, &map);
    const RandomFrame ends = endsPerVoxel(frame, kOrigin);
    end_voxels = endsPerVoxel(frame, kOrigin, 1).points.size();
    two_end_voxels = ends.points.size() - end_voxels;
    std::vector<StereoVoxelUpdate> updates;
    bundled_stats = VisibilityStereoIntegrator(kTableI).computeUpdates(frame.points, frame.sigmas,
                                                                       kOrigin, map, &updates);
    bundled = asTable(updates);
    two_walks_stats = VisibilityStereoIntegrator(perRay()).computeUpdates(ends.points, ends.sigmas,
                                                                          kOrigin, map, &updates);
    two_walks = asTable(updates);
  }
  VoxelMap map;
  std::size_t end_voxels = 0, two_end_voxels = 0;
  StereoIntegrationStats bundled_stats, two_walks_stats;
  UpdateTable bundled, two_walks;
};

TEST(VisibilityStereoIntegratorTest, BundledRaysWalkToTheFarthestPointWithTheNearestPointsToo) {
  const RandomFrame frame = pointsOnLinesOfSight(8);
  const BundledAgainstTwoWalks run(frame);
  ASSERT_GT(run.two_end_voxels, 100u);
  // Each ray on its own, reduced: the same updates where both rays cross the same voxels.
  EXPECT_EQ(run.bundled, run.two_walks);
  EXPECT_EQ(run.bundled_stats.rays, run.end_voxels);  // one walk per end voxel
  EXPECT_EQ(run.bundled_stats.merged_points, frame.points.size() - run.end_voxels);
  EXPECT_LT(run.bundled_stats.voxel_visits, run.two_walks_stats.voxel_visits * 3 / 4);
  // The points in between did add updates of their own (their full hits), which bundling leaves
  // out.
  std::vector<StereoVoxelUpdate> unbundled;
  VisibilityStereoIntegrator(perRay()).computeUpdates(frame.points, frame.sigmas, kOrigin, run.map,
                                                      &unbundled);
  EXPECT_NE(run.bundled, asTable(unbundled));
}

TEST(VisibilityStereoIntegratorTest, BundledRaysOfAVoxelsSpreadPointsAreOneWalkEach) {
  // Points spread across their voxels: one walk per end voxel, whose voxels and updates are
  // those of the two rays but for voxels at a corner that only one of them crosses.
  const BundledAgainstTwoWalks run(crowdedFrame(8));
  EXPECT_EQ(run.bundled_stats.rays, run.end_voxels);
  std::size_t same = 0;
  for (const auto& [key, values] : run.bundled) {
    same += run.two_walks.count(key) && run.two_walks.at(key) == values;
  }
  EXPECT_GT(same, 0.9 * run.two_walks.size());
  EXPECT_LE(run.bundled.size(), run.two_walks.size());
}

// The rays are handed to the threads in contiguous spans, a thread that is done taking chunks
// from the back of another's: on any number of threads every ray is cast once (the same voxel
// visits) and the updates are those of one thread.
TEST(VisibilityStereoIntegratorTest, AnyNumberOfThreadsCastsEveryRayOnceWithTheSameUpdates) {
  VoxelMap map(mapConfig());
  scatter(9, &map);
  const RandomFrame frame = randomFrame(6000, 10);  // 23 times a thread's minimum of 256 rays
  VisibilityStereoConfig octomap = perRay();
  octomap.method = StereoIntegrationMethod::kOctomap;  // every ray walks to its point
  const int before = omp_get_max_threads();
  for (const VisibilityStereoConfig& config : {perRay(), octomap}) {
    const VisibilityStereoIntegrator integrator(config);
    std::vector<StereoVoxelUpdate> alone, shared;
    omp_set_num_threads(1);
    const StereoIntegrationStats one =
        integrator.computeUpdates(frame.points, frame.sigmas, kOrigin, map, &alone);
    EXPECT_EQ(one.rays, frame.points.size());
    EXPECT_GT(one.voxel_visits, 5 * one.rays);
    for (const int threads : {2, 3, 5, 8}) {
      SCOPED_TRACE(threads);
      omp_set_num_threads(threads);
      const StereoIntegrationStats many =
          integrator.computeUpdates(frame.points, frame.sigmas, kOrigin, map, &shared);
      EXPECT_EQ(many.rays, one.rays);
      EXPECT_EQ(many.voxel_visits, one.voxel_visits);
      EXPECT_EQ(asTable(shared), asTable(alone));
    }
  }
  omp_set_num_threads(before);
}

// From 8192 points on, the grouping runs in consecutive parts on every thread and joins them in
// order: the same rays as one pass, also for voxels whose points straddle a part boundary, with
// equal ranges on both sides of it (the first point counts) and a nearer point after it.
TEST(VisibilityStereoIntegratorTest, BundlingInPartsEqualsOnePass) {
  VoxelMap map(mapConfig());
  scatter(7, &map);
  RandomFrame frame;
  for (unsigned seed = 20; frame.points.size() < 20000; ++seed) {
    const RandomFrame more = crowdedFrame(seed);
    frame.points.insert(frame.points.end(), more.points.begin(), more.points.end());
    frame.sigmas.insert(frame.sigmas.end(), more.sigmas.begin(), more.sigmas.end());
  }
  const int before = omp_get_max_threads();
  omp_set_num_threads(3);  // parts end at a third and two thirds of the points
  // Two voxels of their own, in front of the crowd (nothing hides them), each with points on both
  // sides of a boundary. At the first, the nearest point's copy (another sigma) after it ties and
  // must not count, a farther point after it becomes the farthest; at the second, a nearer point
  // after it becomes the nearest and the farthest point's copy after it ties.
  const std::size_t first = frame.points.size() / 3, second = 2 * frame.points.size() / 3;
  const auto place = [&](std::size_t i, const Eigen::Vector3f& point, float sigma) {
    frame.points[i] = point;
    frame.sigmas[i] = sigma;
  };
  const Eigen::Vector3f a(0.72f, 0.05f, 0.05f), a_farther(0.78f, 0.05f, 0.05f);
  place(first - 2, a, 0.05f);
  place(first + 1, a, 0.15f);
  place(first + 3, a_farther, 0.05f);
  const Eigen::Vector3f b(0.88f, 0.15f, 0.05f), b_nearer(0.82f, 0.15f, 0.05f);
  place(second - 2, b, 0.05f);
  place(second + 1, b_nearer, 0.05f);
  place(second + 3, b, 0.15f);
  // Bundling the chosen points again, in one pass, gives the same walks: each voxel's nearest and
  // farthest point (the first of equals: the copies tie in range, not in sigma).
  const RandomFrame ends = endsPerVoxel(frame, kOrigin);
  std::vector<StereoVoxelUpdate> bundled, expected;
  const StereoIntegrationStats stats = VisibilityStereoIntegrator(kTableI).computeUpdates(
      frame.points, frame.sigmas, kOrigin, map, &bundled);
  omp_set_num_threads(1);
  const StereoIntegrationStats one_pass = VisibilityStereoIntegrator(kTableI).computeUpdates(
      ends.points, ends.sigmas, kOrigin, map, &expected);
  omp_set_num_threads(before);
  EXPECT_EQ(stats.rays, endsPerVoxel(frame, kOrigin, 1).points.size());
  EXPECT_EQ(stats.rays, one_pass.rays);
  EXPECT_EQ(asTable(bundled), asTable(expected));
}

TEST(VisibilityStereoIntegratorTest, BundlingChangesNothingWithOnePointPerVoxel) {
  // Near the camera, where every pixel has a voxel of its own.
  VoxelMap map(mapConfig());
  scatter(9, &map);
  const RandomFrame frame = endsPerVoxel(randomFrame(400, 10), kOrigin, 1);
  std::vector<StereoVoxelUpdate> bundled, unbundled;
  const StereoIntegrationStats stats = VisibilityStereoIntegrator(kTableI).computeUpdates(
      frame.points, frame.sigmas, kOrigin, map, &bundled);
  VisibilityStereoIntegrator(perRay()).computeUpdates(frame.points, frame.sigmas, kOrigin, map,
                                                      &unbundled);
  EXPECT_EQ(stats.merged_points, 0u);
  EXPECT_EQ(asTable(bundled), asTable(unbundled));
}

TEST(VisibilityStereoIntegratorTest, BundleKeepsTheHitsOfTheNearestAndFarthestPoint) {
  // Three points in voxel 15 on one line, tiny sigma: 1.52 m (before voxel 15's centre at 1.55,
  // which gets its full hit), 1.55 and 1.58 m (at and past the centre: the full hit goes to voxel
  // 16). The bundle walks to the last with the first's P(I_v) too: both hits stay. The nearest
  // point alone would lose voxel 16's.
  const Eigen::Vector3f middle(1.55f, 0.05f, 0.05f), deeper(1.58f, 0.05f, 0.05f);
  const std::vector<Eigen::Vector3f> points = {middle, deeper, kPoint};
  const std::vector<float> sigmas(3, kTinySigma);
  VoxelMap bundled(mapConfig()), unbundled(mapConfig()), nearest_only(mapConfig());
  for (VoxelMap* map : {&bundled, &unbundled, &nearest_only}) fillFreeCorridor(false, map);
  const StereoIntegrationStats stats =
      VisibilityStereoIntegrator(kTableI).integrate(points, sigmas, kOrigin, &bundled);
  VisibilityStereoIntegrator(perRay()).integrate(points, sigmas, kOrigin, &unbundled);
  integrateOnePoint(perRay(), &nearest_only);
  EXPECT_EQ(stats.rays, 1u);  // one walk
  EXPECT_EQ(stats.merged_points, 2u);
  const double hit = occupancyAfterMeasurement(0.3, true, 1.0, kTableI);
  for (const VoxelMap* map : {&bundled, &unbundled}) {
    EXPECT_NEAR(probabilityAt(*map, 15), hit, 1e-6);
    EXPECT_NEAR(probabilityAt(*map, 16), hit, 1e-6);
  }
  EXPECT_NEAR(probabilityAt(nearest_only, 16), 0.3, 1e-6);
  unbundled.forEachKnownVoxel([&](const VoxelIndex& index, float value) {
    EXPECT_EQ(bundled.logOdds(index), std::optional<float>(value));
  });
}

TEST(VisibilityStereoIntegratorTest, BundledOctomapModeIsDiscretizedPointCloud) {
  // liboctomap's insertPointCloud(discretize = true): one ray per end voxel, to its centre.
  VisibilityStereoConfig config;
  config.method = StereoIntegrationMethod::kOctomap;
  const VisibilityStereoIntegrator stereo(config);
  const PointCloudIntegrator cloud{PointCloudIntegratorConfig{}};
  VoxelMap ours(mapConfig()), reference(mapConfig()), per_point(mapConfig());
  for (unsigned frame = 0; frame < 3; ++frame) {
    const RandomFrame points = crowdedFrame(20 + frame);
    // Off the voxel lattice: a ray from a voxel corner to voxel centres passes exactly through
    // other corners, where the float centres here and the integrator's double ones could pick
    // different voxels.
    const Eigen::Vector3d origin(0.013 + 0.03 * frame, -0.021 * frame - 0.007, 0.017);
    std::vector<Eigen::Vector3f> centres;
    for (const Eigen::Vector3f& point : endsPerVoxel(points, origin, 1).points) {
      const VoxelIndex v = voxelIndexOf(point.cast<double>(), kRes);
      centres.push_back(((v.cast<double>().array() + 0.5) * kRes).cast<float>());
    }
    stereo.integrate(points.points, points.sigmas, origin, &ours);
    cloud.integrate(centres, origin, &reference);
    cloud.integrate(points.points, origin, &per_point);
  }
  ASSERT_EQ(ours.knownVoxelCount(), reference.knownVoxelCount());
  reference.forEachKnownVoxel([&](const VoxelIndex& index, float value) {
    EXPECT_EQ(ours.logOdds(index), std::optional<float>(value));
  });
  EXPECT_LT(ours.knownVoxelCount(), per_point.knownVoxelCount());  // fewer rays, fewer voxels
}

TEST(VisibilityStereoIntegratorTest, MaxRangeClearsUpToTheRangeWithoutAHit) {
  // The point at 1.47 m from the origin, max_range 1.0 m: the cut lies at x = 1.05, in voxel 10,
  // which is left out as in OctoMap. Voxels 0..9 get visible misses (P(I) = 0: the point is
  // thousands of sigma away), nothing from voxel 10 on changes, and there is no hit.
  VisibilityStereoConfig config;
  config.max_range = 1.0;
  VoxelMap map(mapConfig());
  fillFreeCorridor(false, &map);
  const StereoIntegrationStats stats =
      VisibilityStereoIntegrator(config).integrate({kPoint}, {kTinySigma}, kOrigin, &map);
  EXPECT_EQ(stats.skipped_points, 0u);
  EXPECT_EQ(stats.updated_voxels, 10u);
  for (int k = 0; k <= 9; ++k) EXPECT_NEAR(probabilityAt(map, k), 0.135 / 0.534, 1e-6) << k;
  for (int k = 10; k <= 17; ++k) EXPECT_NEAR(probabilityAt(map, k), 0.3, 1e-6) << k;

  // Within max_range the point is integrated as without one.
  config.max_range = 1.6;
  VoxelMap within(mapConfig());
  fillFreeCorridor(false, &within);
  integrateOnePoint(config, &within);
  EXPECT_NEAR(probabilityAt(within, 15), 0.165 / 0.466, 1e-6);
}

TEST(VisibilityStereoIntegratorTest, MaxRangeKeepsVisibility) {
  // Behind the known wall at voxels 10, 11 the clipped ray (cut at x = 1.35, voxel 13) stops
  // as the full ray does: voxel 12 is not updated.
  VisibilityStereoConfig config;
  config.max_range = 1.3;
  VoxelMap map(mapConfig());
  fillFreeCorridor(true, &map);
  const StereoIntegrationStats stats =
      VisibilityStereoIntegrator(config).integrate({kPoint}, {kTinySigma}, kOrigin, &map);
  EXPECT_EQ(stats.rays_invisible, 1u);
  EXPECT_EQ(stats.updated_voxels, 12u);
  EXPECT_NEAR(probabilityAt(map, 12), 0.3, 1e-6);
}

TEST(VisibilityStereoIntegratorTest, KnownOnlyNeighboursMapUnknownSpaceAtOnce) {
  // With unknown neighbours left out of Eq. 1 the first frame into an unknown map reaches the
  // point at full visibility: misses from the prior 0.5 (0.45 / 1.02) up to voxel 14, the full
  // hit in voxel 15 (0.55 / 0.98).
  VisibilityStereoConfig config;
  config.unknown_neighbours = UnknownNeighbours::kKnownOnly;
  VoxelMap map(mapConfig());
  const StereoIntegrationStats stats =
      VisibilityStereoIntegrator(config).integrate({kPoint}, {kTinySigma}, kOrigin, &map);
  EXPECT_EQ(stats.rays_invisible, 0u);
  EXPECT_EQ(stats.updated_voxels, 16u);
  for (int k = 0; k <= 14; ++k) EXPECT_NEAR(probabilityAt(map, k), 0.45 / 1.02, 1e-6) << k;
  EXPECT_NEAR(probabilityAt(map, 15), 0.55 / 0.98, 1e-6);
  EXPECT_EQ(unknownNeighboursFromString("known_only"), UnknownNeighbours::kKnownOnly);
  EXPECT_EQ(unknownNeighboursFromString("prior"), UnknownNeighbours::kPrior);
  EXPECT_EQ(toString(UnknownNeighbours::kPrior), "prior");
  EXPECT_THROW(unknownNeighboursFromString("zero"), std::invalid_argument);
}

TEST(VisibilityStereoIntegratorTest, DisparityImageFormEqualsPointForm) {
  // 3 x 1 image seen from a camera at (0.05, 0.05, 0.05) looking along map +x.
  const std::vector<float> disparity = {10.0f, 20.0f, 40.0f};
  const DisparityImageView view{3, 1, disparity.data(), 0};
  const StereoCamera camera{100.0, 100.0, 1.0, 0.0, 0.2};
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  T_map_camera.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // optical z -> map x
  T_map_camera.translation() = kOrigin;
  VisibilityStereoIntegrator integrator(kTableI);
  std::vector<Eigen::Vector3f> points;
  std::vector<float> sigmas;
  integrator.disparityToMapPoints(view, camera, T_map_camera, &points, &sigmas, nullptr);
  ASSERT_EQ(points.size(), 3u);
  // Pixel (1, 0), d = 20: z = 1 m straight ahead, sigma_z = 0.5 / 20 * 1 = 0.025.
  EXPECT_TRUE(points[1].isApprox(Eigen::Vector3f(1.05f, 0.05f, 0.05f), 1e-6f));
  EXPECT_NEAR(sigmas[1], 0.025, 1e-7);
  // Pixel (0, 0), d = 10: z = 2, x = -0.02, the ray is longer than z by |(-0.01, 0, 1)|.
  EXPECT_NEAR(sigmas[0], 0.1 * std::sqrt(1.0001), 1e-7);
  VoxelMap from_image(mapConfig());
  VoxelMap from_points(mapConfig());
  integrator.integrate(view, camera, T_map_camera, &from_image);
  integrator.integrate(points, sigmas, kOrigin, &from_points);
  EXPECT_EQ(from_image.knownVoxelCount(), from_points.knownVoxelCount());
  from_points.forEachKnownVoxel([&](const VoxelIndex& index, float value) {
    EXPECT_EQ(from_image.logOdds(index), std::optional<float>(value));
  });
}

// The disparity image's path converts, moves to the map frame and keys the pixels in one pass on
// every thread, with a slot per pixel; the point form gets disparityToMapPoints' compact list.
// Both must give the same rays: the same map bit for bit and the same counts, at every input
// resolution, bundled or not, on one thread or two. The image is a tilted plane with holes,
// near-zero disparities (dropped as uncertain) and a patch of wrong disparity.
// A slanted plane's disparity with noise, holes, values dropped as too uncertain and a patch
// shifted towards the camera, seen from a tilted camera away from the map's origin.
struct NoisyPlaneFrame {
  static constexpr int kWidth = 96, kHeight = 72;
  std::vector<float> disparity = std::vector<float>(kWidth * kHeight);
  StereoCamera camera{80.0, 80.0, 48.0, 36.0, 0.12};
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();

  NoisyPlaneFrame() {
    std::mt19937 random(3);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    for (int v = 0; v < kHeight; ++v) {
      for (int u = 0; u < kWidth; ++u) {
        float d = 30.0f + 0.2f * u - 0.1f * v + 0.3f * (uniform(random) - 0.5f);
        const float roll = uniform(random);
        if (roll < 0.1f) d = std::nanf("");
        if (roll >= 0.1f && roll < 0.13f) d = 0.002f;  // sigma_z / z = 250: dropped
        if (u >= 40 && u < 52 && v >= 20 && v < 32)
          d += 6.0f;  // a patch shifted towards the camera
        disparity[v * kWidth + u] = d;
      }
    }
    T_map_camera.linear() =
        Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()).toRotationMatrix() *
        (Eigen::Matrix3d() << 0, 0, 1, -1, 0, 0, 0, -1, 0).finished();
    T_map_camera.translation() = Eigen::Vector3d(0.31, -0.47, 1.13);
  }
  DisparityImageView view() const { return {kWidth, kHeight, disparity.data(), 0}; }
};

TEST(VisibilityStereoIntegratorTest, DisparityImageFormEqualsPointFormOnEveryPath) {
  const NoisyPlaneFrame noisy;
  const DisparityImageView view = noisy.view();
  const StereoCamera& camera = noisy.camera;
  const Eigen::Isometry3d& T_map_camera = noisy.T_map_camera;
  const int threads_before = omp_get_max_threads();
  for (const InputResolution input :
       {InputResolution::kFull, InputResolution::kHalf, InputResolution::kQuarter}) {
    for (const bool bundle : {true, false}) {
      for (const int threads : {1, 2}) {
        SCOPED_TRACE(toString(input) + (bundle ? " bundled" : " per ray") + " threads " +
                     std::to_string(threads));
        omp_set_num_threads(threads);
        VisibilityStereoConfig config = visibilityStereoConfigFor(StereoParameterSet::kMeasured);
        config.disparity.input_resolution = input;
        config.bundle_rays = bundle;
        const VisibilityStereoIntegrator integrator(config);
        VoxelMap from_image(mapConfig()), from_points(mapConfig());
        std::vector<Eigen::Vector3f> points;
        std::vector<float> sigmas;
        std::size_t dropped = 0;
        integrator.disparityToMapPoints(view, camera, T_map_camera, &points, &sigmas, nullptr,
                                        &dropped);
        ASSERT_GT(dropped, 0u);
        // Two frames: the second reads the first's map.
        for (int frame = 0; frame < 2; ++frame) {
          const StereoIntegrationStats image_stats =
              integrator.integrate(view, camera, T_map_camera, &from_image);
          const MeasuredSurface surface =
              integrator.measuredSurface(view, camera, T_map_camera, kRes);
          const StereoIntegrationStats point_stats = integrator.integrate(
              points, sigmas, T_map_camera.translation(), &from_points, &surface);
          EXPECT_EQ(image_stats.points, points.size());
          EXPECT_EQ(image_stats.points, point_stats.points);
          EXPECT_EQ(image_stats.skipped_points, point_stats.skipped_points);
          EXPECT_EQ(image_stats.dropped_uncertain, dropped);
          EXPECT_EQ(image_stats.rays, point_stats.rays);
          EXPECT_EQ(image_stats.voxel_visits, point_stats.voxel_visits);
          EXPECT_EQ(image_stats.updated_voxels, point_stats.updated_voxels);
        }
        EXPECT_GT(from_points.knownVoxelCount(), 20u);
        EXPECT_EQ(from_image.knownVoxelCount(), from_points.knownVoxelCount());
        from_points.forEachKnownVoxel([&](const VoxelIndex& index, float value) {
          EXPECT_EQ(from_image.logOdds(index), std::optional<float>(value));
        });
      }
    }
  }
  omp_set_num_threads(threads_before);
}

// integrate() writes each block straight from the threads' tables; computeUpdates() merges the
// tables into one list first, which apply() writes: the same maps, on one to three threads.
TEST(VisibilityStereoIntegratorTest, WritingFromTheThreadsTablesEqualsMergingThenApplying) {
  const NoisyPlaneFrame noisy;
  const int threads_before = omp_get_max_threads();
  for (const bool bundle : {true, false}) {
    for (const int threads : {1, 2, 3}) {
      SCOPED_TRACE(std::string(bundle ? "bundled" : "per ray") + ", threads " +
                   std::to_string(threads));
      omp_set_num_threads(threads);
      VisibilityStereoConfig config = visibilityStereoConfigFor(StereoParameterSet::kMeasured);
      config.bundle_rays = bundle;
      const VisibilityStereoIntegrator integrator(config);
      std::vector<Eigen::Vector3f> points;
      std::vector<float> sigmas;
      integrator.disparityToMapPoints(noisy.view(), noisy.camera, noisy.T_map_camera, &points,
                                      &sigmas, nullptr);
      // 1 cm voxels: the plane at about 0.3 m gives over 256 bundled rays a thread.
      VoxelMapConfig fine = mapConfig();
      fine.resolution = 0.01;
      const MeasuredSurface surface =
          integrator.measuredSurface(noisy.view(), noisy.camera, noisy.T_map_camera, 0.01);
      const Eigen::Vector3d origin = noisy.T_map_camera.translation();
      VoxelMap written(fine), merged(fine);
      // Three frames, the camera stepping aside: later frames update voxels the map knows.
      for (int frame = 0; frame < 3; ++frame) {
        const Eigen::Vector3f step(0.0f, 0.02f * frame, 0.0f);
        std::vector<Eigen::Vector3f> moved = points;
        for (Eigen::Vector3f& p : moved) p += step;
        const Eigen::Vector3d moved_origin = origin + step.cast<double>();
        const StereoIntegrationStats stats =
            integrator.integrate(moved, sigmas, moved_origin, &written, &surface);
        std::vector<StereoVoxelUpdate> updates;
        integrator.computeUpdates(moved, sigmas, moved_origin, merged, &updates, &surface);
        integrator.apply(updates, &merged);
        EXPECT_EQ(stats.updated_voxels, updates.size());
        EXPECT_GE(stats.rays, 256u * threads);
        EXPECT_GT(updates.size(), 50u);
      }
      EXPECT_EQ(written.knownVoxelCount(), merged.knownVoxelCount());
      merged.forEachKnownVoxel([&](const VoxelIndex& index, float value) {
        EXPECT_EQ(written.logOdds(index), std::optional<float>(value));
      });
    }
  }
  omp_set_num_threads(threads_before);
}

// One integrator shared by threads (its const members may run concurrently): the call that finds
// the kept ray slots taken uses slots of its own, and every map is the map of a call made alone.
TEST(VisibilityStereoIntegratorTest, ConcurrentDisparityFramesGiveTheMapsOfSequentialOnes) {
  constexpr int kWidth = 64, kHeight = 48, kThreads = 4, kFrames = 5;
  const StereoCamera camera{60.0, 60.0, 32.0, 24.0, 0.12};
  std::vector<std::vector<float>> images(kThreads, std::vector<float>(kWidth * kHeight));
  for (int t = 0; t < kThreads; ++t) {
    for (int v = 0; v < kHeight; ++v) {
      for (int u = 0; u < kWidth; ++u) images[t][v * kWidth + u] = 8.0f + 0.05f * u + 0.5f * t;
    }
  }
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  T_map_camera.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T_map_camera.translation() = kOrigin;
  const VisibilityStereoIntegrator integrator(
      visibilityStereoConfigFor(StereoParameterSet::kMeasured));
  auto mapOf = [&](int t, VoxelMap* map) {
    const DisparityImageView view{kWidth, kHeight, images[t].data(), 0};
    for (int frame = 0; frame < kFrames; ++frame) {
      integrator.integrate(view, camera, T_map_camera, map);
    }
  };
  std::vector<std::unique_ptr<VoxelMap>> alone, together;
  for (int t = 0; t < kThreads; ++t) {
    alone.push_back(std::make_unique<VoxelMap>(mapConfig()));
    together.push_back(std::make_unique<VoxelMap>(mapConfig()));
    mapOf(t, alone.back().get());
  }
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) threads.emplace_back(mapOf, t, together[t].get());
  for (std::thread& thread : threads) thread.join();
  for (int t = 0; t < kThreads; ++t) {
    EXPECT_GT(alone[t]->knownVoxelCount(), 20u);
    EXPECT_EQ(together[t]->knownVoxelCount(), alone[t]->knownVoxelCount());
    alone[t]->forEachKnownVoxel([&](const VoxelIndex& index, float value) {
      EXPECT_EQ(together[t]->logOdds(index), std::optional<float>(value));
    });
  }
}

// A near-zero disparity among good ones (a match lost in noise): z = 20 km with sigma_z = 1e7 m,
// so Eq. 8 gives every voxel of its ray P(I) ~ 0.5, and the largest P(I) of a frame's rays wins.
// With max_depth_sigma_ratio (sigma_z / z = 2e4 / 20 = 500 here) the point is dropped and the map
// is exactly the good pixels' map.
TEST(VisibilityStereoIntegratorTest, NearZeroDisparityLeavesTheVoxelsNearTheSensorFree) {
  const float kNearZero = 0.001f;
  const std::vector<float> with_bad = {20.0f, kNearZero, 20.0f};  // f * b = 20: z = 1 m
  const std::vector<float> good_only = {20.0f, std::nanf(""), 20.0f};
  const StereoCamera camera{100.0, 100.0, 1.0, 0.0, 0.2};
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  T_map_camera.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // optical z -> map x
  T_map_camera.translation() = kOrigin;
  auto mapAfterFrames = [&](const std::vector<float>& pixels, double max_ratio, int frames,
                            std::size_t* dropped) {
    VisibilityStereoConfig config;
    config.disparity.max_depth_sigma_ratio = max_ratio;
    const VisibilityStereoIntegrator integrator(config);
    auto map = std::make_unique<VoxelMap>(mapConfig());
    fillFreeCorridor(false, map.get());
    for (int i = 0; i < frames; ++i) {
      const StereoIntegrationStats stats = integrator.integrate(
          DisparityImageView{3, 1, pixels.data(), 0}, camera, T_map_camera, map.get());
      *dropped = stats.dropped_uncertain;
    }
    return map;
  };
  std::size_t dropped = 0;
  const auto reference = mapAfterFrames(good_only, 0.5, 1, &dropped);
  EXPECT_EQ(dropped, 0u);
  const auto capped = mapAfterFrames(with_bad, 0.5, 1, &dropped);
  EXPECT_EQ(dropped, 1u);
  EXPECT_EQ(capped->knownVoxelCount(), reference->knownVoxelCount());
  reference->forEachKnownVoxel([&](const VoxelIndex& index, float value) {
    EXPECT_EQ(capped->logOdds(index), std::optional<float>(value));
  });
  // Voxels 0..9 lie before the good points (voxel 9's centre 4 sigma_z in front, P(I) = 3e-5):
  // visible misses from 0.3, 0.135 / 0.534.
  for (int k = 0; k <= 9; ++k) EXPECT_NEAR(probabilityAt(*capped, k), 0.135 / 0.534, 1e-5) << k;

  // Without the cap the bad ray's P(I) ~ 0.5 overrides the good rays' misses: one frame raises
  // the voxels next to the sensor above their prior 0.3 (half a hit, half a miss of Eq. 8), ...
  const auto uncapped = mapAfterFrames(with_bad, -1.0, 1, &dropped);
  EXPECT_EQ(dropped, 0u);
  const double p_inside = 0.5;  // Phi(-2e4 / 1e7) = 0.4992
  const double expected = occupancyAfterInterpolatedMeasurement(0.3, p_inside, 1.0, kTableI);
  for (int k = 0; k <= 9; ++k) EXPECT_NEAR(probabilityAt(*uncapped, k), expected, 2e-3) << k;
  EXPECT_GT(expected, 0.3);
  // ... and repeated frames hold them at Eq. 8's fixed point for P(I) = 0.5 (0.363, three times
  // the clamp) instead of clearing them, while the capped map clamps them free.
  const auto uncapped_many = mapAfterFrames(with_bad, -1.0, 20, &dropped);
  const auto capped_many = mapAfterFrames(with_bad, 0.5, 20, &dropped);
  const double clamp_min = probabilityFromLogOdds(capped_many->minLogOdds());
  for (int k = 0; k <= 9; ++k) {
    EXPECT_NEAR(probabilityAt(*capped_many, k), clamp_min, 1e-6) << k;
    EXPECT_GT(probabilityAt(*uncapped_many, k), 0.35) << k;
  }
}

}  // namespace
}  // namespace occupancy_fusion
