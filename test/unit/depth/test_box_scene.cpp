// The pyramidal depth integrator on the simulated BOX scene (Pirker et al. Sec. 5.1) against
// the scene's analytic ground truth: a few views at a coarse resolution, so the test is fast.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"
#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {
namespace {

constexpr double kResolution = 0.1;
constexpr double kMaxRange = 15.0;

struct Scores {
  double surface_covered = 0.0;  // visible true surface points within one voxel of an occupied
  double free_correct = 0.0;     // observed ground-truth free voxels labelled free
  std::size_t surface_points = 0;
  std::size_t free_voxels = 0;
};

// Views 0, 4, 8, ... of the paper's 4-degree sweep, about the camera's x and then y axis.
Scores mapBoxScene(DepthMethod method) {
  const sim::Scene scene = sim::makeBoxScene();
  const CameraIntrinsics camera = sim::pirkerSyntheticCamera();
  const std::vector<Eigen::Isometry3d> sweep = sim::rotationSweep(sim::boxSceneCameraPosition());
  std::vector<Eigen::Isometry3d> views;
  for (int k : {0, 3, 6, 9, 93, 96, 99}) views.push_back(sweep[k]);

  PyramidDepthConfig config;
  config.k = 0.1;
  config.sigma = 0.1;
  config.max_range = kMaxRange;
  config.method = method;
  const PyramidDepthIntegrator integrator(config);
  VoxelMapConfig map_config;
  map_config.resolution = kResolution;
  VoxelMap map(map_config);
  std::vector<sim::DepthImage> images;
  for (const Eigen::Isometry3d& view : views) {
    images.push_back(sim::renderDepth(scene, camera, view, kMaxRange));
    const DepthImageView depth{camera.width, camera.height, images.back().depth.data()};
    integrator.integrate(depth, camera, view, &map);
  }

  // A surface point is visible when some view's depth at its pixel matches its own.
  auto visible = [&](const Eigen::Vector3d& point) {
    for (std::size_t i = 0; i < views.size(); ++i) {
      const Eigen::Vector3d p = views[i].inverse() * point;
      if (p.z() <= 0.0) continue;
      const Eigen::Vector2d uv = camera.project(p);
      const int u = static_cast<int>(std::lround(uv.x()));
      const int v = static_cast<int>(std::lround(uv.y()));
      if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) continue;
      if (std::abs(images[i].at(u, v) - p.z()) < 0.5 * kResolution) return true;
    }
    return false;
  };
  Scores scores;
  std::size_t covered = 0;
  for (const Eigen::Vector3d& point : scene.sampleSurface(kResolution)) {
    if (!visible(point)) continue;
    ++scores.surface_points;
    const VoxelIndex center = map.indexOf(point);
    bool near_occupied = false;
    for (int dz = -1; dz <= 1 && !near_occupied; ++dz) {
      for (int dy = -1; dy <= 1 && !near_occupied; ++dy) {
        for (int dx = -1; dx <= 1 && !near_occupied; ++dx) {
          const std::optional<float> value = map.logOdds(center + VoxelIndex(dx, dy, dz));
          near_occupied = value && map.classify(*value) == Occupancy::kOccupied;
        }
      }
    }
    covered += near_occupied;
  }
  std::size_t free_correct = 0;
  const double diagonal = std::sqrt(3.0) * kResolution;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    const Eigen::Vector3d c = map.centerOf(index);
    if (scene.isOccupied(c) || scene.distanceToSurface(c) <= diagonal) return;
    ++scores.free_voxels;
    free_correct += map.classify(log_odds) == Occupancy::kFree;
  });
  scores.surface_covered = static_cast<double>(covered) / scores.surface_points;
  scores.free_correct = static_cast<double>(free_correct) / scores.free_voxels;
  std::printf(
      "BOX %s: %zu visible surface points, %.2f %% within one voxel of an occupied voxel; "
      "%zu observed free voxels, %.3f %% labelled free\n",
      toString(method).c_str(), scores.surface_points, 100.0 * scores.surface_covered,
      scores.free_voxels, 100.0 * scores.free_correct);
  return scores;
}

TEST(BoxScene, PyramidFindsTheSurfacesAndTheFreeSpace) {
  const Scores scores = mapBoxScene(DepthMethod::kPyramid);
  EXPECT_GT(scores.surface_points, 1000u);
  EXPECT_GT(scores.free_voxels, 100000u);
  EXPECT_GE(scores.surface_covered, 0.95);
  EXPECT_GE(scores.free_correct, 0.99);
}

}  // namespace
}  // namespace occupancy_fusion
