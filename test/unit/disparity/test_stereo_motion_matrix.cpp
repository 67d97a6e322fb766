// Two cells of the stereo evaluation matrix (eval/stereo_motion_matrix.h, the full matrix is
// `benchmark disparity-artifacts --part matrix`): a camera driven along the corridor at 0.1 m per
// frame and a standing one, 320 x 240 disparity with white noise and patches of wrong disparity,
// 0.2 m voxels. After every frame from the 5th on, the mappers' default (parameter_set measured)
// against the OctoMap mode on the same rays and against the paper's Table I.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "occupancy_fusion/eval/stereo_motion_matrix.h"

namespace occupancy_fusion {
namespace {

constexpr double kResolution = 0.2;
constexpr int kFirstJudgedFrame = 4;  // the 5th frame

struct CellResult {
  double worst_coverage_ratio = 1e9;  // ours / OctoMap mode's, from the 5th frame on
  double worst_false_ratio = 0.0;
  double table_i_best_coverage = 0.0;  // Table I's coverage at its best frame
};

// reference_coverage: what the OctoMap mode covers at least from the 5th frame on (it maps every
// end point at once, but half input's rays leave gaps between them at fine voxels).
CellResult runCell(const std::string& motion, double resolution = kResolution, int frames = 20,
                   InputResolution input = InputResolution::kFull,
                   double reference_coverage = 0.9) {
  StereoMotionSetup setup;
  setup.motion = stereoMotionCaseFromName(motion);
  setup.frames = frames;
  const sim::Scene scene = setup.scene();
  const StereoRecording recording = renderStereoRecording(scene, setup);
  StereoGroundTruth truth(scene, recording, resolution);
  VisibilityStereoConfig measured = visibilityStereoConfigFor(StereoParameterSet::kMeasured);
  measured.disparity.input_resolution = input;
  VisibilityStereoConfig octomap = measured;
  octomap.method = StereoIntegrationMethod::kOctomap;
  VisibilityStereoConfig table_i;
  table_i.disparity.input_resolution = input;
  const StereoRunCurve ours = mapStereoRecording(measured, recording, resolution, &truth);
  const StereoRunCurve reference = mapStereoRecording(octomap, recording, resolution, &truth);
  const StereoRunCurve table_i_run = mapStereoRecording(table_i, recording, resolution, &truth);
  CellResult result;
  for (std::size_t k = kFirstJudgedFrame; k < ours.frames.size(); ++k) {
    const auto& q = ours.frames[k];
    const auto& r = reference.frames[k];
    EXPECT_GT(r.coverage, reference_coverage) << "frame " << k + 1;
    EXPECT_GT(r.false_occupied, 20u) << "frame " << k + 1;  // and the patches with it
    result.worst_coverage_ratio = std::min(result.worst_coverage_ratio, q.coverage / r.coverage);
    result.worst_false_ratio =
        std::max(result.worst_false_ratio, static_cast<double>(q.false_occupied) /
                                               std::max<std::size_t>(r.false_occupied, 1));
    result.table_i_best_coverage =
        std::max(result.table_i_best_coverage, table_i_run.frames[k].coverage);
  }
  std::printf(
      "%s: worst coverage ratio %.3f, worst false-occupied ratio %.3f, Table I's best "
      "coverage %.3f\n",
      motion.c_str(), result.worst_coverage_ratio, result.worst_false_ratio,
      result.table_i_best_coverage);
  return result;
}

TEST(StereoMotionMatrixTest, MovingCameraIsMappedWithoutTheOctomapModesArtifacts) {
  // Measured (Release, 20 frames): coverage ratio >= 0.93, false-occupied ratio <= 0.08; Table I
  // maps nothing of this corridor.
  const CellResult cell = runCell("forward_0.10");
  EXPECT_GE(cell.worst_coverage_ratio, 0.85);
  EXPECT_LE(cell.worst_false_ratio, 0.2);
  EXPECT_LT(cell.table_i_best_coverage, 0.1);
}

TEST(StereoMotionMatrixTest, StandingCameraIsMappedWithoutTheOctomapModesArtifacts) {
  // Measured (Release, 20 frames): coverage ratio >= 0.89 (at the 5th frame), false-occupied
  // ratio <= 0.08; Table I covers less than a tenth of the surface within 20 frames.
  const CellResult cell = runCell("standing");
  EXPECT_GE(cell.worst_coverage_ratio, 0.8);
  EXPECT_LE(cell.worst_false_ratio, 0.2);
  EXPECT_LT(cell.table_i_best_coverage, 0.2);
}

TEST(StereoMotionMatrixTest, FineVoxelsAtHalfInputStayWithinBothGoals) {
  // The matrix's tightest cell for false-occupied voxels (forward 0.1 m/frame, 0.05 m, half input;
  // 0.174 of the OctoMap mode's at frame 11 over 40 frames): its first 14 frames. Measured
  // (Release): coverage ratio >= 0.947, false-occupied ratio <= 0.174. With the measured surface's
  // sigma allowed to 3 voxels the false-occupied ratio is 0.225 here (0.230 over the 40 frames).
  const CellResult cell = runCell("forward_0.10", 0.05, 14, InputResolution::kHalf, 0.75);
  EXPECT_GE(cell.worst_coverage_ratio, 0.9);
  EXPECT_LE(cell.worst_false_ratio, 0.2);
  EXPECT_LT(cell.table_i_best_coverage, 0.01);
}

TEST(StereoMotionMatrixTest, MotionNames) {
  EXPECT_EQ(stereoMatrixMotions().size(), 6u);
  EXPECT_EQ(stereoMotionCaseFromName("turn_5deg").motion, StereoMotion::kTurn);
  EXPECT_DOUBLE_EQ(stereoMotionCaseFromName("forward_0.20").step, 0.2);
  EXPECT_THROW(stereoMotionCaseFromName("backward"), std::invalid_argument);
  // Other speeds of the same motions.
  const StereoMotionCase faster = stereoMotionCaseFromName("forward_0.35");
  EXPECT_EQ(faster.motion, StereoMotion::kForward);
  EXPECT_DOUBLE_EQ(faster.step, 0.35);
  EXPECT_DOUBLE_EQ(stereoMotionCaseFromName("turn_12.5deg").step, 12.5);
  EXPECT_EQ(stereoMotionCaseFromName("aisle_curve_0.25").motion, StereoMotion::kAisleCurve);
  EXPECT_EQ(stereoMotionCaseFromName("aisle_backward_0.2").motion, StereoMotion::kAisleBackward);
  for (const char* bad : {"forward_", "forward_-0.1", "forward_0", "forward_0.1x", "turn_5",
                          "turn_deg", "sideways_nan", "aisle_0.1"}) {
    EXPECT_THROW(stereoMotionCaseFromName(bad), std::invalid_argument) << bad;
  }
  // Poses: forward moves 0.1 m per frame along +x, standing stays.
  StereoMotionSetup setup;
  setup.motion = stereoMotionCaseFromName("forward_0.10");
  const auto poses = setup.poses();
  ASSERT_EQ(poses.size(), 40u);
  EXPECT_NEAR((poses[10].translation() - poses[0].translation()).x(), 1.0, 1e-12);
  setup.motion = stereoMotionCaseFromName("standing");
  EXPECT_TRUE(setup.poses().back().isApprox(setup.poses().front()));
}

TEST(StereoMotionMatrixTest, AisleMotionsHaveTheirOwnCameraAndScene) {
  EXPECT_EQ(stereoAisleMotions().size(), 4u);
  const StereoMotionSetup aisle = stereoSetupFor(stereoMotionCaseFromName("aisle_fast_0.30"));
  EXPECT_EQ(aisle.width, 640);
  EXPECT_DOUBLE_EQ(aisle.baseline, 0.09);
  EXPECT_DOUBLE_EQ(aisle.noise.patch_offset_px, 2.0);
  const auto poses = aisle.poses();
  EXPECT_NEAR((poses[10].translation() - poses[0].translation()).x(), 3.0, 1e-9);
  // The aisle's far wall at x = 14 is straight ahead: the first pose sees it 13.7 m away.
  const sim::Scene scene = aisle.scene();
  const Eigen::Vector3d forward = poses[0].linear().col(2);  // the optical axis
  const auto hit = scene.castRay(poses[0].translation(),
                                 Eigen::Vector3d(forward.x(), forward.y(), 0).normalized(), 20.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 13.7, 1e-6);
  // The matrix's own motions keep the matrix's camera.
  EXPECT_EQ(stereoSetupFor(stereoMotionCaseFromName("forward_0.10")).width, 320);
}

TEST(StereoMotionMatrixTest, OfficeMotionsStayInTheOfficesFreeSpace) {
  EXPECT_EQ(stereoOfficeMotions().size(), 5u);
  for (const char* name : {"office_loop_0.25", "office_zigzag_0.20", "office_backward_0.20"}) {
    SCOPED_TRACE(name);
    const StereoMotionSetup office = stereoSetupFor(stereoMotionCaseFromName(name));
    EXPECT_EQ(office.width, 848);
    EXPECT_DOUBLE_EQ(office.baseline, 0.095);
    const sim::Scene scene = office.scene();
    const auto poses = office.poses();
    ASSERT_EQ(poses.size(), 40u);
    for (std::size_t k = 0; k < poses.size(); ++k) {
      // Each step is the motion's, and no surface lies within 0.2 m of the camera: rays in the
      // six axis directions leave it freely.
      if (k > 0) {
        const double step = office.motion.step;
        const double moved = (poses[k].translation() - poses[k - 1].translation()).norm();
        EXPECT_NEAR(moved, step, 0.25 * step) << "frame " << k;
      }
      EXPECT_NEAR(poses[k].translation().z(), 1.1, 1e-9);
      for (int axis = 0; axis < 3; ++axis) {
        for (double sign : {-1.0, 1.0}) {
          const Eigen::Vector3d direction = sign * Eigen::Vector3d::Unit(axis);
          EXPECT_FALSE(scene.castRay(poses[k].translation(), direction, 0.2).has_value())
              << "frame " << k << " axis " << axis;
        }
      }
    }
  }
  // The zigzag's heading swings through +-30 deg: after 4 frames it looks 30 deg to the left.
  const StereoMotionSetup zigzag = stereoSetupFor(stereoMotionCaseFromName("office_zigzag_0.10"));
  const Eigen::Vector3d axis = zigzag.poses()[4].linear().col(2);  // the optical axis
  EXPECT_NEAR(std::atan2(axis.y(), axis.x()), 30.0 * M_PI / 180.0, 1e-9);
  // Backwards along the same line: from x = 3.8 towards -x, looking the same way.
  const StereoMotionSetup backward =
      stereoSetupFor(stereoMotionCaseFromName("office_backward_0.10"));
  EXPECT_NEAR(backward.poses()[10].translation().x(), 2.8, 1e-9);
  EXPECT_TRUE(backward.poses()[4].linear().isApprox(zigzag.poses()[4].linear()));
}

}  // namespace
}  // namespace occupancy_fusion
