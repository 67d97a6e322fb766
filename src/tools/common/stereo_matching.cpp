#include "occupancy_fusion/tools/stereo_matching.h"

#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

namespace occupancy_fusion {

std::vector<float> sgbmDisparity(const std::string& left_path, const std::string& right_path,
                                 const SgbmSettings& settings, float offset_px, int* width,
                                 int* height) {
  const cv::Mat left = cv::imread(left_path, cv::IMREAD_COLOR);
  const cv::Mat right = cv::imread(right_path, cv::IMREAD_COLOR);
  if (left.empty() || right.empty()) {
    throw std::runtime_error("cannot read " + left_path + " / " + right_path);
  }
  const int block = settings.block_size;
  const cv::Ptr<cv::StereoSGBM> matcher = cv::StereoSGBM::create(
      0, settings.num_disparities, block, 8 * 3 * block * block, 32 * 3 * block * block, 1, 0, 10,
      100, 2, cv::StereoSGBM::MODE_SGBM_3WAY);
  cv::Mat fixed_point;
  matcher->compute(left, right, fixed_point);  // CV_16S, disparity * 16
  *width = fixed_point.cols;
  *height = fixed_point.rows;
  std::vector<float> disparity(fixed_point.total());
  for (int v = 0; v < fixed_point.rows; ++v) {
    for (int u = 0; u < fixed_point.cols; ++u) {
      const short raw = fixed_point.at<short>(v, u);
      disparity[static_cast<std::size_t>(v) * fixed_point.cols + u] =
          raw >= 0 ? raw / 16.0f + offset_px : std::numeric_limits<float>::quiet_NaN();
    }
  }
  return disparity;
}

}  // namespace occupancy_fusion
