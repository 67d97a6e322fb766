// The point-cloud integrator against liboctomap's OcTree::insertPointCloud on the same clouds,
// and its own semantics (max range, skipped points, one update per voxel per cloud).
#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "../../common/random_segments.h"
#include "occupancy_fusion/integrators/point_cloud_integrator.h"
#include "occupancy_fusion/integrators/ray_traversal.h"

namespace occupancy_fusion {
namespace {

using Cloud = std::vector<Eigen::Vector3f>;
using Key = std::tuple<int, int, int>;

struct Scan {
  Cloud points;
  Eigen::Vector3d origin;
};

// Origins given to both libraries must be equal: OctoMap takes floats.
Eigen::Vector3d floatExact(double x, double y, double z) {
  return Eigen::Vector3f(x, y, z).cast<double>();
}

Cloud randomShell(std::mt19937* rng, const Eigen::Vector3d& origin, double r_min, double r_max,
                  int count) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> radius(r_min, r_max);
  Cloud cloud;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d direction =
        Eigen::Vector3d(normal(*rng), normal(*rng), normal(*rng)).normalized();
    cloud.push_back((origin + radius(*rng) * direction).cast<float>());
  }
  return cloud;
}

// A wall x = wall_x, |y| <= 1.5, 0 <= z <= 2, sampled every `spacing` metres with jitter.
Cloud wall(std::mt19937* rng, double wall_x, double spacing) {
  std::uniform_real_distribution<double> jitter(-0.3 * spacing, 0.3 * spacing);
  Cloud cloud;
  for (double y = -1.5; y <= 1.5; y += spacing) {
    for (double z = 0.0; z <= 2.0; z += spacing) {
      cloud.emplace_back(wall_x + jitter(*rng), y + jitter(*rng), z + jitter(*rng));
    }
  }
  return cloud;
}

// Label and log-odds of one voxel; label -1 unknown, 0 free, 1 occupied.
struct Cell {
  int label = -1;
  float log_odds = 0.0f;
};

struct Comparison {
  std::size_t voxels = 0;  // touched by either
  std::size_t agree = 0;
  std::size_t occupied = 0;  // occupied in ours, for checks that the scene is not trivial
  std::vector<std::string> disagreements;
};

Comparison compare(const VoxelMap& map, const octomap::OcTree& tree) {
  constexpr int kKeyOffset = 32768;  // OctoMap's tree_max_val at depth 16
  std::map<Key, Cell> ours;
  std::map<Key, Cell> theirs;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    ours[{index.x(), index.y(), index.z()}] = {map.classify(log_odds) == Occupancy::kOccupied,
                                               log_odds};
  });
  const int depth = static_cast<int>(tree.getTreeDepth());
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const octomap::OcTreeKey key = it.getKey();
    // A pruned leaf covers 2^(depth - its depth) voxels per axis, from its key rounded down.
    const int side = 1 << (depth - static_cast<int>(it.getDepth()));
    const Cell cell{tree.isNodeOccupied(*it) ? 1 : 0, it->getLogOdds()};
    const int x0 = (key[0] & ~(side - 1)) - kKeyOffset;
    const int y0 = (key[1] & ~(side - 1)) - kKeyOffset;
    const int z0 = (key[2] & ~(side - 1)) - kKeyOffset;
    for (int x = x0; x < x0 + side; ++x) {
      for (int y = y0; y < y0 + side; ++y) {
        for (int z = z0; z < z0 + side; ++z) theirs[{x, y, z}] = cell;
      }
    }
  }
  Comparison result;
  std::map<Key, std::pair<Cell, Cell>> all;
  for (const auto& [key, cell] : ours) all[key].first = cell;
  for (const auto& [key, cell] : theirs) all[key].second = cell;
  for (const auto& [key, cells] : all) {
    const auto& [a, b] = cells;
    ++result.voxels;
    if (a.label == 1) ++result.occupied;
    const bool same =
        a.label == b.label && (a.label == -1 || std::abs(a.log_odds - b.log_odds) < 1e-4);
    if (same) {
      ++result.agree;
    } else if (result.disagreements.size() < 20) {
      std::ostringstream line;
      line << "voxel (" << std::get<0>(key) << ", " << std::get<1>(key) << ", " << std::get<2>(key)
           << "): ours label " << a.label << " log-odds " << a.log_odds << ", octomap label "
           << b.label << " log-odds " << b.log_odds;
      result.disagreements.push_back(line.str());
    }
  }
  return result;
}

// Integrates the scans in order into both maps and compares them.
Comparison integrateBoth(const std::vector<Scan>& scans, double resolution, double max_range,
                         bool discretize = false) {
  VoxelMapConfig map_config;
  map_config.resolution = resolution;
  VoxelMap map(map_config);
  PointCloudIntegratorConfig config;
  config.max_range = max_range;
  config.discretize = discretize;
  const PointCloudIntegrator integrator(config);

  octomap::OcTree tree(resolution);
  tree.setProbHit(map_config.model.prob_hit);
  tree.setProbMiss(map_config.model.prob_miss);
  tree.setClampingThresMin(map_config.model.clamp_min);
  tree.setClampingThresMax(map_config.model.clamp_max);
  tree.setOccupancyThres(map_config.model.occupancy_threshold);

  for (const Scan& scan : scans) {
    integrator.integrate(scan.points, scan.origin, &map);
    octomap::Pointcloud cloud;
    for (const Eigen::Vector3f& p : scan.points) cloud.push_back(p.x(), p.y(), p.z());
    const octomap::point3d origin(scan.origin.x(), scan.origin.y(), scan.origin.z());
    tree.insertPointCloud(cloud, origin, max_range, false, discretize);
  }
  return compare(map, tree);
}

// OctoMap's computeRayKeys walks in float coordinates with a normalised float direction, breaks
// exact ties between axes the other way (strict <), and stops a ray early when its accumulated
// distance passes the segment length by rounding; so where a ray passes within rounding of a voxel
// edge or corner, or ends within rounding of a face, the two walks may pick a different voxel.
void expectAgreement(const Comparison& result, std::size_t min_voxels) {
  const double fraction = static_cast<double>(result.agree) / result.voxels;
  std::cout << "  " << result.agree << " of " << result.voxels << " voxels agree ("
            << 100.0 * fraction << " %), " << result.occupied << " occupied\n";
  for (const std::string& line : result.disagreements) std::cout << "  differs: " << line << "\n";
  EXPECT_GE(result.voxels, min_voxels);
  EXPECT_GE(fraction, 0.999);
}

TEST(PointCloudIntegrator, AgreesWithOctomapOnRandomPoints) {
  std::mt19937 rng(1);
  const Eigen::Vector3d origin = floatExact(0.12, -0.31, 0.05);
  const std::vector<Scan> scans{{randomShell(&rng, origin, 0.3, 4.0, 3000), origin}};
  const Comparison result = integrateBoth(scans, 0.1, -1.0);
  expectAgreement(result, 20000);
  EXPECT_GT(result.occupied, 2500u);
}

TEST(PointCloudIntegrator, AgreesWithOctomapOnAPlane) {
  std::mt19937 rng(2);
  const Eigen::Vector3d origin = floatExact(-0.4, 0.21, 1.1);
  const std::vector<Scan> scans{{wall(&rng, 3.0, 0.02), origin}};
  const Comparison result = integrateBoth(scans, 0.05, -1.0);
  expectAgreement(result, 50000);
  EXPECT_GT(result.occupied, 2000u);
}

TEST(PointCloudIntegrator, AgreesWithOctomapBeyondMaxRange) {
  std::mt19937 rng(3);
  const Eigen::Vector3d origin = floatExact(1.3, -2.7, -0.6);
  const std::vector<Scan> scans{{randomShell(&rng, origin, 0.5, 6.0, 3000), origin}};
  const Comparison result = integrateBoth(scans, 0.1, 3.0);
  expectAgreement(result, 20000);
  EXPECT_GT(result.occupied, 500u);
}

TEST(PointCloudIntegrator, AgreesWithOctomapOverASequenceOfClouds) {
  // Overlapping clouds from moving origins, at negative coordinates: free and occupied updates
  // accumulate on the same voxels and reach both clamping bounds.
  std::mt19937 rng(4);
  std::vector<Scan> scans;
  for (int i = 0; i < 12; ++i) {
    const Eigen::Vector3d origin = floatExact(-0.5 - 0.05 * i, -0.3 + 0.03 * i, 1.0);
    Cloud cloud = wall(&rng, -4.0 + 0.01 * (i % 3), 0.05);
    const Cloud shell = randomShell(&rng, origin, 0.5, 3.5, 500);
    cloud.insert(cloud.end(), shell.begin(), shell.end());
    scans.push_back({cloud, origin});
  }
  const Comparison result = integrateBoth(scans, 0.1, 3.6);
  expectAgreement(result, 10000);
}

TEST(PointCloudIntegrator, DiscretizedAgreesWithOctomapDiscretized) {
  // A dense wall (many points per voxel) and a shell beyond max_range, over several clouds:
  // liboctomap's discretize = true casts one ray per end voxel, to its centre.
  std::mt19937 rng(5);
  std::vector<Scan> scans;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d origin = floatExact(0.313 - 0.07 * i, 0.171 + 0.05 * i, 0.937);
    Cloud cloud = wall(&rng, 3.0, 0.01);
    const Cloud shell = randomShell(&rng, origin, 0.5, 5.0, 800);
    cloud.insert(cloud.end(), shell.begin(), shell.end());
    scans.push_back({cloud, origin});
  }
  const Comparison discretized = integrateBoth(scans, 0.1, 4.0, true);
  expectAgreement(discretized, 10000);
  EXPECT_GT(discretized.occupied, 500u);
  // And it is a different map from the plain mode's (rays to centres, not to the points).
  const Comparison plain = integrateBoth(scans, 0.1, 4.0, false);
  EXPECT_NE(plain.voxels, discretized.voxels);
}

TEST(PointCloudIntegrator, DiscretizedCastsOneRayPerEndVoxel) {
  PointCloudIntegratorConfig config;
  config.discretize = true;
  const PointCloudIntegrator integrator(config);
  VoxelMapConfig map_config;
  map_config.resolution = 0.5;
  VoxelMap map(map_config);
  // Five points in voxel (4, 0, 0), two in (4, 1, 0), one not finite.
  const std::vector<Eigen::Vector3f> points{
      {2.1f, 0.1f, 0.1f},    {2.2f, 0.2f, 0.3f}, {2.4f, 0.4f, 0.2f}, {2.3f, 0.1f, 0.4f},
      {2.45f, 0.05f, 0.05f}, {2.1f, 0.6f, 0.1f}, {2.2f, 0.9f, 0.2f}, {std::nanf(""), 0.0f, 0.0f}};
  const IntegrationStats stats = integrator.integrate(points, Eigen::Vector3d(0.1, 0.1, 0.1), &map);
  EXPECT_EQ(stats.rays, 2u);
  EXPECT_EQ(stats.skipped_points, 1u);
  EXPECT_EQ(stats.occupied_voxels, 2u);
  EXPECT_EQ(map.occupancy(VoxelIndex(4, 0, 0)), Occupancy::kOccupied);
  EXPECT_EQ(map.occupancy(VoxelIndex(4, 1, 0)), Occupancy::kOccupied);
  EXPECT_EQ(map.occupancy(VoxelIndex(2, 0, 0)), Occupancy::kFree);
}

VoxelMap makeMap(double resolution) {
  VoxelMapConfig config;
  config.resolution = resolution;
  return VoxelMap(config);
}

TEST(PointCloudIntegrator, MaxRangeClearsUpToTheRangeWithoutAHit) {
  VoxelMap map = makeMap(0.1);
  PointCloudIntegratorConfig config;
  config.max_range = 2.0;
  const PointCloudIntegrator integrator(config);
  const Eigen::Vector3d origin(0.05, 0.05, 0.05);
  // 5 m away: clipped at x = 2.05 (voxel 20), which OctoMap's rule leaves out.
  const IntegrationStats far =
      integrator.integrate({Eigen::Vector3f(5.05, 0.05, 0.05)}, origin, &map);
  EXPECT_EQ(far.free_voxels, 20u);
  EXPECT_EQ(far.occupied_voxels, 0u);
  const float miss = map.model().missLogOdds();
  for (int x = 0; x < 20; ++x) EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(x, 0, 0)), miss) << x;
  EXPECT_EQ(map.occupancy(VoxelIndex(20, 0, 0)), Occupancy::kUnknown);
  EXPECT_EQ(map.occupancy(VoxelIndex(50, 0, 0)), Occupancy::kUnknown);

  // 1.5 m away along y: a hit at voxel 15, free before it.
  const IntegrationStats near =
      integrator.integrate({Eigen::Vector3f(0.05, 1.55, 0.05)}, origin, &map);
  EXPECT_EQ(near.free_voxels, 15u);  // voxel (0,0,0) again, then y = 1..14
  EXPECT_EQ(near.occupied_voxels, 1u);
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(0, 15, 0)), map.model().hitLogOdds());
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(0, 14, 0)), miss);
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(0, 0, 0)), 2 * miss);
}

TEST(PointCloudIntegrator, SkipsNonFinitePoints) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const Cloud good{{1.0f, 0.5f, 0.2f}, {-2.0f, 0.3f, 0.1f}, {0.4f, -1.2f, 0.9f}};
  Cloud mixed{{nan, 0.0f, 0.0f}, good[0], {1.0f, inf, 0.0f}, good[1], good[2], {0.0f, 0.0f, -inf}};
  const Eigen::Vector3d origin(0.01, 0.02, 0.03);
  const PointCloudIntegrator integrator;
  VoxelMap with_bad = makeMap(0.1);
  VoxelMap only_good = makeMap(0.1);
  const IntegrationStats stats = integrator.integrate(mixed, origin, &with_bad);
  integrator.integrate(good, origin, &only_good);
  EXPECT_EQ(stats.points, 6u);
  EXPECT_EQ(stats.skipped_points, 3u);
  EXPECT_EQ(stats.rays, 3u);
  EXPECT_EQ(stats.occupied_voxels, 3u);
  EXPECT_EQ(with_bad.knownVoxelCount(), only_good.knownVoxelCount());
  std::size_t compared = 0;
  only_good.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    ++compared;
    EXPECT_EQ(with_bad.logOdds(index), log_odds);
  });
  EXPECT_GT(compared, 30u);
}

TEST(PointCloudIntegrator, UpdatesEachVoxelOncePerCloud) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> inside(0.201f, 0.299f);
  Cloud cloud;  // 100 points in voxel (2, 2, 2), seen from 1.5 m away along -x
  for (int i = 0; i < 100; ++i) cloud.emplace_back(inside(rng), inside(rng), inside(rng));
  const Eigen::Vector3d origin(-1.25, 0.25, 0.25);
  VoxelMap map = makeMap(0.1);
  const PointCloudIntegrator integrator;
  const IntegrationStats stats = integrator.integrate(cloud, origin, &map);
  EXPECT_EQ(stats.occupied_voxels, 1u);
  const float hit = map.model().hitLogOdds();
  const float miss = map.model().missLogOdds();
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(2, 2, 2)), hit);
  // Every free voxel got exactly one miss, however many of the 100 rays crossed it.
  map.forEachFreeVoxel([&](const VoxelIndex& index, float log_odds) {
    EXPECT_FLOAT_EQ(log_odds, miss) << index.transpose();
  });
  EXPECT_EQ(map.knownVoxelCount(), stats.free_voxels + 1);
  integrator.integrate(cloud, origin, &map);
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(2, 2, 2)), 2 * hit);
}

TEST(PointCloudIntegrator, OccupiedWinsOverFreeWithinACloud) {
  // The ray to the far point crosses the near point's voxel: it gets a hit only.
  VoxelMap map = makeMap(0.1);
  const PointCloudIntegrator integrator;
  integrator.integrate({Eigen::Vector3f(1.05f, 0.05f, 0.05f), Eigen::Vector3f(2.05f, 0.05f, 0.05f)},
                       Eigen::Vector3d(0.05, 0.05, 0.05), &map);
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(10, 0, 0)), map.model().hitLogOdds());
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(20, 0, 0)), map.model().hitLogOdds());
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(15, 0, 0)), map.model().missLogOdds());
  EXPECT_EQ(map.knownVoxelCount(), 21u);
}

TEST(PointCloudIntegrator, ThreadCountDoesNotChangeTheUpdate) {
  std::mt19937 rng(6);
  const Eigen::Vector3d origin(-0.2, 0.4, 0.9);
  const Cloud cloud = randomShell(&rng, origin, 0.2, 3.0, 4000);
  const PointCloudIntegrator integrator;
  VoxelUpdateSet serial;
  VoxelUpdateSet parallel;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  integrator.computeUpdate(cloud, origin, 0.05, &serial);
  omp_set_num_threads(std::max(2, threads));
  integrator.computeUpdate(cloud, origin, 0.05, &parallel);
  omp_set_num_threads(threads);
  ASSERT_EQ(serial.freeCount(), parallel.freeCount());
  ASSERT_EQ(serial.occupiedCount(), parallel.occupiedCount());
  std::size_t checked = 0;
  serial.forEachFree([&](const VoxelIndex& index) {
    ++checked;
    ASSERT_TRUE(parallel.isFree(index));
  });
  serial.forEachOccupied([&](const VoxelIndex& index) { ASSERT_TRUE(parallel.isOccupied(index)); });
  EXPECT_GT(checked, 10000u);
}

TEST(PointCloudIntegrator, DiscretizedEndVoxelsCountOnceWhicheverHalfHasThem) {
  // 20 000 points (the end voxels are collected on two threads from 8192 on): the first half's
  // voxels again in the second half, in another order, plus voxels of the second half alone,
  // non-finite points in both.
  std::mt19937 rng(8);
  const Eigen::Vector3d origin(0.31, -0.42, 0.57);
  const Cloud first = randomShell(&rng, origin, 0.5, 3.0, 10000);
  Cloud cloud = first;
  Cloud again = first;
  std::shuffle(again.begin(), again.end(), rng);
  again.resize(6000);
  const Cloud own = randomShell(&rng, origin, 0.5, 3.0, 3998);
  cloud.insert(cloud.end(), again.begin(), again.end());
  cloud.insert(cloud.end(), own.begin(), own.end());
  cloud[17] = cloud[15000] = Eigen::Vector3f(std::nanf(""), 0.0f, 0.0f);
  const double resolution = 0.1;
  std::set<std::tuple<int, int, int>> distinct;
  for (const Eigen::Vector3f& p : cloud) {
    if (!p.allFinite()) continue;
    const VoxelIndex v = voxelIndexOf(p.cast<double>(), resolution);
    distinct.insert({v.x(), v.y(), v.z()});
  }
  PointCloudIntegratorConfig config;
  config.discretize = true;
  const PointCloudIntegrator integrator(config);
  const int threads = omp_get_max_threads();
  VoxelUpdateSet updates[2];
  IntegrationStats stats[2];
  for (int run = 0; run < 2; ++run) {
    omp_set_num_threads(run == 0 ? 1 : std::max(2, threads));
    stats[run] = integrator.computeUpdate(cloud, origin, resolution, &updates[run]);
  }
  omp_set_num_threads(threads);
  for (int run = 0; run < 2; ++run) {
    EXPECT_EQ(stats[run].rays, distinct.size()) << "run " << run;
    EXPECT_EQ(stats[run].skipped_points, 2u) << "run " << run;
  }
  EXPECT_GT(distinct.size(), 4000u);
  EXPECT_EQ(updates[0].freeCount(), updates[1].freeCount());
  EXPECT_EQ(updates[0].occupiedCount(), updates[1].occupiedCount());
  updates[0].forEachOccupied(
      [&](const VoxelIndex& index) { ASSERT_TRUE(updates[1].isOccupied(index)); });
}

TEST(VoxelUpdateSet, MarksMergesAndCounts) {
  const int far = VoxelMap::kMaxCoordinateVoxels - 1;
  VoxelUpdateSet a;
  a.markFree(VoxelIndex(-1, -1, -1));
  a.markFree(VoxelIndex(-1, -1, -1));
  a.markFree(VoxelIndex(far, -far, 0));
  a.markOccupied(VoxelIndex(7, 8, -9));
  VoxelUpdateSet b;
  b.markOccupied(VoxelIndex(-1, -1, -1));  // occupied wins over a's free mark
  b.markFree(VoxelIndex(0, 0, 0));
  a.merge(b);
  EXPECT_EQ(a.occupiedCount(), 2u);
  EXPECT_EQ(a.freeCount(), 2u);
  EXPECT_TRUE(a.isOccupied(VoxelIndex(-1, -1, -1)));
  EXPECT_FALSE(a.isFree(VoxelIndex(-1, -1, -1)));
  EXPECT_TRUE(a.isFree(VoxelIndex(far, -far, 0)));
  EXPECT_TRUE(a.isFree(VoxelIndex(0, 0, 0)));
  EXPECT_FALSE(a.isFree(VoxelIndex(0, 0, 1)));
  std::vector<VoxelIndex> free_voxels;
  a.forEachFree([&](const VoxelIndex& index) { free_voxels.push_back(index); });
  ASSERT_EQ(free_voxels.size(), 2u);
  for (const VoxelIndex& index : free_voxels) EXPECT_TRUE(a.isFree(index));
  for (const BlockIndex& block : {BlockIndex(-VoxelMap::kMaxBlockCoordinate, 0, 5),
                                  BlockIndex(VoxelMap::kMaxBlockCoordinate, -3, -1)}) {
    EXPECT_EQ(VoxelUpdateSet::unpackBlock(VoxelUpdateSet::packBlock(block)), block);
  }
  VoxelUpdateSet copy = a;
  copy.markFree(VoxelIndex(100, 100, 100));  // must not write into a's table
  EXPECT_FALSE(a.isFree(VoxelIndex(100, 100, 100)));
  EXPECT_TRUE(copy.isFree(VoxelIndex(100, 100, 100)));
}

// markFreeTowardsEnd follows the walk block by block (a bit stride per step, the block's words
// found again only where the ray leaves a block): the same set as markFree on each voxel the walk
// visits before the end voxel, for rays across many blocks in both directions along every axis,
// along the axes, inside one voxel and around the origin (negative indices), and the ray is
// left on its end voxel.
TEST(VoxelUpdateSet, MarkingFreeTowardsTheEndEqualsMarkingEachVoxel) {
  std::mt19937 rng(23);
  int blocks_crossed = 0;
  for (int i = 0; i < 600; ++i) {
    const double r = i % 3 == 0 ? 0.05 : 0.1;
    auto [s, e] = randomSegment(rng, i, 4.0);
    if (i % 11 == 0) e = s + (e - s) * 0.001;  // within a voxel or two
    if (i % 13 == 0) e = s, e[i % 3] += 2.0;   // along one axis
    VoxelUpdateSet expected, marked;
    forEachVoxelOnRay(s, e, r, RayEnd::kExclude,
                      [&](const VoxelIndex& index) { expected.markFree(index); });
    RayTraversal ray(s, e, r);
    marked.markFreeTowardsEnd(&ray);
    EXPECT_EQ(ray.current(), voxelIndexOf(e, r)) << i;
    ASSERT_EQ(marked.freeCount(), expected.freeCount()) << i;
    ASSERT_EQ(marked.blocks().size(), expected.blocks().size()) << i;
    expected.forEachFree([&](const VoxelIndex& index) { ASSERT_TRUE(marked.isFree(index)) << i; });
    blocks_crossed += static_cast<int>(marked.blocks().size()) > 1;
  }
  EXPECT_GT(blocks_crossed, 400);
}

// clear_passed: a wall at x = 2 seen until clamped, then taken away (the cloud now ends on a wall
// at x = 4 behind it). OctoMap's miss (log-odds -0.405) needs ceil(3.51 / 0.405) = 9 clouds to
// bring the clamped voxels to free, the passed miss (-1.10) ceil(3.51 / 1.10) = 4.
int cloudsUntilTheWallLeft(bool clear_passed, std::size_t* passed) {
  VoxelMapConfig map_config;
  map_config.resolution = 0.1;
  VoxelMap map(map_config);
  PointCloudIntegratorConfig config;
  config.clear_passed = clear_passed;
  const PointCloudIntegrator integrator(config);
  std::mt19937 rng(3);
  const Eigen::Vector3d origin = floatExact(0.01, 0.02, 1.03);
  for (int i = 0; i < 10; ++i) integrator.integrate(wall(&rng, 2.0, 0.03), origin, &map);
  const auto occupied_left = [&] {
    std::size_t count = 0;
    // The part of the old wall that rays to the new one pass (x = 2 is half way to x = 4).
    const Eigen::AlignedBox3d seen(Eigen::Vector3d(1.8, -0.6, 0.6), Eigen::Vector3d(2.2, 0.6, 1.4));
    map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
      const Eigen::Vector3d centre = (index.cast<double>().array() + 0.5) * map.resolution();
      count += (seen.contains(centre) && log_odds > 0.0f) ? 1 : 0;
    });
    return count;
  };
  const std::size_t before = occupied_left();
  EXPECT_GT(before, 100u);
  *passed = 0;
  for (int clouds = 1; clouds <= 20; ++clouds) {
    *passed += integrator.integrate(wall(&rng, 4.0, 0.03), origin, &map).passed_voxels;
    if (occupied_left() < before / 100) return clouds;
  }
  return -1;
}

TEST(PointCloudIntegrator, ClearPassedClearsWhatLeftInFourClouds) {
  std::size_t passed = 0;
  EXPECT_EQ(cloudsUntilTheWallLeft(false, &passed), 9);
  EXPECT_EQ(passed, 0u);
  EXPECT_EQ(cloudsUntilTheWallLeft(true, &passed), 4);
  EXPECT_GT(passed, 100u);
}

// A surface the cloud still sees keeps OctoMap's update: the same clouds of a floor seen at a
// grazing angle and a wall (rays to far floor points pass just above the near floor's voxels)
// give the same occupied voxels with and without clear_passed.
TEST(PointCloudIntegrator, ClearPassedLeavesASurfaceStillSeen) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> along(0.3, 6.0), across(-2.0, 2.0), noise(-0.01, 0.01);
  std::vector<Cloud> clouds;
  for (int c = 0; c < 8; ++c) {
    Cloud cloud = wall(&rng, 6.0, 0.04);
    for (int i = 0; i < 20000; ++i) {
      cloud.emplace_back(along(rng), across(rng), noise(rng));  // the floor
    }
    clouds.push_back(cloud);
  }
  std::map<bool, std::set<Key>> occupied;
  for (bool clear_passed : {false, true}) {
    VoxelMapConfig map_config;
    map_config.resolution = 0.05;
    VoxelMap map(map_config);
    PointCloudIntegratorConfig config;
    config.clear_passed = clear_passed;
    const PointCloudIntegrator integrator(config);
    for (const Cloud& cloud : clouds) integrator.integrate(cloud, floatExact(0, 0, 0.8), &map);
    map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
      if (log_odds > 0.0f) occupied[clear_passed].insert({index.x(), index.y(), index.z()});
    });
  }
  EXPECT_GT(occupied[false].size(), 5000u);
  std::size_t kept = 0;
  for (const Key& key : occupied[false]) kept += occupied[true].count(key);
  EXPECT_GE(static_cast<double>(kept), 0.995 * static_cast<double>(occupied[false].size()));
  EXPECT_LE(occupied[true].size(), occupied[false].size());
}

TEST(PointCloudIntegratorConfig, RejectsNaNMaxRange) {
  PointCloudIntegratorConfig config;
  config.max_range = std::nan("");
  EXPECT_THROW(config.validate(), std::invalid_argument);
  EXPECT_THROW(PointCloudIntegrator{config}, std::invalid_argument);
  config.max_range = -1.0;
  EXPECT_NO_THROW(config.validate());
  for (double probability : {0.0, 0.5, std::nan("")}) {
    config.passed_miss_probability = probability;
    EXPECT_THROW(config.validate(), std::invalid_argument) << probability;
  }
  config.passed_miss_probability = 0.25;
  config.passed_margin = -1;
  EXPECT_THROW(config.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace occupancy_fusion
