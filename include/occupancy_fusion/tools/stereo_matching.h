// Disparity from a rectified image pair with OpenCV's semi-global matcher (StereoSGBM), for the
// disparity benchmark and the demo recording: real matcher noise, not ground truth. The matching
// itself is the core's StereoMatcher (sensors/stereo_matcher.h), which the StereoMatcher nodelet
// runs too; this adds reading the images and the settings these tools have always used.
#pragma once

#include <string>
#include <vector>

#include "occupancy_fusion/sensors/stereo_matcher.h"

namespace occupancy_fusion {

struct SgbmSettings {
  int num_disparities = 80;  // px, a multiple of 16
  int block_size = 5;        // px, odd
};

// The StereoMatcherConfig of these settings, with the choices explained below.
StereoMatcherConfig sgbmMatcherConfig(const SgbmSettings& settings);

// StereoSGBM on a rectified pair, as float disparity of the left image in px (its 1/16 px fixed
// point divided out) plus offset_px; unmatched pixels (below minDisparity) become NaN.
//   blockSize 5: the quarter-size Middlebury images have little texture per pixel; 3 px windows
//     leave many wrong matches, 7 px and more round off the objects' edges.
//   P1 = 8 * 3 * 5^2, P2 = 32 * 3 * 5^2: OpenCV's documented choice for 3-channel input (the
//     smoothness penalties for disparity changes of 1 px and more).
//   uniquenessRatio 10, speckleWindowSize 100, speckleRange 2, disp12MaxDiff 1: OpenCV's
//     stereo_match sample; they reject ambiguous matches, small islands and left-right
//     inconsistent pixels, but keep the matcher's errors on repetitive or untextured surfaces.
//   MODE_SGBM_3WAY: the fast 3-way variant (a real-time matcher's choice).
// Throws std::runtime_error naming the images when they cannot be read.
std::vector<float> sgbmDisparity(const std::string& left_path, const std::string& right_path,
                                 const SgbmSettings& settings, float offset_px, int* width,
                                 int* height);

}  // namespace occupancy_fusion
