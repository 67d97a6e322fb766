#include "occupancy_fusion/sim/stereo_camera.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "occupancy_fusion/sim/deterministic_random.h"

namespace occupancy_fusion {
namespace sim {
namespace {

constexpr float kInvalid = std::numeric_limits<float>::quiet_NaN();

// Separate hash streams so patch layout and white noise never share random numbers.
constexpr std::uint64_t kPatchStream = 0x5041544348ULL;  // "PATCH"
constexpr std::uint64_t kWhiteStream = 0x5748495445ULL;  // "WHITE"

DisparityPatch drawPatch(const DisparityNoise& noise, std::uint64_t cell_key, int cell_u0,
                         int cell_v0) {
  const int size = noise.patch_size_px;
  auto uniform = [&](std::uint64_t which) { return uniform01(hashKey({cell_key, which})); };
  auto extent = [&](double r) {
    return std::clamp(static_cast<int>(std::lround(size * (0.5 + 0.5 * r))), 1, size);
  };
  DisparityPatch patch;
  patch.width = extent(uniform(1));
  patch.height = extent(uniform(2));
  patch.u0 = cell_u0 + static_cast<int>(uniform(3) * (size - patch.width + 1));
  patch.v0 = cell_v0 + static_cast<int>(uniform(4) * (size - patch.height + 1));
  patch.elliptical = uniform(5) < 0.5;
  patch.offset_px = uniform(6) < 0.5 ? noise.patch_offset_px : -noise.patch_offset_px;
  return patch;
}

// Per-pixel disparity offset of the frame's patches (patches never overlap: one per cell).
std::vector<float> patchOffsets(const DisparityNoise& noise, int width, int height,
                                int frame_index) {
  std::vector<float> offsets(static_cast<std::size_t>(width) * height, 0.0f);
  for (const DisparityPatch& patch : disparityPatches(noise, width, height, frame_index)) {
    for (int v = patch.v0; v < std::min(height, patch.v0 + patch.height); ++v) {
      for (int u = patch.u0; u < std::min(width, patch.u0 + patch.width); ++u) {
        if (patch.covers(u, v)) {
          offsets[static_cast<std::size_t>(v) * width + u] = static_cast<float>(patch.offset_px);
        }
      }
    }
  }
  return offsets;
}

// True when a surface nearer than `point` blocks the right camera's view of it. The tolerance
// absorbs the float rounding of the depth image the point was made from.
bool hiddenFromRightCamera(const Scene& scene, const Eigen::Vector3d& right_center,
                           const Eigen::Vector3d& point) {
  const Eigen::Vector3d to_point = point - right_center;
  const double distance = to_point.norm();
  const std::optional<double> t = scene.castRay(right_center, to_point / distance, distance);
  return t && *t < distance * (1.0 - 1e-5) - 1e-6;
}

}  // namespace

void DisparityNoise::validate() const {
  if (!(std::isfinite(sigma_px) && sigma_px >= 0)) {
    throw std::invalid_argument("DisparityNoise.sigma_px must be finite and >= 0");
  }
  if (!(patch_probability >= 0 && patch_probability <= 1)) {
    throw std::invalid_argument("DisparityNoise.patch_probability must be in [0, 1]");
  }
  if (patch_size_px < 1) throw std::invalid_argument("DisparityNoise.patch_size_px must be >= 1");
  if (!std::isfinite(patch_offset_px)) {
    throw std::invalid_argument("DisparityNoise.patch_offset_px must be finite");
  }
  if (patch_persistence_frames < 1) {
    throw std::invalid_argument("DisparityNoise.patch_persistence_frames must be >= 1");
  }
}

bool DisparityPatch::covers(int u, int v) const {
  if (u < u0 || u >= u0 + width || v < v0 || v >= v0 + height) return false;
  if (!elliptical) return true;
  // Pixel centre against the ellipse inscribed in the rectangle.
  const double x = (u + 0.5 - u0 - 0.5 * width) / (0.5 * width);
  const double y = (v + 0.5 - v0 - 0.5 * height) / (0.5 * height);
  return x * x + y * y <= 1.0;
}

std::vector<DisparityPatch> disparityPatches(const DisparityNoise& noise, int width, int height,
                                             int frame_index) {
  noise.validate();
  if (frame_index < 0) throw std::invalid_argument("frame_index must be >= 0");
  std::vector<DisparityPatch> patches;
  if (noise.patch_probability <= 0) return patches;
  const auto epoch = static_cast<std::uint64_t>(frame_index / noise.patch_persistence_frames);
  const int size = noise.patch_size_px;
  for (int cell_v0 = 0; cell_v0 < height; cell_v0 += size) {
    for (int cell_u0 = 0; cell_u0 < width; cell_u0 += size) {
      const std::uint64_t cell_key =
          hashKey({noise.seed, kPatchStream, epoch, static_cast<std::uint64_t>(cell_u0),
                   static_cast<std::uint64_t>(cell_v0)});
      if (uniform01(cell_key) < noise.patch_probability) {
        patches.push_back(drawPatch(noise, cell_key, cell_u0, cell_v0));
      }
    }
  }
  return patches;
}

DisparityImage renderDisparity(const Scene& scene, const PinholeCamera& camera, double baseline,
                               const Eigen::Isometry3d& T_world_camera, double max_range,
                               const DisparityNoise& noise, int frame_index) {
  if (!(std::isfinite(baseline) && baseline > 0)) {
    throw std::invalid_argument("baseline must be positive and finite");
  }
  const std::vector<float> offsets =
      patchOffsets(noise, camera.width, camera.height, frame_index);  // validates noise
  const DepthImage depth = renderDepth(scene, camera, T_world_camera, max_range);
  DisparityImage image;
  image.width = depth.width;
  image.height = depth.height;
  image.focal_px = camera.fx;
  image.baseline_m = baseline;
  image.disparity.assign(depth.depth.size(), kInvalid);
  const double fb = camera.fx * baseline;
  const auto frame = static_cast<std::uint64_t>(frame_index);
  const Eigen::Vector3d right_center = T_world_camera * Eigen::Vector3d(baseline, 0, 0);
#pragma omp parallel for schedule(dynamic, 4)
  for (int v = 0; v < image.height; ++v) {
    for (int u = 0; u < image.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * image.width + u;
      const float z = depth.depth[i];
      if (!std::isfinite(z)) continue;
      if (noise.left_right_check &&
          hiddenFromRightCamera(scene, right_center,
                                T_world_camera * (z * camera.pixelRay(u, v)))) {
        continue;
      }
      double d = fb / z + offsets[i];
      if (noise.sigma_px > 0) {
        d += noise.sigma_px * standardNormal(hashKey({noise.seed, kWhiteStream, frame, i}));
      }
      if (d > 0) image.disparity[i] = static_cast<float>(d);
    }
  }
  return image;
}

DepthImage disparityToDepth(const DisparityImage& image) {
  DepthImage depth;
  depth.width = image.width;
  depth.height = image.height;
  depth.depth.assign(image.disparity.size(), kInvalid);
  const double fb = image.focal_px * image.baseline_m;
  for (std::size_t i = 0; i < image.disparity.size(); ++i) {
    const float d = image.disparity[i];
    if (std::isfinite(d) && d > 0) depth.depth[i] = static_cast<float>(fb / d);
  }
  return depth;
}

}  // namespace sim
}  // namespace occupancy_fusion
