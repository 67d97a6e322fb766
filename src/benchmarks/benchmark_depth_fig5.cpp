// benchmark depth-fig5: Pirker et al.'s Fig. 2 / Fig. 5 setup. A 400 x 400 camera (f = 400)
// sees an obstacle at 6 m on the left of an edge and one at 10 m on the right; map voxels of
// r = 0.1 m, k = sigma = 0.6. Occupancy along the optical axis for the ideal model (Eq. 8-9),
// the pyramid (Eq. 10-17) and Andert's min-depth scheme, their errors against the ideal, a PNG
// plot, and the same errors as the edge moves off the axis.
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "occupancy_fusion/eval/depth_axis_profile.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

using Profile = AxisProfile;

struct Curve {
  const Profile* profile;
  cv::Scalar color;  // BGR
  std::string label;
  int thickness;  // the ideal is drawn wide underneath, so a method on top of it stays visible
};

// Occupancy probability over distance: axes with ticks, one polyline per curve, a legend.
cv::Mat plotProfiles(const std::vector<Curve>& curves) {
  const int width = 900, height = 520, left = 70, right = 20, top = 30, bottom = 60;
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const double z_max = 12.5, p_min = 0.2, p_max = 1.0;
  auto to_pixel = [&](double z, double p) {
    return cv::Point(left + static_cast<int>(std::lround((width - left - right) * z / z_max)),
                     top + static_cast<int>(std::lround((height - top - bottom) * (p_max - p) /
                                                        (p_max - p_min))));
  };
  const cv::Scalar black(0, 0, 0), grey(200, 200, 200);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  for (int z = 0; z <= 12; z += 2) {
    cv::line(image, to_pixel(z, p_min), to_pixel(z, p_max), grey, 1);
    cv::putText(image, std::to_string(z), to_pixel(z, p_min) + cv::Point(-6, 20), font, 0.5, black,
                1, cv::LINE_AA);
  }
  for (int tenth = 2; tenth <= 10; ++tenth) {
    const double p = 0.1 * tenth;
    cv::line(image, to_pixel(0.0, p), to_pixel(z_max, p), grey, 1);
    char label[8];
    std::snprintf(label, sizeof(label), "%.1f", p);
    cv::putText(image, label, to_pixel(0.0, p) + cv::Point(-40, 5), font, 0.5, black, 1,
                cv::LINE_AA);
  }
  cv::rectangle(image, to_pixel(0.0, p_max), to_pixel(z_max, p_min), black, 1);
  cv::putText(image, "distance along the optical axis [m]", cv::Point(width / 2 - 150, height - 15),
              font, 0.55, black, 1, cv::LINE_AA);
  cv::putText(image, "p(occupied)", cv::Point(5, 20), font, 0.55, black, 1, cv::LINE_AA);
  for (std::size_t c = 0; c < curves.size(); ++c) {
    const Profile& profile = *curves[c].profile;
    std::vector<cv::Point> points;
    for (std::size_t i = 0; i < profile.distance.size(); ++i) {
      points.push_back(to_pixel(profile.distance[i], profileProbability(profile.log_odds[i])));
    }
    cv::polylines(image, points, false, curves[c].color, curves[c].thickness, cv::LINE_AA);
    const cv::Point legend(left + 20, top + 25 + 25 * static_cast<int>(c));
    cv::line(image, legend, legend + cv::Point(30, 0), curves[c].color, curves[c].thickness,
             cv::LINE_AA);
    cv::putText(image, curves[c].label, legend + cv::Point(40, 5), font, 0.55, black, 1,
                cv::LINE_AA);
  }
  return image;
}

}  // namespace

int runDepthFig5(const CommandLine& args) {
  const std::string output = args.value("output", "");
  // depth/finer_layers (not the paper): 0 leaves it out, F > 0 adds the pyramid with it.
  const int finer_layers = args.intValue("finer_layers", 0);
  if (finer_layers < 0 || finer_layers > 4) throw UsageError("--finer_layers must be in [0, 4]");
  const bool with_finer = finer_layers > 0;
  const Profile ideal = fig5AxisProfile(DepthMethod::kIdeal, 0.0);
  const Profile pyramid = fig5AxisProfile(DepthMethod::kPyramid, 0.0);
  const Profile andert = fig5AxisProfile(DepthMethod::kAndert, 0.0);
  const Profile finer =
      with_finer ? fig5AxisProfile(DepthMethod::kPyramid, 0.0, finer_layers) : Profile();
  std::printf(
      "# Fig. 5: obstacles at 6 m (left of the edge) and 10 m, edge on the optical axis,\n"
      "# 400 x 400 px, f = 400, r = 0.1 m, k = sigma = 0.6; p = 0.5 where unknown\n");
  std::printf("# z[m]  ideal   pyramid andert%s\n", with_finer ? "  pyramid_finer" : "");
  for (std::size_t i = 0; i < ideal.distance.size(); ++i) {
    std::printf("%6.2f  %.4f  %.4f  %.4f", ideal.distance[i], profileProbability(ideal.log_odds[i]),
                profileProbability(pyramid.log_odds[i]), profileProbability(andert.log_odds[i]));
    if (with_finer) std::printf("  %.4f", profileProbability(finer.log_odds[i]));
    std::printf("\n");
  }
  const ProfileErrors pyramid_errors = errorsAgainstIdeal(ideal, pyramid);
  const ProfileErrors andert_errors = errorsAgainstIdeal(ideal, andert);
  std::printf("depth-fig5 method=pyramid edge_offset_px=0 mean_abs_error=%.4f max_abs_error=%.4f\n",
              pyramid_errors.mean, pyramid_errors.max);
  std::printf("depth-fig5 method=andert edge_offset_px=0 mean_abs_error=%.4f max_abs_error=%.4f\n",
              andert_errors.mean, andert_errors.max);
  if (with_finer) {
    const ProfileErrors finer_errors = errorsAgainstIdeal(ideal, finer);
    std::printf(
        "depth-fig5 method=pyramid finer_layers=%d edge_offset_px=0 mean_abs_error=%.4f "
        "max_abs_error=%.4f\n",
        finer_layers, finer_errors.mean, finer_errors.max);
  }

  // The edge moved off the axis: the axis voxels then see only the near obstacle in the ideal
  // model once their footprint (t_0 / z pixels) no longer reaches the edge.
  const double sweep_max = args.doubleValue("sweep_max", 8.0);
  for (double offset = 0.5; offset <= sweep_max + 1e-9; offset += 0.5) {
    const Profile ideal_off = fig5AxisProfile(DepthMethod::kIdeal, offset);
    const ProfileErrors p =
        errorsAgainstIdeal(ideal_off, fig5AxisProfile(DepthMethod::kPyramid, offset));
    const ProfileErrors a =
        errorsAgainstIdeal(ideal_off, fig5AxisProfile(DepthMethod::kAndert, offset));
    std::printf(
        "depth-fig5-offaxis edge_offset_px=%.1f pyramid_mean=%.4f pyramid_max=%.4f "
        "andert_mean=%.4f andert_max=%.4f closer=%s (tie: means within 1e-4)",
        offset, p.mean, p.max, a.mean, a.max,
        std::abs(p.mean - a.mean) < 1e-4 ? "tie"
        : p.mean < a.mean                ? "pyramid"
                                         : "andert");
    if (with_finer) {
      const ProfileErrors f = errorsAgainstIdeal(
          ideal_off, fig5AxisProfile(DepthMethod::kPyramid, offset, finer_layers));
      std::printf(" finer_mean=%.4f finer_max=%.4f", f.mean, f.max);
    }
    std::printf("\n");
  }

  if (!output.empty()) {
    std::vector<Curve> curves = {{&ideal, cv::Scalar(170, 170, 170), "ideal (Eq. 8-9)", 7},
                                 {&pyramid, cv::Scalar(200, 80, 0), "pyramid (Eq. 10-17)", 2},
                                 {&andert, cv::Scalar(0, 0, 220), "Andert (min depth)", 2}};
    const std::string finer_label =
        "pyramid, finer_layers " + std::to_string(finer_layers) + " (not the paper)";
    if (with_finer) curves.push_back({&finer, cv::Scalar(0, 160, 0), finer_label, 2});
    const cv::Mat plot = plotProfiles(curves);
    if (!cv::imwrite(output, plot)) throw UsageError("cannot write --output " + output);
    std::printf("# plot written to %s\n", output.c_str());
  }
  return 0;
}

}  // namespace occupancy_fusion
