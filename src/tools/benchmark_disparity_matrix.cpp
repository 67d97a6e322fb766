// benchmark disparity-artifacts --part matrix: the stereo methods on a moving camera
// (eval/stereo_motion_matrix.h). For every cell (motion x voxel size x input resolution) and
// method (the configuration under test, the paper's Table I, the OctoMap mode on the same rays):
// false-occupied voxels and surface coverage after every frame, as ratios to the OctoMap mode of
// the same frame, and the cell's worst ratio from the 5th frame on.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "occupancy_fusion/eval/stereo_motion_matrix.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

constexpr int kFirstJudgedFrame = 4;  // the 5th frame: the goals hold from it on

struct MethodUnderTest {
  std::string name;
  VisibilityStereoConfig config;
};

struct CellResult {
  std::string motion;
  double resolution = 0;
  std::string input;
  std::vector<StereoRunCurve> curves;  // per method, [last] the OctoMap mode
};

// Worst ratios to the OctoMap mode from the 5th frame on: lowest coverage, highest false count.
struct WorstRatios {
  double coverage = 1e9;
  double false_occupied = 0;
  int coverage_frame = -1, false_frame = -1;
};

double falseRatio(std::size_t ours, std::size_t reference) {
  // A reference of 0 false voxels: ours / 1, so that any false voxel shows.
  return static_cast<double>(ours) / std::max<std::size_t>(reference, 1);
}

WorstRatios worstRatios(const StereoRunCurve& curve, const StereoRunCurve& octomap) {
  WorstRatios worst;
  for (std::size_t k = kFirstJudgedFrame; k < curve.frames.size(); ++k) {
    const auto& ours = curve.frames[k];
    const auto& reference = octomap.frames[k];
    const double coverage = reference.coverage > 0 ? ours.coverage / reference.coverage : 1.0;
    const double false_ratio = falseRatio(ours.false_occupied, reference.false_occupied);
    if (coverage < worst.coverage) {
      worst.coverage = coverage;
      worst.coverage_frame = static_cast<int>(k);
    }
    if (false_ratio > worst.false_occupied) {
      worst.false_occupied = false_ratio;
      worst.false_frame = static_cast<int>(k);
    }
  }
  return worst;
}

}  // namespace

int runDisparityMatrix(const CommandLine& args, const VisibilityStereoConfig& candidate,
                       const std::vector<double>& resolutions) {
  std::vector<StereoMotionCase> motions;
  if (args.has("motions")) {
    for (const std::string& name : args.listValue("motions", "")) {
      motions.push_back(stereoMotionCaseFromName(name));
    }
  } else {
    motions = stereoMatrixMotions();
  }
  std::vector<InputResolution> inputs;
  for (const std::string& name : args.listValue("inputs", "full,half")) {
    inputs.push_back(inputResolutionFromString(name));
  }
  const int frames = args.intValue("frames", 40);
  if (frames <= kFirstJudgedFrame) throw UsageError("--frames must be at least 5");
  const std::string curves_path = args.value("curves", "");
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> curves(nullptr, &std::fclose);
  if (!curves_path.empty()) {
    curves.reset(std::fopen(curves_path.c_str(), "w"));
    if (!curves) throw UsageError("cannot write " + curves_path);
    std::fprintf(curves.get(),
                 "motion,resolution,input,method,frame,occupied,surface_occupied,false_occupied,"
                 "coverage,coverage_vs_octomap,false_vs_octomap\n");
  }
  VisibilityStereoConfig table_i = visibilityStereoConfigFor(StereoParameterSet::kTableI);
  VisibilityStereoConfig octomap = table_i;
  octomap.method = StereoIntegrationMethod::kOctomap;
  std::printf(
      "# matrix: %zu motions x %zu voxel sizes x %zu inputs, %d frames; ratios to the "
      "OctoMap mode of the same frame, worst from frame 5 on\n",
      motions.size(), resolutions.size(), inputs.size(), frames);
  for (const StereoMotionCase& motion : motions) {
    StereoMotionSetup setup;
    setup.motion = motion;
    setup.frames = frames;
    const sim::Scene scene = setup.scene();
    const StereoRecording recording = renderStereoRecording(scene, setup);
    for (double resolution : resolutions) {
      StereoGroundTruth truth(scene, recording, resolution);
      for (InputResolution input : inputs) {
        std::vector<MethodUnderTest> methods = {
            {"candidate", candidate}, {"table_i", table_i}, {"octomap_mode", octomap}};
        for (MethodUnderTest& method : methods) method.config.disparity.input_resolution = input;
        std::vector<StereoRunCurve> runs;
        for (const MethodUnderTest& method : methods) {
          runs.push_back(mapStereoRecording(method.config, recording, resolution, &truth));
        }
        const StereoRunCurve& reference = runs.back();
        for (std::size_t m = 0; m < methods.size(); ++m) {
          const StereoRunCurve& run = runs[m];
          const auto& last = run.frames.back();
          const auto& last_reference = reference.frames.back();
          const WorstRatios worst = worstRatios(run, reference);
          std::printf(
              "disparity-matrix motion=%s resolution=%.2f input=%s method=%s occupied=%zu "
              "surface_occupied=%zu false_occupied=%zu coverage=%.3f end_coverage_vs_octomap=%.3f "
              "end_false_vs_octomap=%.3f worst_coverage_vs_octomap=%.3f@%d "
              "worst_false_vs_octomap=%.3f@%d ms_per_frame=%.1f\n",
              motion.name.c_str(), resolution, toString(input).c_str(), methods[m].name.c_str(),
              last.occupied, last.surface_occupied, last.false_occupied, last.coverage,
              last_reference.coverage > 0 ? last.coverage / last_reference.coverage : 1.0,
              falseRatio(last.false_occupied, last_reference.false_occupied), worst.coverage,
              worst.coverage_frame + 1, worst.false_occupied, worst.false_frame + 1,
              1e3 * run.seconds / frames);
          if (!curves) continue;
          for (std::size_t k = 0; k < run.frames.size(); ++k) {
            const auto& q = run.frames[k];
            const auto& r = reference.frames[k];
            std::fprintf(curves.get(), "%s,%.2f,%s,%s,%zu,%zu,%zu,%zu,%.4f,%.4f,%.4f\n",
                         motion.name.c_str(), resolution, toString(input).c_str(),
                         methods[m].name.c_str(), k + 1, q.occupied, q.surface_occupied,
                         q.false_occupied, q.coverage,
                         r.coverage > 0 ? q.coverage / r.coverage : 1.0,
                         falseRatio(q.false_occupied, r.false_occupied));
          }
        }
        std::fflush(stdout);
      }
    }
  }
  return 0;
}

}  // namespace occupancy_fusion
