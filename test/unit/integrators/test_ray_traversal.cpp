// Ray traversal against brute force over the voxels of the segment's bounding box.
//
// The rule tested, for a segment from s to e (voxel membership by floor(p / r) per axis):
//  1. the walk starts at the voxel of s and ends at the voxel of e;
//  2. every step moves one face towards the end voxel, so the walk has exactly
//     1 + |Δx| + |Δy| + |Δz| voxels and none repeats (the shortest face-connected path);
//  3. complete: every voxel whose open interior the segment crosses is visited, and so is the
//     voxel of every point of the segment (this catches segments lying in a boundary plane);
//  4. exact: every visited voxel's closed cube touches the segment (an extra voxel taken at an
//     exact edge or corner crossing only touches it there), visited in order of the parameter
//     at which the segment enters its closed cube.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "../../common/random_segments.h"
#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {
namespace {

constexpr double kTolerance = 1e-9;  // m; far above rounding of coordinates of a few metres

using Key = std::tuple<int, int, int>;
Key keyOf(const VoxelIndex& index) { return {index.x(), index.y(), index.z()}; }

std::vector<VoxelIndex> walk(const Eigen::Vector3d& start, const Eigen::Vector3d& end,
                             double resolution, RayEnd end_mode = RayEnd::kInclude) {
  std::vector<VoxelIndex> voxels;
  forEachVoxelOnRay(start, end, resolution, end_mode,
                    [&voxels](const VoxelIndex& index) { voxels.push_back(index); });
  return voxels;
}

// Parameter interval [t_in, t_out] of the segment inside the box [lo, hi] (grown by `grow`,
// which may be negative to shrink it), clipped to [0, 1]; empty if t_in > t_out.
std::pair<double, double> segmentInBox(const Eigen::Vector3d& s, const Eigen::Vector3d& e,
                                       const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                       double grow) {
  double t_in = 0.0;
  double t_out = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double a = lo[axis] - grow;
    const double b = hi[axis] + grow;
    const double d = e[axis] - s[axis];
    if (d == 0.0) {
      if (s[axis] < a || s[axis] > b) return {1.0, 0.0};
      continue;
    }
    double t0 = (a - s[axis]) / d;
    double t1 = (b - s[axis]) / d;
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  return {t_in, t_out};
}

void expectExactTraversal(const Eigen::Vector3d& s, const Eigen::Vector3d& e, double r) {
  SCOPED_TRACE(::testing::Message() << "segment (" << s.transpose() << ") -> (" << e.transpose()
                                    << "), resolution " << r);
  const std::vector<VoxelIndex> voxels = walk(s, e, r);
  const VoxelIndex first = voxelIndexOf(s, r);
  const VoxelIndex last = voxelIndexOf(e, r);
  ASSERT_FALSE(voxels.empty());
  EXPECT_EQ(voxels.front(), first);
  EXPECT_EQ(voxels.back(), last);
  ASSERT_EQ(static_cast<int>(voxels.size()), 1 + (last - first).cwiseAbs().sum());

  // 2. Face steps towards the end voxel.
  for (std::size_t i = 1; i < voxels.size(); ++i) {
    const VoxelIndex step = voxels[i] - voxels[i - 1];
    ASSERT_EQ(step.cwiseAbs().sum(), 1) << "step " << i;
    const int axis = step.x() != 0 ? 0 : (step.y() != 0 ? 1 : 2);
    ASSERT_GT(step[axis] * (last[axis] - first[axis]), 0) << "step " << i << " turns back";
  }

  // 4. Every visited voxel touches the segment, in order of entry.
  std::set<Key> visited;
  double previous_entry = -1.0;
  for (const VoxelIndex& index : voxels) {
    visited.insert(keyOf(index));
    const Eigen::Vector3d lo = index.cast<double>() * r;
    const auto [t_in, t_out] = segmentInBox(s, e, lo, lo.array() + r, kTolerance);
    ASSERT_LE(t_in, t_out) << "voxel " << index.transpose() << " does not touch the segment";
    EXPECT_GE(t_in, previous_entry - kTolerance) << "voxel " << index.transpose();
    previous_entry = t_in;
  }

  // 3a. Every voxel of the bounding box whose interior the segment crosses is visited.
  const VoxelIndex box_lo = first.cwiseMin(last);
  const VoxelIndex box_hi = first.cwiseMax(last);
  for (int x = box_lo.x(); x <= box_hi.x(); ++x) {
    for (int y = box_lo.y(); y <= box_hi.y(); ++y) {
      for (int z = box_lo.z(); z <= box_hi.z(); ++z) {
        const Eigen::Vector3d lo = Eigen::Vector3d(x, y, z) * r;
        const auto [t_in, t_out] = segmentInBox(s, e, lo, lo.array() + r, -kTolerance);
        if (t_in < t_out) {
          EXPECT_TRUE(visited.count({x, y, z})) << "missed voxel " << x << " " << y << " " << z;
        }
      }
    }
  }
  // 3b. The voxel of every sample point, skipping samples within rounding of a boundary on an
  // axis where the coordinate varies (on a constant axis the coordinate is exact).
  for (int k = 0; k <= 64; ++k) {
    const double t = k / 64.0;
    const Eigen::Vector3d p = k == 64 ? e : Eigen::Vector3d(s + t * (e - s));  // s + (e - s) != e
    bool near_boundary = false;
    for (int axis = 0; axis < 3; ++axis) {
      const double cells = p[axis] / r;
      if (e[axis] != s[axis] && std::abs(cells - std::round(cells)) < 1e-7) near_boundary = true;
    }
    if (k == 0 || k == 64 || !near_boundary) {
      EXPECT_TRUE(visited.count(keyOf(voxelIndexOf(p, r)))) << "sample t=" << t;
    }
  }
}

TEST(RayTraversal, HandComputedWalks) {
  using V = VoxelIndex;
  EXPECT_EQ(walk({0.5, 0.5, 0.5}, {2.5, 0.5, 0.5}, 1.0),
            (std::vector<V>{V(0, 0, 0), V(1, 0, 0), V(2, 0, 0)}));
  // Starts on a boundary and walks down: the start voxel is the one above the boundary.
  EXPECT_EQ(walk({1.0, 0.5, 0.5}, {0.5, 0.5, 0.5}, 1.0), (std::vector<V>{V(1, 0, 0), V(0, 0, 0)}));
  // Lies in the plane z = 0 and y = 0: floor puts it in voxels with y = z = 0.
  EXPECT_EQ(walk({-0.5, 0.0, 0.0}, {0.5, 0.0, 0.0}, 1.0),
            (std::vector<V>{V(-1, 0, 0), V(0, 0, 0)}));
  // Through an edge exactly: ties step x first.
  EXPECT_EQ(walk({0.5, 0.5, 0.2}, {1.5, 1.5, 0.2}, 1.0),
            (std::vector<V>{V(0, 0, 0), V(1, 0, 0), V(1, 1, 0)}));
  // Negative coordinates, resolution 0.25: x from voxel -8 to -5.
  EXPECT_EQ(walk({-1.9, -0.1, 0.1}, {-1.1, -0.1, 0.1}, 0.25),
            (std::vector<V>{V(-8, -1, 0), V(-7, -1, 0), V(-6, -1, 0), V(-5, -1, 0)}));
  // Zero length: one voxel, or none without the end voxel.
  EXPECT_EQ(walk({0.3, -0.3, 7.0}, {0.3, -0.3, 7.0}, 0.1), (std::vector<V>{V(2, -3, 70)}));
  EXPECT_TRUE(walk({0.3, -0.3, 7.0}, {0.3, -0.3, 7.0}, 0.1, RayEnd::kExclude).empty());
}

TEST(RayTraversal, ExcludingTheEndAndStoppingEarly) {
  const Eigen::Vector3d s(0.05, 0.05, 0.05);
  const Eigen::Vector3d e(1.05, 0.37, -0.44);
  const std::vector<VoxelIndex> all = walk(s, e, 0.1);
  const std::vector<VoxelIndex> without_end = walk(s, e, 0.1, RayEnd::kExclude);
  ASSERT_EQ(without_end.size() + 1, all.size());
  EXPECT_TRUE(std::equal(without_end.begin(), without_end.end(), all.begin()));

  int calls = 0;
  const int visited = forEachVoxelOnRay(s, e, 0.1, RayEnd::kInclude,
                                        [&calls](const VoxelIndex&) { return ++calls < 3; });
  EXPECT_EQ(calls, 3);
  EXPECT_EQ(visited, 3);
}

TEST(RayTraversal, ContinuesAlongTheRayBeyondTheEnd) {
  const Eigen::Vector3d s(-0.33, 0.12, 0.71);
  const Eigen::Vector3d e(0.41, -0.52, 0.93);
  const double r = 0.1;
  RayTraversal ray(s, e, r);
  while (ray.beforeEnd()) ray.next();
  ASSERT_TRUE(ray.atEnd());
  EXPECT_EQ(ray.current(), voxelIndexOf(e, r));
  // The segment extended to three times its length: the walk beyond the end must continue it.
  const Eigen::Vector3d far = s + 3.0 * (e - s);
  std::vector<VoxelIndex> extended = walk(s, far, r);
  std::vector<VoxelIndex> stepped;
  RayTraversal again(s, e, r);
  stepped.push_back(again.current());
  double previous_entry = 0.0;
  while (stepped.size() < extended.size()) {
    again.next();
    EXPECT_GE(again.entryParameter(), previous_entry);
    previous_entry = again.entryParameter();
    stepped.push_back(again.current());
  }
  EXPECT_EQ(stepped, extended);
  EXPECT_NEAR(previous_entry, 3.0, 0.2);  // entered the last voxel shortly before t = 3
  EXPECT_NEAR(again.length(), (e - s).norm(), 1e-12);
}

// walkTowardsEnd keeps the walk's state in locals and writes it back: the same voxels and entry
// parameters as stepTowardsEnd, also when it stops part way (fn returns false) and for the walk
// beyond the end with next() afterwards.
TEST(RayTraversal, WalkingInOneCallEqualsSteppingOneByOne) {
  std::mt19937 rng(17);
  int stopped_early = 0;
  for (int i = 0; i < 1000; ++i) {
    const double r = i % 2 == 0 ? 0.1 : 0.25;
    const auto [s, e] = randomSegment(rng, i, 3.0);
    RayTraversal stepped(s, e, r), walked(s, e, r);
    const int steps = stepped.stepsToEnd();
    // fn returns false at the stop_after-th voxel (at least the first).
    const int stop_after = i % 3 == 0 ? std::max(1, steps / 2) : steps;
    std::vector<VoxelIndex> expected, seen;
    for (int k = 0; k < std::min(stop_after, steps); ++k) {
      stepped.stepTowardsEnd();
      expected.push_back(stepped.current());
    }
    const int calls = walked.walkTowardsEnd(steps, [&](const VoxelIndex& voxel) {
      seen.push_back(voxel);
      return static_cast<int>(seen.size()) < stop_after;
    });
    stopped_early += calls < steps;
    ASSERT_EQ(calls, std::min(stop_after, steps)) << i;
    ASSERT_EQ(seen, expected) << i;
    ASSERT_EQ(walked.current(), stepped.current());
    ASSERT_EQ(walked.stepsToEnd(), stepped.stepsToEnd());
    ASSERT_EQ(walked.entryParameter(), stepped.entryParameter());
    for (int k = 0; k < 12; ++k) {  // on to the end and beyond it
      stepped.next();
      walked.next();
      ASSERT_EQ(walked.current(), stepped.current()) << i << " step " << k;
      ASSERT_EQ(walked.entryParameter(), stepped.entryParameter());
    }
  }
  EXPECT_GT(stopped_early, 100);
}

// walkAxesTowardsEnd names the axis of each step: the one coordinate that changed, by the
// ray's step along it.
TEST(RayTraversal, WalkingByAxisNamesTheAxisOfEachStep) {
  std::mt19937 rng(5);
  int per_axis[3] = {0, 0, 0};
  for (int i = 0; i < 300; ++i) {
    const auto [s, e] = randomSegment(rng, i, 3.0);
    RayTraversal ray(s, e, 0.1);
    VoxelIndex previous = ray.current();
    ray.walkAxesTowardsEnd(ray.stepsToEnd(), [&](const VoxelIndex& voxel, auto axis) {
      constexpr int a = decltype(axis)::value;
      VoxelIndex expected = previous;
      expected[a] += ray.stepOf(a);
      ASSERT_EQ(voxel, expected) << i;
      ++per_axis[a];
      previous = voxel;
    });
    ASSERT_EQ(previous, voxelIndexOf(e, 0.1)) << i;
  }
  for (int a = 0; a < 3; ++a) EXPECT_GT(per_axis[a], 1000);
}

TEST(RayTraversal, MatchesBruteForceOnRandomSegments) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> coordinate(-3.0, 3.0);
  const double resolutions[] = {0.05, 0.1, 0.25, 1.0};
  for (int i = 0; i < 2000; ++i) {
    const double r = resolutions[i % 4];
    const Eigen::Vector3d s(coordinate(rng), coordinate(rng), coordinate(rng));
    Eigen::Vector3d e(coordinate(rng), coordinate(rng), coordinate(rng));
    if (i % 5 == 0) e = s + (e - s) * 0.1;  // short segments, often within a few voxels
    expectExactTraversal(s, e, r);
    if (HasFatalFailure()) return;
  }
}

TEST(RayTraversal, MatchesBruteForceOnBoundaryAndAxisAlignedSegments) {
  // Coordinates on a lattice of quarter voxels: many start/end points lie exactly on faces,
  // edges and corners, many segments run along axes, in boundary planes or through corners.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> quarter(-24, 24);
  std::uniform_int_distribution<int> pick(0, 5);
  const double resolutions[] = {0.25, 1.0, 0.1};
  for (int i = 0; i < 3000; ++i) {
    const double r = resolutions[i % 3];
    auto lattice = [&] {
      Eigen::Vector3d point;
      for (int axis = 0; axis < 3; ++axis) point[axis] = quarter(rng) * (r / 4.0);
      return point;
    };
    const Eigen::Vector3d s = lattice();
    Eigen::Vector3d e = lattice();
    switch (pick(rng)) {
      case 0:  // along one axis
        e.y() = s.y();
        e.z() = s.z();
        break;
      case 1:  // in an axis plane
        e.z() = s.z();
        break;
      case 2:  // exact diagonal through edges and corners
        e = s + Eigen::Vector3d(1, -1, 1) * (quarter(rng) * r / 4.0);
        break;
      case 3:  // zero length
        e = s;
        break;
      default:
        break;
    }
    expectExactTraversal(s, e, r);
    if (HasFatalFailure()) return;
  }
}

TEST(RayTraversal, VoxelOfAPointMatchesTheMap) {
  VoxelMapConfig config;
  config.resolution = 0.1;
  const VoxelMap map(config);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coordinate(-50.0, 50.0);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d p(coordinate(rng), coordinate(rng), std::round(coordinate(rng)) * 0.1);
    EXPECT_EQ(voxelIndexOf(p, 0.1), map.indexOf(p));
    EXPECT_EQ(RayTraversal(p, p, 0.1).current(), map.indexOf(p));
  }
}

}  // namespace
}  // namespace occupancy_fusion
