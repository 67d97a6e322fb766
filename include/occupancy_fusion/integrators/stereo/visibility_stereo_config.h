// The configuration of the visibility stereo integrator (Schauwecker & Zell 2014, Table I and the
// parameter sets beyond it; VisibilityStereoIntegrator).
#pragma once

#include <string>

#include "occupancy_fusion/integrators/stereo/measured_surface.h"
#include "occupancy_fusion/sensors/disparity_image.h"

namespace occupancy_fusion {

enum class StereoIntegrationMethod {
  kVisibility,  // the paper's method, Eq. 1-8
  kOctomap,     // OctoMap's update on the same rays: free up to the end voxel, a
                // hit in it
};
std::string toString(StereoIntegrationMethod method);
StereoIntegrationMethod stereoIntegrationMethodFromString(const std::string& name);

// How Eq. 1 reads a neighbour that was never observed. The paper's map is an OctoMap, which
// holds no node for unknown space, and the paper does not say; see docs/disparity_method.md
// for the measurements behind the default.
enum class UnknownNeighbours {
  kPrior,      // an unknown neighbour counts with P(O) = unknown_neighbour_occupancy
  kKnownOnly,  // the minimum of Eq. 1 over the known neighbours only; none known: P(C) = 0
  // Beyond the paper: an unknown neighbour is read from the current frame's own measurement
  // (MeasuredSurface): P(O) = Phi((z - z_s) / sigma_z(z_s)), the probability that the measured
  // surface on its line of sight lies in front of it (Eq. 7's sigma_z). Unknown space in front of
  // the measured surface is transparent at once, space behind it occludes as a known surface
  // does; where the image does not say, the prior (unknown_neighbour_occupancy).
  kMeasured,
};
std::string toString(UnknownNeighbours policy);
UnknownNeighbours unknownNeighboursFromString(
    const std::string& name);  // "known_only" | "prior" | "measured"

struct VisibilityStereoConfig {
  StereoIntegrationMethod method = StereoIntegrationMethod::kVisibility;

  // Sensor model of the Bayesian network (Fig. 2b), Table I.
  double prob_hit_visible_occupied = 0.55;  // P(H | V, O)
  double prob_hit_visible_free = 0.43;      // P(H | V, not O)
  double prob_hit_invisible = 0.05;         // P(H | not V)
  // Eq. 3, Table I: P(V_i | C_i, V_i-1) and P(V_i | not C_i, V_i-1).
  double prob_visible_if_occluded = 0.20;
  double prob_visible_if_not_occluded = 1.00;
  // q_min: a ray stops where the visibility falls below it. q_max: visibilities
  // at or above it count as 1 (Sec. III-A), so that clamped free voxels (P(O) =
  // the map's clamp_min) do not erode the visibility along a free ray. Table I:
  // {0.1, 0.7}.
  double visibility_min = 0.1;
  double visibility_max = 0.7;
  // P(O) of a never-observed voxel as the prior of Eq. 4-6.
  double unknown_occupancy = 0.5;
  // Eq. 1 and unknown space. kPrior at 0.5 (the default): unknown space is partly occluding
  // (each step through it multiplies the visibility by 1 - 0.8 * 0.5 = 0.6, below q_max), so a
  // new view is mapped a few voxels deeper with every frame (the gradual growth of Fig. 5a), and
  // Eq. 8's walk past a point into the unobserved space behind a surface ends within a few
  // voxels. Unknown space made non-occluding (kKnownOnly, or kPrior below 0.375, where the
  // factor reaches q_max) maps the corridor scene completely but with 4-17x OctoMap's
  // false-occupied voxels: behind a one-voxel-thick wall Eq. 1's minimum finds an unknown
  // neighbour, so nothing stops the walk past the point (measurements in
  // docs/disparity_method.md).
  UnknownNeighbours unknown_neighbours = UnknownNeighbours::kPrior;
  // P(O) of a never-observed neighbour in Eq. 1 under kPrior (and kMeasured where the image
  // does not say).
  double unknown_neighbour_occupancy = 0.5;
  // kMeasured, the frame's measured surface (MeasuredSurface) and how it enters Eq. 1-8 beyond
  // the paper (docs/disparity_method.md, "Moving camera"). Its depth sigma is Eq. 7's sigma_z,
  // kept within [sigma_min_voxels, sigma_max_voxels] voxels: at least the voxel's own extent,
  // at most what lets a far surface (sigma_z of metres) still occlude within two voxels. The
  // surface is a mean over a window, far less uncertain than one pixel's sigma_z: at 3 voxels
  // the rays went on ~1.5 sigma behind far walls at visibilities just above q_min, and their weak
  // hits were most of the matrix's false-occupied voxels at 0.05 m (forward 0.1 m/frame, half
  // input: 0.230 of the OctoMap mode's at 3 voxels, 0.178 at 2, 0.154 at 1.5 with coverage 0.90).
  MeasuredSurfaceConfig measured_surface;
  double measured_sigma_min_voxels = 1.0;
  double measured_sigma_max_voxels = 2.0;
  // Eq. 1 reads a known neighbour as the map's log-odds plus the measurement's free-space
  // evidence (at most one clamped miss), not the map's alone, so that a voxel the map holds near
  // 0.5 does not block a ray that the frame shows passing. Off by default: since voxels over
  // invalid pixels read the surface next to them it no longer carries coverage, and with it a
  // noisy frame's free space wore down walls the map knew (1 px of noise: false-occupied up to
  // 0.249 of the OctoMap mode's, 0.179 without; docs/design_notes.md).
  bool measured_fuse_known = false;
  // The prior of Eq. 4-6 of a never-observed voxel is the measurement's P(O) where that is below
  // unknown_occupancy: a hit in space the frame's surface shows free (a phantom of a patch shifted
  // towards the camera, the noise in front of a surface) starts from free.
  bool measured_prior = true;
  // P(I_v) of Eq. 8 is at most P(the measured surface lies in front of the voxel's back): a
  // voxel counts as inside only where the frame's surface agrees with its rays.
  bool measured_inside = true;
  // A voxel's visibility on a ray is at most P(the measured surface lies behind the voxel's
  // front): the space behind the frame's surface is invisible however Eq. 1's minimum reads the
  // neighbours (a ray grazing a surface always finds one in front of it).
  bool measured_visibility = true;
  // Beyond the paper, for what has left the view: a voxel that a ray passes clearly in front of
  // its measured point (its far side more than passed_sigmas range sigmas of Eq. 7 before the
  // point) does not occlude the rest of that ray, and, where no ray of the frame ends near it
  // (P(I_v) below 0.01 on all of them), takes a miss of passed_miss_probability instead of Eq.
  // 4-8's: the frame saw through it to a surface behind it. A matcher's correlated error ends its
  // rays in the error, not behind it.
  bool clear_passed = false;
  double passed_sigmas = 3.0;
  double passed_miss_probability = 0.3;
  // Eq. 8: the ray stops at the first voxel whose P(I_v) reaches this value
  // ("close to 1"); that voxel gets a full hit, P(O_v | H).
  double inside_stop_probability = 0.99;
  // m, as OctoMap's maxrange: a point farther from the sensor clears its ray up to this
  // distance (the voxel holding the cut is left out) and adds no hit. Negative: unlimited.
  double max_range = -1.0;
  // End-voxel ray bundling, the analogue of OctoMap's insertPointCloud(discretize = true): the
  // points of a frame whose measured point falls into the same voxel share its rays. A standing
  // camera's far surfaces give tens to hundreds of pixels per voxel, and every ray is walked
  // voxel by voxel, so this bounds the frame's work by its end voxels instead of its pixels.
  //  - kVisibility: the rays of the nearest and the farthest point (one if the voxel has one
  //    point), each with its own range sigma (Eq. 7), as one walk to the farthest point that
  //    carries both points' P(I_v): the two rays cross the same voxels but for one at a corner
  //    now and then, and a second walk cost a quarter of a frame (docs/design_notes.md). The
  //    frame's reduction takes the largest P(I_v) per voxel (StereoVoxelUpdate): in the end voxel
  //    and before it that is the nearest point's, since Phi((s - r) / sigma_r) grows as r falls.
  //    Eq. 8 puts the full hit ~2.3 sigma past a point, so the bundle's hits span from the nearest
  //    point's stop voxel to the farthest's, and the farthest ray keeps the deepest of them. The
  //    nearest point alone lost those (rostest sim_disparity_standing: 119 occupied voxels where it
  //    asks for >= 130); a mean depth would put the hit where no point is. Left out: the points in
  //    between (their depths lie between the two) and the lateral spread of the rays inside the
  //    voxel.
  //  - kOctomap: one ray to the end voxel's centre, as liboctomap's discretize = true does (the
  //    depth of the point does not enter OctoMap's update), so the two compare directly.
  // Points beyond max_range are bundled like the others (two walks where the farthest point of a
  // voxel lies beyond it, the cut one as the walk to such a point is).
  bool bundle_rays = true;
  // The disparity image's conversion to points (sigma_d of Eq. 7, input
  // resolution).
  DisparityConversionConfig disparity;

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// Named parameter sets of the visibility method. Sec. IV-A: the map's expansion into unknown
// space "strongly depends on the voxel size, q_max and P(V_vi | V_vi-1, C) ... one can choose a
// compromise between the speed of the map expansion and map quality". Measured on the simulated
// corridor (eval/stereo_corridor.h; docs/disparity_method.md, "Expansion against artifacts").
enum class StereoParameterSet {
  // The paper's Table I (the in-class defaults of VisibilityStereoConfig): about 1/13 of OctoMap's
  // false-occupied voxels but 0.75 of its surface coverage after 80 frames, since a ray stops
  // ~4 voxels into unknown space (0.6^n < q_min = 0.1) and a new view is mapped gradually.
  kTableI,
  // Table I with q_min = 0.003 and P(H | not V) = 0.2: a ray goes ~11 voxels into unknown space
  // (0.6^11 < 0.003), and a miss at partial visibility carries more evidence (an invisible
  // voxel's miss is less certain). q_max and P(V | C, V) stay at Table I's values: the swept
  // alternatives that raise the unknown-space factor 0.5 + 0.5 P(V | C, V) to q_max make unknown
  // space transparent, a cliff to 4-5x OctoMap's false-occupied voxels; these two keep a margin
  // of 0.1 from it. Corridor, 0.2 m: 0.11 of OctoMap's false-occupied voxels at 0.935 of its
  // coverage (80 frames), 0.07 at 0.935 (200 frames).
  kFastExpansion,
  // Beyond the paper, the default of the mappers: Table I with unknown_neighbours kMeasured, the
  // visibility of never-observed space from the frame's own measured surface, so that a moving
  // camera's new view is mapped from its first frames while the correlated matcher errors stay
  // rejected (docs/disparity_method.md, "Moving camera"), and clear_passed, so that what has left
  // the view is cleared within a few frames (docs/dynamic_scenes.md).
  kMeasured,
};
std::string toString(StereoParameterSet set);
StereoParameterSet stereoParameterSetFromString(
    const std::string& name);  // table_i | fast_expansion | measured
// The configuration of a named parameter set (every other field at the in-class defaults).
VisibilityStereoConfig visibilityStereoConfigFor(StereoParameterSet set);

}  // namespace occupancy_fusion
