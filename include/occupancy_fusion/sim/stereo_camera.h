// Simulated stereo disparity with the error kinds a stereo matcher makes: white noise and
// spatially correlated patches of wrong disparity that persist over several frames.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/scene.h"

namespace occupancy_fusion {
namespace sim {

// Error model. The image is cut into a grid of patch_size_px x patch_size_px cells; each cell
// holds, with probability patch_probability, one patch: a rectangle or an inscribed ellipse
// (even odds) of random width and height in [patch_size_px / 2, patch_size_px], placed at random
// inside its cell, in which every disparity is shifted by +patch_offset_px (the matcher sees a
// surface in front of the true one) or -patch_offset_px (behind it), even odds. About
// 0.56 * patch_probability of the image is covered. The layout depends only on seed and
// floor(frame_index / patch_persistence_frames): frames k*P .. k*P + P-1 share it, and frame
// (k+1)*P draws a new one. White Gaussian noise of sigma_px is drawn anew for each pixel and frame.
struct DisparityNoise {
  double sigma_px = 0.0;              // px, standard deviation of the white noise
  double patch_probability = 0.0;     // [0, 1], chance that a grid cell holds a patch
  int patch_size_px = 24;             // px, edge of a grid cell (the largest patch)
  double patch_offset_px = 4.0;       // px, magnitude of the shift inside a patch
  int patch_persistence_frames = 10;  // frames that share one patch layout
  std::uint64_t seed = 1;
  // Invalidate pixels whose surface point the right camera cannot see (occluded by a nearer
  // surface), as a matcher's left-right consistency check does.
  bool left_right_check = false;

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// Row-major float disparity in pixels, d = focal_px * baseline_m / z (the convention of
// stereo_msgs/DisparityImage, f = fx of the left camera, T = baseline). NaN marks an invalid
// pixel: nothing within range, or a disparity made <= 0 by the noise. (A ROS publisher writes
// invalid pixels as a value below min_disparity.)
struct DisparityImage {
  int width = 0;
  int height = 0;
  double focal_px = 0.0;
  double baseline_m = 0.0;
  std::vector<float> disparity;  // disparity[v * width + u]

  float at(int u, int v) const { return disparity[static_cast<std::size_t>(v) * width + u]; }
};

// One patch of wrong disparity: pixels u0 <= u < u0 + width, v0 <= v < v0 + height (inside the
// ellipse inscribed in that rectangle when `elliptical`), clipped to the image.
struct DisparityPatch {
  int u0 = 0;
  int v0 = 0;
  int width = 0;
  int height = 0;
  bool elliptical = false;
  double offset_px = 0.0;  // added to the true disparity

  bool covers(int u, int v) const;
};

// The patch layout of frame_index (frame_index >= 0) for an image of width x height.
std::vector<DisparityPatch> disparityPatches(const DisparityNoise& noise, int width, int height,
                                             int frame_index);

// Renders the disparity of the left camera of a rectified pair whose left optical frame is
// T_world_camera and whose right camera sits `baseline` metres along the left camera's +x.
// max_range (m) limits the true z-depth as in renderDepth. A pixel is valid where the left camera
// sees a surface and, with noise.left_right_check, the right camera sees the same point.
// Deterministic given noise.seed and frame_index.
DisparityImage renderDisparity(const Scene& scene, const PinholeCamera& camera, double baseline,
                               const Eigen::Isometry3d& T_world_camera, double max_range,
                               const DisparityNoise& noise = DisparityNoise(), int frame_index = 0);

// z = focal_px * baseline_m / d, NaN for invalid or non-positive d.
DepthImage disparityToDepth(const DisparityImage& image);

}  // namespace sim
}  // namespace occupancy_fusion
