// Disparity from a rectified stereo pair with OpenCV's matchers (StereoSGBM, StereoBM), and the
// fields of a stereo_msgs/DisparityImage as stereo_image_proc fills them. Shared by the
// StereoMatcher nodelet and the tools (demo recording, disparity benchmark), so that a disparity
// image matched online equals one matched offline from the same images.
#pragma once

#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace occupancy_fusion {

// stereo_image_proc's stereo_algorithm values (0 block matching, 1 semi-global).
enum class StereoAlgorithm { kBlockMatching = 0, kSemiGlobal = 1 };
std::string toString(StereoAlgorithm algorithm);

// StereoSGBM's modes: MODE_SGBM (5 directions), MODE_SGBM_3WAY (3 directions, faster),
// MODE_HH (8 directions, stereo_image_proc's fullDP, much more memory).
enum class SgbmMode { kFiveWay, kThreeWay, kFullDp };
std::string toString(SgbmMode mode);
SgbmMode sgbmModeFromString(const std::string& name);  // "sgbm", "3way", "hh"

// The matcher's settings under stereo_image_proc's names (Disparity.cfg), in px unless noted.
struct StereoMatcherConfig {
  StereoAlgorithm algorithm = StereoAlgorithm::kSemiGlobal;
  // Odd. 5 px: with semi-global matching the smoothness terms carry the regularisation, and
  // larger windows round off objects' edges (stereo_image_proc's 15 suits block matching).
  int correlation_window_size = 5;
  int min_disparity = 0;     // may be negative (verged cameras)
  int disparity_range = 64;  // a positive multiple of 16 (OpenCV's constraint)
  // %: the best match's cost must undercut the second best by this margin.
  int uniqueness_ratio = 10;
  int texture_threshold = 10;  // block matching only: minimum texture in the window
  int speckle_size = 100;      // connected regions of fewer pixels are dropped; 0 keeps them
  int speckle_range = 4;       // largest disparity step within one speckle region
  int prefilter_size = 9;      // block matching only: normalisation window, odd, 5..255
  int prefilter_cap = 31;      // clips the prefiltered image, 1..63
  // Semi-global only: smoothness penalties for disparity changes of 1 px and of more, OpenCV's
  // documented choice 8 * channels * window^2 and 32 * channels * window^2 for a mono 5 px window.
  int p1 = 200;
  int p2 = 800;
  // Largest left-right consistency difference in whole pixels; negative disables the check.
  int disp12_max_diff = 1;
  SgbmMode sgbm_mode = SgbmMode::kThreeWay;

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// The window of pixels where the matcher can find a disparity (stereo_msgs/DisparityImage's
// valid_window), in pixels of the left image.
struct DisparityWindow {
  int x_offset = 0;
  int y_offset = 0;
  int width = 0;
  int height = 0;
};

// What a rectified pair's camera_infos give a disparity image: f and T of the message, and the
// principal points' x offset that stereo_image_proc subtracts from every disparity so that
// d = x_l - x_r - (cx_l - cx_r) and z = f * T / d hold for verged cameras too.
struct StereoGeometry {
  double focal_px = 0.0;              // the right projection matrix's fx
  double baseline_m = 0.0;            // -P_right[0][3] / P_right[0][0]
  double principal_point_offset = 0;  // cx_l - cx_r of the projection matrices, px
};

// A DisparityImage's scalar fields for images of one size: stereo_image_proc's rules.
struct DisparityImageFields {
  double f = 0.0;
  double T = 0.0;
  // The searched range in published values (after the principal points' offset is taken off):
  // min_disparity - offset .. min_disparity + disparity_range - 1 - offset; every pixel below it
  // is invalid. stereo_image_proc does not subtract the offset from the range, so for verged
  // cameras its range disagrees with its own values; here they agree.
  float min_disparity = 0.0f;
  float max_disparity = 0.0f;
  float delta_d = 1.0f / 16.0f;  // OpenCV's matchers resolve 1/16 px
  DisparityWindow valid_window;
};

// stereo_image_proc's rules: f, T from the geometry, the range from the config, delta_d 1/16,
// and the valid window that leaves out the half window at every border and, on the left, the
// columns whose match would lie left of the right image. Throws std::invalid_argument when the
// image is too small for the window and range (the window would be empty).
DisparityImageFields disparityImageFields(const StereoMatcherConfig& config,
                                          const StereoGeometry& geometry, int width, int height);

// One OpenCV matcher, created once for its config (creating StereoSGBM allocates nothing per
// image, but reusing it keeps OpenCV's buffers between frames). Not thread-safe: OpenCV's
// matchers keep per-call buffers.
class StereoMatcher {
 public:
  explicit StereoMatcher(const StereoMatcherConfig& config);  // validates the config

  // Matches a rectified pair (same size, both CV_8UC1 or both CV_8UC3) into `disparity`
  // (CV_32FC1, the left image's size): OpenCV's fixed-point result / 16 minus
  // principal_point_offset; unmatched pixels get invalidValue(principal_point_offset), which
  // lies below the published range. Throws std::invalid_argument on mismatched or unsupported
  // images.
  void match(const cv::Mat& left, const cv::Mat& right, double principal_point_offset,
             cv::Mat* disparity);

  // min_disparity - 1 - offset: below DisparityImageFields::min_disparity, as stereo_image_proc's
  // (min_disparity - 1) is below its range.
  float invalidValue(double principal_point_offset) const;
  const StereoMatcherConfig& config() const { return config_; }

 private:
  StereoMatcherConfig config_;
  cv::Ptr<cv::StereoMatcher> matcher_;
  cv::Mat fixed_point_;  // CV_16S, kept between frames
};

}  // namespace occupancy_fusion
