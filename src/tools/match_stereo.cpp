// match_stereo: the core StereoMatcher (what the StereoMatcher nodelet runs) on one stereo pair
// from files, timed: how a matcher configuration performs on a camera's images before it runs on
// the robot, and the figures of the user guide's timing line.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "occupancy_fusion/params/stereo_matcher_config_reader.h"
#include "occupancy_fusion/sensors/stereo_matcher.h"
#include "occupancy_fusion/tools/command_line.h"
#include "occupancy_fusion/tools/tool_main.h"
#include "occupancy_fusion/tools/yaml_parameter_source.h"

namespace occupancy_fusion {
namespace {

const char kUsage[] = R"(usage: match_stereo --left IMAGE --right IMAGE [options]

Matches a rectified stereo pair with the StereoMatcher nodelet's core matcher and prints the
matched fraction of the valid window and the time per frame (median of the repeats).

  --config FILE     the nodelet's parameters (config/stereo_matcher.yaml); default: its defaults
  --set KEY=VALUE   override one parameter (repeatable), e.g. --set disparity_range=32
  --scale S         resize both images by S first (0.5: half resolution), default 1
  --threads N       OpenCV's threads (cv::setNumThreads), default: OpenCV's choice
  --repeat N        frames timed after one warm-up frame, default 20
)";

int run(int argc, char** argv) {
  const CommandLine args(argc, argv,
                         {"left", "right", "config", "set", "scale", "threads", "repeat"}, {});
  YamlParameterSource parameters = args.has("config")
                                       ? YamlParameterSource::fromFile(args.value("config"))
                                       : YamlParameterSource::fromString("{}");
  for (const std::string& assignment : args.values("set")) parameters.addOverride(assignment);
  StereoMatcher matcher(readStereoMatcherConfig(parameters));
  const double scale = args.doubleValue("scale", 1.0);
  const int repeat = args.intValue("repeat", 20);
  if (!(scale > 0.0 && scale <= 4.0)) throw UsageError("--scale must be in (0, 4]");
  if (repeat < 1) throw UsageError("--repeat must be at least 1");
  if (args.has("threads")) cv::setNumThreads(args.intValue("threads", 1));

  cv::Mat left = cv::imread(args.required("left"), cv::IMREAD_GRAYSCALE);
  cv::Mat right = cv::imread(args.required("right"), cv::IMREAD_GRAYSCALE);
  if (left.empty() || right.empty()) throw UsageError("cannot read the images");
  if (scale != 1.0) {
    cv::resize(left, left, cv::Size(), scale, scale, cv::INTER_AREA);
    cv::resize(right, right, cv::Size(), scale, scale, cv::INTER_AREA);
  }
  const DisparityImageFields fields =
      disparityImageFields(matcher.config(), StereoGeometry{1.0, 1.0, 0.0}, left.cols, left.rows);
  cv::Mat disparity;
  matcher.match(left, right, 0.0, &disparity);  // warm-up: OpenCV allocates its buffers
  std::vector<double> milliseconds;
  for (int i = 0; i < repeat; ++i) {
    const auto start = std::chrono::steady_clock::now();
    matcher.match(left, right, 0.0, &disparity);
    milliseconds.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
  }
  std::sort(milliseconds.begin(), milliseconds.end());
  const DisparityWindow& w = fields.valid_window;
  const cv::Mat window = disparity(cv::Rect(w.x_offset, w.y_offset, w.width, w.height));
  const double matched =
      static_cast<double>(cv::countNonZero(window >= fields.min_disparity)) / window.total();
  std::printf(
      "%dx%d px, %s, %d threads: %.1f ms per frame (median of %d, min %.1f, max %.1f), "
      "%.1f %% of the valid window matched\n",
      left.cols, left.rows, toString(matcher.config().algorithm).c_str(), cv::getNumThreads(),
      milliseconds[milliseconds.size() / 2], repeat, milliseconds.front(), milliseconds.back(),
      100.0 * matched);
  return 0;
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  return occupancy_fusion::runTool("match_stereo", occupancy_fusion::kUsage, argc, argv,
                                   occupancy_fusion::run);
}
