#include "occupancy_fusion/eval/stereo_corridor.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {

sim::PinholeCamera StereoCorridorSetup::camera() const {
  sim::PinholeCamera camera;
  camera.width = 160;
  camera.height = 120;
  camera.fx = camera.fy = 131.25;
  camera.cx = 79.5;
  camera.cy = 59.5;
  return camera;
}

StereoCamera StereoCorridorSetup::stereo() const {
  const sim::PinholeCamera c = camera();
  return {c.fx, c.fy, c.cx, c.cy, baseline};
}

sim::DisparityNoise StereoCorridorSetup::noise() const {
  sim::DisparityNoise noise;
  noise.sigma_px = 0.3;
  noise.patch_probability = 0.3;
  noise.patch_size_px = 12;
  noise.patch_offset_px = 1.5;
  noise.patch_persistence_frames = 10;
  noise.seed = 7;
  return noise;
}

std::vector<Eigen::Isometry3d> StereoCorridorSetup::poses() const {
  const Eigen::Vector3d start(start_x, 0.0, height);
  const Eigen::Vector3d end = start + Eigen::Vector3d(step_per_frame * frames, 0.0, 0.0);
  std::vector<Eigen::Isometry3d> poses;
  for (const Eigen::Isometry3d& body : sim::straightLinePath(start, end, frames, 0.0, 0.0)) {
    poses.push_back(body * sim::opticalFrameInBody());
  }
  return poses;
}

std::vector<StereoFrame> renderStereoCorridor(const sim::Scene& scene,
                                              const StereoCorridorSetup& setup,
                                              const VisibilityStereoIntegrator& converter) {
  const sim::PinholeCamera camera = setup.camera();
  const std::vector<Eigen::Isometry3d> poses = setup.poses();
  std::vector<StereoFrame> frames(poses.size());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const sim::DisparityImage image =
        sim::renderDisparity(scene, camera, setup.baseline, poses[k], setup.max_range,
                             setup.noise(), static_cast<int>(k));
    const DisparityImageView view{image.width, image.height, image.disparity.data(), 0};
    converter.disparityToMapPoints(view, setup.stereo(), poses[k], &frames[k].points,
                                   &frames[k].sigmas, nullptr);
    frames[k].origin = poses[k].translation();
  }
  return frames;
}

std::vector<SeenSurfaceSample> seenSurface(const sim::Scene& scene,
                                           const StereoCorridorSetup& setup, double spacing) {
  const sim::PinholeCamera camera = setup.camera();
  const std::vector<Eigen::Isometry3d> poses = setup.poses();
  std::vector<SeenSurfaceSample> seen;
  for (const Eigen::Vector3d& sample : scene.sampleSurface(spacing)) {
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < poses.size(); k += 4) {
      const Eigen::Vector3d p = poses[k].inverse() * sample;
      if (p.z() <= 0.1 || p.z() > setup.max_range) continue;
      const double u = camera.fx * p.x() / p.z() + camera.cx;
      const double v = camera.fy * p.y() / p.z() + camera.cy;
      if (u < 0 || v < 0 || u > camera.width - 1 || v > camera.height - 1) continue;
      const Eigen::Vector3d offset = sample - poses[k].translation();
      const double distance = offset.norm();
      if (distance >= nearest) continue;
      const auto t = scene.castRay(poses[k].translation(), offset / distance, distance + 0.01);
      if (t && *t >= distance - 0.02) nearest = distance;
    }
    if (std::isfinite(nearest)) seen.push_back({sample, nearest});
  }
  return seen;
}

void OccupiedVoxelSet::add(const VoxelIndex& index) {
  if (keys.insert(packKey(index)).second) voxels.push_back(index);
}

bool OccupiedVoxelSet::contains(const VoxelIndex& index) const {
  return keys.count(packKey(index)) > 0;
}

OccupiedVoxelSet occupiedVoxelsOf(const VoxelMap& map) {
  OccupiedVoxelSet occupied;
  map.forEachOccupiedVoxel([&](const VoxelIndex& index, float) { occupied.add(index); });
  return occupied;
}

namespace {

bool hasOccupiedWithinOneVoxel(const OccupiedVoxelSet& map, const VoxelIndex& base) {
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (map.contains(base + VoxelIndex(dx, dy, dz))) return true;
      }
    }
  }
  return false;
}

}  // namespace

StereoMapQuality evaluateStereoMap(const sim::Scene& scene, const OccupiedVoxelSet& map,
                                   double resolution,
                                   const std::vector<SeenSurfaceSample>& surface) {
  StereoMapQuality quality;
  const double tolerance = std::sqrt(3.0) * resolution;  // one voxel diagonal
  for (const VoxelIndex& index : map.voxels) {
    const Eigen::Vector3d center = (index.cast<double>().array() + 0.5) * resolution;
    const bool wrong = !scene.isOccupied(center) && scene.distanceToSurface(center) > tolerance;
    quality.is_false.push_back(wrong);
    quality.false_occupied += wrong ? 1 : 0;
  }
  quality.occupied = map.voxels.size();
  std::size_t covered = 0;
  std::size_t covered_in_bin[kCoverageDistanceBins] = {};
  for (const SeenSurfaceSample& sample : surface) {
    const bool found = hasOccupiedWithinOneVoxel(map, voxelIndexOf(sample.point, resolution));
    const int bin = std::min(kCoverageDistanceBins - 1,
                             static_cast<int>(sample.nearest_view / kCoverageBinWidth));
    ++quality.samples_by_distance[bin];
    covered_in_bin[bin] += found ? 1 : 0;
    covered += found ? 1 : 0;
  }
  quality.coverage = surface.empty() ? 0.0 : static_cast<double>(covered) / surface.size();
  for (int b = 0; b < kCoverageDistanceBins; ++b) {
    quality.coverage_by_distance[b] =
        quality.samples_by_distance[b] == 0
            ? -1.0
            : static_cast<double>(covered_in_bin[b]) / quality.samples_by_distance[b];
  }
  return quality;
}

StereoCorridorRun mapStereoCorridor(const VisibilityStereoConfig& config,
                                    const std::vector<StereoFrame>& frames, double resolution) {
  const VisibilityStereoIntegrator integrator(config);
  VoxelMapConfig map_config;
  map_config.resolution = resolution;
  VoxelMap map(map_config);
  StereoCorridorRun run;
  for (const StereoFrame& frame : frames) {
    const StereoIntegrationStats stats =
        integrator.integrate(frame.points, frame.sigmas, frame.origin, &map);
    run.seconds += stats.seconds;
    run.voxel_visits += stats.voxel_visits;
    run.cache_hits += stats.cache_hits;
  }
  run.occupied = occupiedVoxelsOf(map);
  return run;
}

}  // namespace occupancy_fusion
