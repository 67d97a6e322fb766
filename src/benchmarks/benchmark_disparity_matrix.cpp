// benchmark disparity-artifacts --part matrix: the stereo methods on a moving camera
// (eval/stereo_motion_matrix.h). For every cell (motion x voxel size x input resolution) and
// method (the set under test, by default the mappers' measured, the paper's Table I, the OctoMap
// mode on the same rays):
// false-occupied voxels and surface coverage after every frame, as ratios to the OctoMap mode of
// the same frame, and the cell's worst ratio from the 5th frame on.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "occupancy_fusion/eval/stereo_motion_matrix.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {

// benchmark_disparity_artifacts.cpp: occupied voxels seen from above, false ones red.
cv::Mat stereoTopView(const std::string& title, const OccupiedVoxelSet& occupied,
                      const std::vector<bool>& is_false, const sim::Scene& scene, double resolution,
                      const std::vector<Eigen::Isometry3d>& poses, double camera_height);

namespace {

constexpr int kFirstJudgedFrame = 4;  // the 5th frame: the goals hold from it on

struct MethodUnderTest {
  std::string name;
  VisibilityStereoConfig config;
};

// The cell whose default has the lowest coverage ratio, kept for its pictures.
struct WorstCell {
  double coverage_ratio = 1e9;
  std::string name;
  std::vector<cv::Mat> top_views;  // per method
  std::vector<StereoRunCurve> runs;
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

// Coverage and false-occupied ratios to the OctoMap mode per frame: the lag of each method.
cv::Mat plotRatios(const WorstCell& cell, const std::vector<std::string>& names) {
  constexpr int kWidth = 640, kHeight = 360, kLeft = 50, kBottom = 40, kTop = 30;
  constexpr double kMaxRatio = 1.2;
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const StereoRunCurve& reference = cell.runs.back();
  const std::size_t frames = reference.frames.size();
  auto pixel = [&](double frame, double ratio) {
    return cv::Point(
        kLeft + static_cast<int>((frame - 1) / (frames - 1) * (kWidth - kLeft - 20)),
        kHeight - kBottom -
            static_cast<int>(std::min(ratio, kMaxRatio) / kMaxRatio * (kHeight - kBottom - kTop)));
  };
  for (double goal : {0.2, 0.9}) {
    cv::line(image, pixel(1, goal), pixel(frames, goal), cv::Scalar(180, 180, 180), 1);
  }
  cv::line(image, pixel(5, 0), pixel(5, kMaxRatio), cv::Scalar(220, 220, 220), 1);
  const cv::Scalar colours[] = {cv::Scalar(200, 80, 0), cv::Scalar(0, 160, 0)};
  for (std::size_t m = 0; m + 1 < cell.runs.size() && m < 2; ++m) {
    for (std::size_t k = 1; k < frames; ++k) {
      auto coverage = [&](std::size_t f) {
        const double r = reference.frames[f].coverage;
        return r > 0 ? cell.runs[m].frames[f].coverage / r : 1.0;
      };
      auto false_ratio = [&](std::size_t f) {
        return falseRatio(cell.runs[m].frames[f].false_occupied,
                          reference.frames[f].false_occupied);
      };
      cv::line(image, pixel(k, coverage(k - 1)), pixel(k + 1, coverage(k)), colours[m], 2,
               cv::LINE_AA);
      cv::line(image, pixel(k, false_ratio(k - 1)), pixel(k + 1, false_ratio(k)), colours[m], 1,
               cv::LINE_AA);
    }
  }
  char text[300];
  std::snprintf(text, sizeof(text),
                "%s: coverage (thick) and false-occupied (thin) / OctoMap mode; blue %s, green %s",
                cell.name.c_str(), names[0].c_str(), names[1].c_str());
  cv::putText(image, text, cv::Point(8, 18), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  for (double tick : {0.0, 0.2, 0.5, 0.9, 1.0}) {
    std::snprintf(text, sizeof(text), "%.1f", tick);
    cv::putText(image, text, pixel(1, tick) + cv::Point(-40, 4), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  for (std::size_t frame : {std::size_t{1}, std::size_t{5}, frames / 2, frames}) {
    std::snprintf(text, sizeof(text), "%zu", frame);
    cv::putText(image, text, pixel(frame, 0) + cv::Point(-6, 18), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  cv::putText(image, "frame", cv::Point(kWidth / 2, kHeight - 6), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return image;
}

// The matcher's errors of a set-up with the options that vary them (--noise_px,
// --patch_probability,
// --patch_px, --patch_offset_px, --seed).
sim::DisparityNoise withOptions(const CommandLine& args, sim::DisparityNoise noise) {
  noise.sigma_px = args.doubleValue("noise_px", noise.sigma_px);
  noise.patch_probability = args.doubleValue("patch_probability", noise.patch_probability);
  noise.patch_size_px = args.intValue("patch_px", noise.patch_size_px);
  noise.patch_offset_px = args.doubleValue("patch_offset_px", noise.patch_offset_px);
  noise.seed = static_cast<std::uint64_t>(args.intValue("seed", static_cast<int>(noise.seed)));
  try {
    noise.validate();
  } catch (const std::invalid_argument& error) {
    throw UsageError(error.what());
  }
  return noise;
}

void writeImage(const std::string& path, const cv::Mat& image) {
  if (!cv::imwrite(path, image)) throw UsageError("cannot write " + path);
  std::printf("wrote %s\n", path.c_str());
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
  const std::string images = args.value("images", "");
  WorstCell worst_cell;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> curves(nullptr, &std::fclose);
  if (!curves_path.empty()) {
    curves.reset(std::fopen(curves_path.c_str(), "w"));
    if (!curves) throw UsageError("cannot write " + curves_path);
    std::fprintf(curves.get(),
                 "motion,resolution,input,method,frame,occupied,surface_occupied,false_occupied,"
                 "coverage,coverage_vs_octomap,false_vs_octomap\n");
  }
  withOptions(args, StereoMotionSetup().noise);  // bad error options fail before any work
  VisibilityStereoConfig table_i = visibilityStereoConfigFor(StereoParameterSet::kTableI);
  VisibilityStereoConfig octomap = table_i;
  octomap.method = StereoIntegrationMethod::kOctomap;
  std::printf(
      "# matrix: %zu motions x %zu voxel sizes x %zu inputs, %d frames; ratios to the "
      "OctoMap mode of the same frame, worst from frame 5 on\n",
      motions.size(), resolutions.size(), inputs.size(), frames);
  for (const StereoMotionCase& motion : motions) {
    StereoMotionSetup setup = stereoSetupFor(motion);
    setup.frames = frames;
    setup.noise = withOptions(args, setup.noise);
    std::printf(
        "# %s: %dx%d px, f %.0f px, b %.2f m, range %.0f m; noise %.2f px, patches %.2f of "
        "%d px cells, %.2f px offset, kept %d frames, seed %llu\n",
        motion.name.c_str(), setup.width, setup.height, setup.focal_px, setup.baseline,
        setup.max_range, setup.noise.sigma_px, setup.noise.patch_probability,
        setup.noise.patch_size_px, setup.noise.patch_offset_px,
        setup.noise.patch_persistence_frames, static_cast<unsigned long long>(setup.noise.seed));
    const sim::Scene scene = setup.scene();
    const StereoRecording recording = renderStereoRecording(scene, setup);
    for (double resolution : resolutions) {
      StereoGroundTruth truth(scene, recording, resolution);
      for (InputResolution input : inputs) {
        std::vector<MethodUnderTest> methods = {
            {args.value("parameter_set", "measured"), candidate},
            {"table_i", table_i},
            {"octomap_mode", octomap}};
        for (MethodUnderTest& method : methods) method.config.disparity.input_resolution = input;
        std::vector<StereoRunCurve> runs;
        for (const MethodUnderTest& method : methods) {
          runs.push_back(mapStereoRecording(method.config, recording, resolution, &truth));
        }
        const StereoRunCurve& reference = runs.back();
        const double coverage_ratio = worstRatios(runs.front(), reference).coverage;
        if (!images.empty() && coverage_ratio < worst_cell.coverage_ratio) {
          worst_cell.coverage_ratio = coverage_ratio;
          char name[160];
          std::snprintf(name, sizeof(name), "%s, %.2f m, %s input", motion.name.c_str(), resolution,
                        toString(input).c_str());
          worst_cell.name = name;
          worst_cell.top_views.clear();
          for (std::size_t m = 0; m < methods.size(); ++m) {
            std::vector<bool> is_false;
            for (const VoxelIndex& v : runs[m].final_occupied.voxels) {
              is_false.push_back(truth.isFalse(v));
            }
            worst_cell.top_views.push_back(stereoTopView(
                std::string(name) + ", " + methods[m].name + " after " + std::to_string(frames) +
                    " frames",
                runs[m].final_occupied, is_false, scene, resolution, recording.poses, 1.2));
          }
          worst_cell.runs = runs;
        }
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
  if (!images.empty() && !worst_cell.runs.empty()) {
    cv::Mat stacked;
    cv::vconcat(worst_cell.top_views, stacked);
    writeImage(images + "/disparity_matrix_worst_top.png", stacked);
    writeImage(images + "/disparity_matrix_worst_curves.png",
               plotRatios(worst_cell, {args.value("parameter_set", "measured"), "table_i"}));
  }
  return 0;
}

}  // namespace occupancy_fusion
