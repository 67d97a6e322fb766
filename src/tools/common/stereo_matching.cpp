#include "occupancy_fusion/tools/stereo_matching.h"

#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

#include "occupancy_fusion/sensors/stereo_matcher.h"

namespace occupancy_fusion {

StereoMatcherConfig sgbmMatcherConfig(const SgbmSettings& settings) {
  StereoMatcherConfig config;
  config.algorithm = StereoAlgorithm::kSemiGlobal;
  config.sgbm_mode = SgbmMode::kThreeWay;
  const int block = settings.block_size;
  config.correlation_window_size = block;
  config.min_disparity = 0;
  config.disparity_range = settings.num_disparities;
  config.p1 = 8 * 3 * block * block;
  config.p2 = 32 * 3 * block * block;
  config.disp12_max_diff = 1;
  // StereoSGBM clips the prefiltered image at max(preFilterCap, 15): 15 is what this setting
  // always had (it passed 0).
  config.prefilter_cap = 15;
  config.uniqueness_ratio = 10;
  config.speckle_size = 100;
  config.speckle_range = 2;
  return config;
}

std::vector<float> sgbmDisparity(const std::string& left_path, const std::string& right_path,
                                 const SgbmSettings& settings, float offset_px, int* width,
                                 int* height) {
  const cv::Mat left = cv::imread(left_path, cv::IMREAD_COLOR);
  const cv::Mat right = cv::imread(right_path, cv::IMREAD_COLOR);
  if (left.empty() || right.empty()) {
    throw std::runtime_error("cannot read " + left_path + " / " + right_path);
  }
  StereoMatcher matcher(sgbmMatcherConfig(settings));
  cv::Mat matched;
  // The matcher subtracts cx_l - cx_r; Middlebury's doffs is cx_r - cx_l, added.
  matcher.match(left, right, -static_cast<double>(offset_px), &matched);
  const float invalid = matcher.invalidValue(-static_cast<double>(offset_px));
  *width = matched.cols;
  *height = matched.rows;
  std::vector<float> disparity(matched.total());
  for (int v = 0; v < matched.rows; ++v) {
    for (int u = 0; u < matched.cols; ++u) {
      const float d = matched.at<float>(v, u);
      disparity[static_cast<std::size_t>(v) * matched.cols + u] =
          d == invalid ? std::numeric_limits<float>::quiet_NaN() : d;
    }
  }
  return disparity;
}

}  // namespace occupancy_fusion
