#include "occupancy_fusion/sensors/stereo_matcher.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace occupancy_fusion {
namespace {

void requireRange(int value, int low, int high, const char* field) {
  if (value < low || value > high) {
    throw std::invalid_argument(std::string("StereoMatcherConfig.") + field + " must be in [" +
                                std::to_string(low) + ", " + std::to_string(high) + "], not " +
                                std::to_string(value));
  }
}

void requireOdd(int value, const char* field) {
  if (value % 2 == 0) {
    throw std::invalid_argument(std::string("StereoMatcherConfig.") + field + " must be odd, not " +
                                std::to_string(value));
  }
}

}  // namespace

std::string toString(StereoAlgorithm algorithm) {
  return algorithm == StereoAlgorithm::kBlockMatching ? "block matching" : "semi-global";
}

std::string toString(SgbmMode mode) {
  switch (mode) {
    case SgbmMode::kFiveWay:
      return "sgbm";
    case SgbmMode::kThreeWay:
      return "3way";
    case SgbmMode::kFullDp:
      return "hh";
  }
  return "?";
}

SgbmMode sgbmModeFromString(const std::string& name) {
  if (name == "sgbm") return SgbmMode::kFiveWay;
  if (name == "3way") return SgbmMode::kThreeWay;
  if (name == "hh") return SgbmMode::kFullDp;
  throw std::invalid_argument("unknown SGBM mode '" + name + "' (sgbm, 3way or hh)");
}

void StereoMatcherConfig::validate() const {
  // OpenCV's own limits (StereoBM rejects windows below 5 and above 255, and needs the range in
  // steps of 16; both need a positive range). Wider limits for the user's parameters are checked
  // by the parameter reader.
  if (algorithm == StereoAlgorithm::kBlockMatching) {
    requireRange(correlation_window_size, 5, 255, "correlation_window_size");
    requireRange(prefilter_size, 5, 255, "prefilter_size");
    requireOdd(prefilter_size, "prefilter_size");
  } else {
    requireRange(correlation_window_size, 1, 255, "correlation_window_size");
  }
  requireOdd(correlation_window_size, "correlation_window_size");
  if (disparity_range <= 0 || disparity_range % 16 != 0) {
    throw std::invalid_argument(
        "StereoMatcherConfig.disparity_range must be a positive multiple of 16, not " +
        std::to_string(disparity_range));
  }
  requireRange(uniqueness_ratio, 0, 100, "uniqueness_ratio");
  requireRange(texture_threshold, 0, 10000, "texture_threshold");
  requireRange(speckle_size, 0, 100000, "speckle_size");
  requireRange(speckle_range, 0, 1000, "speckle_range");
  requireRange(prefilter_cap, 1, 63, "prefilter_cap");
  if (algorithm == StereoAlgorithm::kSemiGlobal) {
    requireRange(p1, 0, 1 << 20, "p1");
    // OpenCV's requirement: P2 > P1, else large disparity steps would be cheaper than small ones.
    if (p2 <= p1) {
      throw std::invalid_argument("StereoMatcherConfig.p2 must be greater than p1 (" +
                                  std::to_string(p2) + " <= " + std::to_string(p1) + ")");
    }
  }
}

DisparityImageFields disparityImageFields(const StereoMatcherConfig& config,
                                          const StereoGeometry& geometry, int width, int height) {
  DisparityImageFields fields;
  fields.f = geometry.focal_px;
  fields.T = geometry.baseline_m;
  const double offset = geometry.principal_point_offset;
  fields.min_disparity = static_cast<float>(config.min_disparity - offset);
  fields.max_disparity =
      static_cast<float>(config.min_disparity + config.disparity_range - 1 - offset);
  fields.delta_d = 1.0f / 16.0f;
  // The matcher's window needs `border` pixels on each side; a left pixel at column x is only
  // searched down to x - (min_disparity + disparity_range - 1), so the leftmost columns cannot
  // be matched over the full range; on the right, a positive min_disparity (or a negative one
  // wider than the border) shifts the match out of the right image.
  const int border = config.correlation_window_size / 2;
  // Clamped at 0: a negative min_disparity wider than the range would give a negative offset,
  // which stereo_image_proc writes into the unsigned field as it is.
  const int left = std::max(0, config.disparity_range + config.min_disparity + border - 1);
  const int right_margin = config.min_disparity >= 0 ? border + config.min_disparity
                                                     : std::max(border, -config.min_disparity);
  const int right = width - 1 - right_margin;
  const int top = border;
  const int bottom = height - 1 - border;
  if (right - left <= 0 || bottom - top <= 0) {
    throw std::invalid_argument("images of " + std::to_string(width) + "x" +
                                std::to_string(height) +
                                " px leave no pixel to match with correlation_window_size " +
                                std::to_string(config.correlation_window_size) +
                                ", min_disparity " + std::to_string(config.min_disparity) +
                                " and disparity_range " + std::to_string(config.disparity_range));
  }
  fields.valid_window = {left, top, right - left, bottom - top};
  return fields;
}

StereoMatcher::StereoMatcher(const StereoMatcherConfig& config) : config_(config) {
  config_.validate();
  if (config_.algorithm == StereoAlgorithm::kBlockMatching) {
    cv::Ptr<cv::StereoBM> bm =
        cv::StereoBM::create(config_.disparity_range, config_.correlation_window_size);
    bm->setMinDisparity(config_.min_disparity);
    bm->setPreFilterSize(config_.prefilter_size);
    bm->setPreFilterCap(config_.prefilter_cap);
    bm->setUniquenessRatio(config_.uniqueness_ratio);
    bm->setTextureThreshold(config_.texture_threshold);
    bm->setSpeckleWindowSize(config_.speckle_size);
    bm->setSpeckleRange(config_.speckle_range);
    bm->setDisp12MaxDiff(config_.disp12_max_diff);
    matcher_ = bm;
  } else {
    int mode = cv::StereoSGBM::MODE_SGBM_3WAY;
    if (config_.sgbm_mode == SgbmMode::kFiveWay) mode = cv::StereoSGBM::MODE_SGBM;
    if (config_.sgbm_mode == SgbmMode::kFullDp) mode = cv::StereoSGBM::MODE_HH;
    matcher_ = cv::StereoSGBM::create(
        config_.min_disparity, config_.disparity_range, config_.correlation_window_size, config_.p1,
        config_.p2, config_.disp12_max_diff, config_.prefilter_cap, config_.uniqueness_ratio,
        config_.speckle_size, config_.speckle_range, mode);
  }
}

float StereoMatcher::invalidValue(double principal_point_offset) const {
  return static_cast<float>(config_.min_disparity - 1) - static_cast<float>(principal_point_offset);
}

void StereoMatcher::match(const cv::Mat& left, const cv::Mat& right, double principal_point_offset,
                          cv::Mat* disparity) {
  if (left.empty() || right.empty()) throw std::invalid_argument("empty stereo image");
  if (left.size() != right.size()) {
    throw std::invalid_argument("left image is " + std::to_string(left.cols) + "x" +
                                std::to_string(left.rows) + " px, right image " +
                                std::to_string(right.cols) + "x" + std::to_string(right.rows));
  }
  if (left.type() != right.type() || (left.type() != CV_8UC1 && left.type() != CV_8UC3)) {
    throw std::invalid_argument("stereo images must both be 8-bit mono or both 8-bit colour");
  }
  if (config_.algorithm == StereoAlgorithm::kBlockMatching && left.channels() == 3) {
    // StereoBM matches grey images only.
    cv::Mat left_grey, right_grey;
    cv::cvtColor(left, left_grey, cv::COLOR_BGR2GRAY);
    cv::cvtColor(right, right_grey, cv::COLOR_BGR2GRAY);
    matcher_->compute(left_grey, right_grey, fixed_point_);
  } else {
    matcher_->compute(left, right, fixed_point_);
  }
  disparity->create(fixed_point_.size(), CV_32FC1);
  // OpenCV marks unmatched pixels with (min_disparity - 1) * 16; every other value is a match.
  const short unmatched = static_cast<short>((config_.min_disparity - 1) * 16);
  const float offset = static_cast<float>(principal_point_offset);
  const float invalid = invalidValue(principal_point_offset);
  for (int v = 0; v < fixed_point_.rows; ++v) {
    const short* in = fixed_point_.ptr<short>(v);
    float* out = disparity->ptr<float>(v);
    for (int u = 0; u < fixed_point_.cols; ++u) {
      out[u] = in[u] <= unmatched ? invalid : in[u] / 16.0f - offset;
    }
  }
}

}  // namespace occupancy_fusion
