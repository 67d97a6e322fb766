// The stereo evaluation matrix: a moving stereo camera (forward along a corridor at three speeds,
// turning in place, a sideways pass along a wall with objects, standing) seeing disparity with
// white noise and persistent patches of wrong disparity, mapped by any stereo configuration;
// after every frame, false-occupied voxels and the coverage of the surface seen so far against
// the scene's ground truth. Shared by `benchmark disparity-artifacts --part matrix` and the
// unit tests.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

#include "occupancy_fusion/eval/stereo_corridor.h"
#include "occupancy_fusion/integrators/stereo/visibility_stereo_integrator.h"
#include "occupancy_fusion/sim/scene.h"
#include "occupancy_fusion/sim/stereo_camera.h"

namespace occupancy_fusion {

enum class StereoMotion {
  kForward,   // along the corridor's axis, looking ahead; step in m per frame
  kTurn,      // turning in place about the vertical in the room; step in deg per frame
  kSideways,  // along the corridor's left wall (a pillar, the doorway), looking at it; m per frame
  kStanding,  // the forward start pose, unmoved
  // The check outside the matrix: the warehouse aisle (sim::makeAisleScene), another camera
  // (stereoSetupFor), motions the matrix does not have.
  kAisleCurve,     // along the aisle, the heading sweeping from -20 to +58 deg; m per frame
  kAisleDiagonal,  // across the aisle at 26.6 deg, looking 15 deg to the left; m per frame
  kAisleFast,      // straight along the aisle; m per frame
  kAisleBackward,  // backing out of the aisle, looking 10 deg to the right of ahead; m per frame
  // A third check: the office (sim::makeOfficeScene), a third camera (stereoSetupFor).
  kOfficeLoop,      // around the furniture on an ellipse, looking along the path; m per frame
  kOfficeZigzag,    // across the office, the heading swinging +-30 deg every 16 frames; m per frame
  kOfficeBackward,  // the zigzag's line backwards from x = 3.8, looking and swinging as it; m/frame
};

struct StereoMotionCase {
  std::string name;  // e.g. "forward_0.10"
  StereoMotion motion = StereoMotion::kForward;
  double step = 0.0;
};
// forward 0.03, 0.1 and 0.2 m per frame; turning 5 deg per frame; sideways 0.1 m per frame;
// standing.
std::vector<StereoMotionCase> stereoMatrixMotions();
// The check outside the matrix: aisle_curve_0.15, aisle_diagonal_0.09, aisle_fast_0.30,
// aisle_backward_0.10, 0.05 to 0.3 m per frame.
std::vector<StereoMotionCase> stereoAisleMotions();
// The third check: office_loop_0.10, office_loop_0.25, office_zigzag_0.10, office_zigzag_0.20,
// office_backward_0.10.
std::vector<StereoMotionCase> stereoOfficeMotions();
StereoMotionCase stereoMotionCaseFromName(const std::string& name);  // throws on an unknown name

struct StereoMotionSetup {
  StereoMotionCase motion;
  int frames = 40;
  int width = 320, height = 240;
  double focal_px = 250.0;
  double baseline = 0.12;  // m
  double max_range = 8.0;  // m, rendered depth limit
  sim::DisparityNoise noise = StereoCorridorSetup().noise();

  bool isAisle() const;
  bool isOffice() const;
  sim::PinholeCamera camera() const;
  StereoCamera stereo() const;
  sim::Scene scene() const;  // corridor, the room for kTurn, the aisle or the office
  std::vector<Eigen::Isometry3d> poses() const;  // the left optical frame per frame
};

// The set-up of a motion: the matrix's camera (above), or for the aisle motions another one:
// 640 x 480, f = 420 px, b = 0.09 m, rendered up to 10 m, white noise 0.4 px and patches of
// +-2 px in 25 % of 16 px cells, kept for 6 frames (seed 11); for the office motions a third:
// 848 x 480, f = 425 px, b = 0.095 m (a depth camera's stereo pair), rendered up to 8 m, white
// noise 0.5 px and patches of +-2.5 px in 20 % of 20 px cells, kept for 4 frames (seed 23).
StereoMotionSetup stereoSetupFor(const StereoMotionCase& motion);

// The rendered disparity images of a set-up (independent of the mapper).
struct StereoRecording {
  StereoMotionSetup setup;
  std::vector<sim::DisparityImage> images;
  std::vector<Eigen::Isometry3d> poses;
};
StereoRecording renderStereoRecording(const sim::Scene& scene, const StereoMotionSetup& setup);

// Ground truth of one voxel size: surface samples `resolution` apart, each with the first frame
// that sees it (in the image, within max_range, not occluded), and a cache of voxel classes.
class StereoGroundTruth {
 public:
  StereoGroundTruth(const sim::Scene& scene, const StereoRecording& recording, double resolution);

  struct FrameQuality {
    std::size_t occupied = 0;
    std::size_t false_occupied = 0;    // centre in free space, farther than a voxel diagonal from
                                       // any surface
    std::size_t surface_occupied = 0;  // the other occupied voxels
    double coverage = 0.0;             // of the samples seen by frames 0..k: an occupied voxel
                                       // within one voxel of it
    std::size_t seen_samples = 0;
  };
  // The quality of `occupied` after frame k.
  FrameQuality evaluate(const OccupiedVoxelSet& occupied, int frame);
  // Whether a voxel is false-occupied when occupied (cached).
  bool isFalse(const VoxelIndex& voxel);
  double resolution() const { return resolution_; }

 private:
  const sim::Scene& scene_;
  double resolution_;
  std::vector<VoxelIndex> sample_voxels_;
  std::vector<int> first_seen_;  // per sample
  SpatialKeyMap<bool> is_false_;
};

// One configuration mapping a recording, evaluated after every frame.
struct StereoRunCurve {
  std::vector<StereoGroundTruth::FrameQuality> frames;
  double seconds = 0.0;  // wall time of the integrate() calls
  OccupiedVoxelSet final_occupied;
};
StereoRunCurve mapStereoRecording(const VisibilityStereoConfig& config,
                                  const StereoRecording& recording, double resolution,
                                  StereoGroundTruth* truth);

}  // namespace occupancy_fusion
