// The depth integrator's configuration (Pirker et al. 2011; PyramidDepthIntegrator).
#pragma once

#include <string>

namespace occupancy_fusion {

enum class DepthMethod {
  kPyramid,  // the paper's: closest-to-t_i pyramid, bilinear (Eq. 15) and inter-layer (Eq. 17)
  kAndert,   // baseline: min-depth pyramid, the one layer nearest the voxel's footprint, no
             // interpolation
  kIdeal,    // Eq. 8-9: every pixel ray through the voxel, weighted by its length inside it
};
std::string toString(DepthMethod method);
DepthMethod depthMethodFromString(const std::string& name);  // "pyramid", "andert", "ideal"

struct PyramidDepthConfig {
  // Inverse sensor model, Eq. 7. Its peak is 0.5 + k / (sigma(d) sqrt(2 pi)), so p stays in
  // (0, 1) only while k / (sigma sqrt(2 pi)) < 0.5.
  double k = 0.6;      // importance factor
  double sigma = 0.6;  // m, measurement uncertainty at distance 0
  // Real depth cameras' noise grows about with the square of the distance:
  // sigma(d) = sigma + sigma_quadratic * d^2, d the measured distance (Eq. 6). A larger sigma
  // lowers and widens the peak, so validity at sigma guarantees validity at every distance.
  double sigma_quadratic = 0.0;  // 1/m
  double min_range = 0.1;        // m, voxels nearer to the camera centre are not updated
  double max_range = 10.0;       // m, measured distances (Eq. 6) beyond it are invalid
  // Space behind surfaces stays unknown: a voxel is updated only if it lies no farther than
  // measured + unknown_behind_sigmas * sigma(measured) for at least one measurement it reads.
  double unknown_behind_sigmas = 3.0;
  int max_pyramid_levels = 12;  // cap on the number of layers M_0 ... M_{L-1}
  // Not the paper (default 0 is): t_0 = focal length x resolution / 2^finer_layers, so every
  // voxel reads layers finer_layers levels finer than Eq. 11-12 assign, and each layer keeps
  // the measurement closest to its halved t_i. With 1 the bilinear stencil of Eq. 15 (two
  // cells) spans about the voxel's footprint instead of twice it: on surfaces seen at more than
  // 80 degrees incidence the paper's cells keep depths tens of sigma beyond or in front of the
  // voxel (docs/depth_method.md, "Grazing incidence"). kPyramid only.
  int finer_layers = 0;
  DepthMethod method = DepthMethod::kPyramid;
  // Not the paper (default false is): a voxel the map holds occupied whose Eq. 15-17 update is
  // at most Eq. 7's value passed_sigmas in front of a measurement (the frame sees through it to a
  // surface behind) takes a miss of passed_miss_probability instead: what has left the view is
  // cleared in 4 frames instead of 5. Not for kIdeal.
  bool clear_passed = false;
  double passed_sigmas = 3.0;             // > 0
  double passed_miss_probability = 0.25;  // in (0, 0.3)

  void validate() const;  // throws std::invalid_argument naming the bad field
};

}  // namespace occupancy_fusion
