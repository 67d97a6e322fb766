// The surface a disparity image measures, made robust against the correlated errors of a stereo
// matcher, for the visibility of never-observed space from the measurement itself (the paper's
// ref. [7], Perrollaz et al., decides visibility in the measurement's own disparity space).
//
// A matcher's wrong disparities come in patches that stick to image positions: a patch shifted
// towards the camera puts a phantom surface into free space, one shifted away makes a hole in a
// true surface through which the space behind it looks visible. On a grid, the median over a
// wide window of the means of point-symmetric pixel pairs ignores both while a patch spoils fewer
// than half the pairs, and on a plane (whose disparity is linear in u and v) every pair mean is
// the plane's disparity at the window's centre; the pairs of a small window within inlier_px of
// that median then give the surface, with the bias at a corner or step of the small window only.
// The grid is read bilinearly in disparity, where a plane stays linear, except across a step
// (an object's outline), where a pixel reads its nearest grid surface; a grid point next to the
// range limit or a hole gets the plane extrapolated from its neighbours.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "occupancy_fusion/integrators/stereo/median_network.h"
#include "occupancy_fusion/sensors/disparity_image.h"

namespace occupancy_fusion {

struct MeasuredSurfaceConfig {
  // px, edge of the median's window. Patches of wrong disparity up to half its area are ignored;
  // a true surface narrower than half the window (a thin pole against a far wall) is read as the
  // surface behind it, which only delays its visibility to a later frame. Below
  // 32 * sample_step_px (127 px with 4 px samples): a median takes at most 31^2 samples.
  int window_px = 25;
  // px between the grid's surfaces, whatever the input resolution of the rays: a coarser grid
  // interpolates across more of an object's outline (docs/disparity_method.md, "Moving camera").
  // The finest grid; see grid_footprint_fraction.
  int grid_step_px = 4;
  // With a voxel size given: the grid may be coarser, up to this fraction of the image size of a
  // voxel at the frame's farthest measured depth (the smallest any voxel a ray reaches appears),
  // rounded down to a multiple of sample_step_px and at most grid_max_step_px. A voxel reads the
  // surface at its centre's projection, so a grid much finer than a voxel's image adds work and
  // no detail: Middlebury's 2-5 m at 0.1 m (17-20 px a voxel) takes an 8 px grid, a quarter of
  // the 4 px grid's points (docs/disparity_method.md). 0: always grid_step_px.
  double grid_footprint_fraction = 0.5;
  // px, the coarsest grid grid_footprint_fraction may choose (a multiple of sample_step_px, at
  // most window_px; 0: window_px). Coarser grids interpolate across more of an object's outline:
  // 12-24 px grids lost up to 0.03 of the surface on Middlebury.
  int grid_max_step_px = 8;
  // px between the wide window's samples (7 x 7 of a 25 px window); grid_step_px must be a
  // multiple of it, so that every grid surface samples one lattice of pixels, read once per frame.
  int sample_step_px = 4;
  // Fraction of the wide window's symmetric pairs that must be valid. Low: near the range limit
  // or a hole only the pairs along the boundary are valid, and they still give a plane's depth.
  double min_valid = 0.03;
  // px, edge of the small window whose pixels within inlier_px of the wide window's median give
  // the surface, as the mean of their symmetric pairs: the median of a wide window is biased at a
  // kink of the surface (a corner, a step) by up to half its width times the change of slope;
  // the small window's mean only by its own. 0: the median itself.
  int local_window_px = 5;
  double inlier_px = 1.0;
  // px. A grid edge whose change of disparity differs by more than this from those of both
  // neighbouring edges along its line is a step (an object's outline, a doorway's jamb against the
  // wall behind): a pixel in a cell with a step reads the surface of its nearest corner instead of
  // interpolating a surface across the gap that no pixel sees. On a plane every edge along a line
  // changes alike; 0.25 px is about four times the noise of one grid surface at 0.3 px of pixel
  // noise. 0: never.
  double step_px = 0.25;
  // Grid points nearer to the image's border than sample_step_px take the surface extrapolated
  // from the two grid points inside them (as next to the range limit) instead of their own
  // median. Their window keeps only the pairs whose pixels both lie inside the image, the one
  // line of samples through the grid point (4 of 25 values), so a patch at the border alone
  // decided it; and they are read by every voxel whose centre lies just outside the image (the
  // reach of depthAt). New space entering the image at a border (sideways motion) got the
  // patch's phantom (docs/design_notes.md, "The border rule"). On a plane
  // the extrapolation is exact. Wider bands (8 and 12 px) rejected more of those phantoms but
  // cost turning motions coverage and false-occupied voxels (measured there).
  bool border_from_interior = true;
  // The vector instructions of the medians and the small windows' means: the same surface either
  // way; kBaseline runs plain x86-64's on any processor (for tests).
  MedianNetwork::Instructions instructions = MedianNetwork::Instructions::kWidest;

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// What the grid's step may follow (MeasuredSurfaceConfig::grid_footprint_fraction): the map's
// voxel size and the smallest disparity whose point the rays use (those below are dropped).
struct SurfaceGridScale {
  double voxel_size_m = 0.0;      // 0: the grid stays at grid_step_px
  double min_disparity_px = 0.0;  // smaller disparities are not measured depths of this frame
  double max_range_m = -1.0;      // rays end here (< 0: no limit): no voxel lies farther
};

class MeasuredSurface {
 public:
  MeasuredSurface() = default;  // measures nothing: depthAt() is always false
  // disparity (px) of the left camera whose optical frame has pose T_map_camera.
  MeasuredSurface(const DisparityImageView& disparity, const StereoCamera& camera,
                  const Eigen::Isometry3d& T_map_camera, const MeasuredSurfaceConfig& config = {},
                  const SurfaceGridScale& scale = {});
  // px between grid nodes for a frame: grid_step_px, or coarser for `scale` (see
  // grid_footprint_fraction).
  static int gridStepFor(const DisparityImageView& disparity, const StereoCamera& camera,
                         const MeasuredSurfaceConfig& config, const SurfaceGridScale& scale);

  bool empty() const { return cells_.empty(); }
  // For a point in the map frame: its depth z along the optical axis and the depth of the
  // measured surface on its line of sight, z_surface; false where the image does not say
  // (behind the camera, outside the image, no grid surface near the pixel). reach_m: a point
  // whose projection lies outside the image by at most the projection of reach_m at its depth
  // reads the surface at the nearest border pixel (a voxel that rays through the border pixels
  // cross has its centre up to half its diagonal outside the image), and one whose pixel has no
  // surface (an invalid region: beyond the matcher's range, a hole) that of the nearest grid node
  // within that projection: a voxel is as large in the image, and a ray through it to a pixel
  // with a surface may have its centre's pixel in the invalid region (near the camera, a 0.2 m
  // voxel covers tens of pixels).
  bool depthAt(const Eigen::Vector3d& point_in_map, double* z, double* z_surface,
               double reach_m = 0.0) const;
  double focalBaseline() const { return focal_baseline_; }  // f * b (px m): z = f b / d
  int gridStep() const { return step_; }                    // px between grid nodes

 private:
  std::size_t linear(int i, int j) const { return static_cast<std::size_t>(j) * columns_ + i; }
  // The surface's disparity at grid node (i, j) (pixel (i, j) * grid_step_px), NaN where none.
  float cellAt(int i, int j) const { return cells_[linear(i, j)]; }
  double disparityAt(double u, double v) const;  // interpolated over the grid, or NaN
  // The disparity of the grid node nearest to pixel (u, v) that has a surface, within radius_px
  // of it; NaN where none has.
  double nearestNodeWithin(double u, double v, double radius_px) const;

  class SampleLattice;  // the wide windows' samples of the image (measured_surface.cpp)
  // gridStepFor, given the smallest disparity of its scan.
  static int gridStepForSmallest(float smallest, const StereoCamera& camera,
                                 const MeasuredSurfaceConfig& config,
                                 const SurfaceGridScale& scale);
  void measureNodes(const DisparityImageView& disparity, const SampleLattice& lattice,
                    const MeasuredSurfaceConfig& config);
  // band_only: only the grid points of the border's band (border_from_interior).
  void extendByOneNode(bool band_only = false);
  bool inBand(int i, int j) const {  // grid point (i, j) lies in the border's band (never: 0 px)
    const int u = i * step_, v = j * step_;
    return u < band_px_ || u > width_ - 1 - band_px_ || v < band_px_ || v > height_ - 1 - band_px_;
  }
  void findSteps(double step_px);

  Eigen::Isometry3d T_camera_map_ = Eigen::Isometry3d::Identity();
  double fx_ = 0, fy_ = 0, cx_ = 0, cy_ = 0, focal_baseline_ = 0;
  int width_ = 0, height_ = 0, step_ = 1, columns_ = 0, rows_ = 0;
  int band_px_ = 0;  // px from the image's border whose grid points are extrapolated (0: none)
  std::vector<float> cells_;         // row-major, columns_ x rows_
  std::vector<std::uint8_t> steps_;  // per cell (corners (i, j) to (i + 1, j + 1)): has a step
};

}  // namespace occupancy_fusion
