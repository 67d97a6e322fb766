// The core stereo matcher: disparity of a known shift, stereo_image_proc's DisparityImage fields,
// the parameter reader's limits, and rectification from raw images (the real RTAB-Map pair
// distorted with a known K, D and R, then rectified back).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "occupancy_fusion/params/stereo_matcher_config_reader.h"
#include "occupancy_fusion/sensors/stereo_matcher.h"
#include "occupancy_fusion/sensors/stereo_rectification.h"

#include "../../common/rtabmap_pair.h"

namespace occupancy_fusion {
namespace {

const std::string kData = std::string(OCCUPANCY_FUSION_SOURCE_DIR) + "/test/data/rtabmap_stereo";

// A textured grey image (blurred noise: every window has texture) and its right view at a
// constant disparity: right(x) = left(x + d).
void shiftedPair(int disparity, cv::Mat* left, cv::Mat* right) {
  cv::Mat noise(240, 320 + disparity, CV_8UC1);
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(noise, noise, cv::Size(3, 3), 0.8);
  *left = noise(cv::Rect(0, 0, 320, 240)).clone();
  *right = noise(cv::Rect(disparity, 0, 320, 240)).clone();
}

// Fraction of the valid window's pixels whose disparity is within tolerance of `expected`.
double fractionNear(const cv::Mat& disparity, const DisparityWindow& window, float expected,
                    float tolerance) {
  std::size_t near = 0, total = 0;
  for (int v = window.y_offset; v < window.y_offset + window.height; ++v) {
    for (int u = window.x_offset; u < window.x_offset + window.width; ++u) {
      ++total;
      near += std::abs(disparity.at<float>(v, u) - expected) <= tolerance ? 1 : 0;
    }
  }
  return static_cast<double>(near) / total;
}

TEST(StereoMatcher, SemiGlobalFindsAKnownShiftToASixteenthOfAPixel) {
  cv::Mat left, right;
  shiftedPair(9, &left, &right);
  StereoMatcher matcher(StereoMatcherConfig{});
  cv::Mat disparity;
  matcher.match(left, right, 0.0, &disparity);
  ASSERT_EQ(disparity.type(), CV_32FC1);
  ASSERT_EQ(disparity.size(), left.size());
  const DisparityImageFields fields =
      disparityImageFields(matcher.config(), {500.0, 0.1, 0.0}, left.cols, left.rows);
  EXPECT_GT(fractionNear(disparity, fields.valid_window, 9.0f, 1.0f / 16), 0.95);
  // The principal points' offset is taken off every value (stereo_image_proc's d - (cx_l - cx_r)).
  matcher.match(left, right, 2.5, &disparity);
  EXPECT_GT(fractionNear(disparity, fields.valid_window, 6.5f, 1.0f / 16), 0.95);
}

TEST(StereoMatcher, BlockMatchingFindsAKnownShift) {
  cv::Mat left, right;
  shiftedPair(12, &left, &right);
  StereoMatcherConfig config;
  config.algorithm = StereoAlgorithm::kBlockMatching;
  config.correlation_window_size = 15;
  StereoMatcher matcher(config);
  cv::Mat disparity;
  matcher.match(left, right, 0.0, &disparity);
  const DisparityImageFields fields =
      disparityImageFields(config, {500.0, 0.1, 0.0}, left.cols, left.rows);
  EXPECT_GT(fractionNear(disparity, fields.valid_window, 12.0f, 1.0f / 16), 0.95);
}

TEST(StereoMatcher, UnmatchedPixelsLieBelowThePublishedRange) {
  // A flat image has nothing to match: every pixel is unmatched.
  const cv::Mat flat(120, 200, CV_8UC1, cv::Scalar(128));
  StereoMatcherConfig config;
  config.min_disparity = 4;
  config.disparity_range = 32;
  StereoMatcher matcher(config);
  cv::Mat disparity;
  matcher.match(flat, flat, 1.5, &disparity);
  const DisparityImageFields fields = disparityImageFields(config, {500.0, 0.1, 1.5}, 200, 120);
  EXPECT_FLOAT_EQ(fields.min_disparity, 2.5f);  // 4 - 1.5
  EXPECT_FLOAT_EQ(matcher.invalidValue(1.5), 1.5f);
  double smallest = 0.0, largest = 0.0;
  cv::minMaxLoc(disparity, &smallest, &largest);
  EXPECT_FLOAT_EQ(static_cast<float>(largest), 1.5f);
  EXPECT_LT(largest, fields.min_disparity);
}

TEST(StereoMatcher, RejectsImagesThatDoNotPair) {
  StereoMatcher matcher(StereoMatcherConfig{});
  cv::Mat disparity;
  const cv::Mat grey(100, 200, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(matcher.match(grey, cv::Mat(100, 201, CV_8UC1), 0.0, &disparity),
               std::invalid_argument);
  EXPECT_THROW(matcher.match(grey, cv::Mat(100, 200, CV_8UC3), 0.0, &disparity),
               std::invalid_argument);
  EXPECT_THROW(
      matcher.match(cv::Mat(100, 200, CV_16UC1), cv::Mat(100, 200, CV_16UC1), 0.0, &disparity),
      std::invalid_argument);
}

TEST(DisparityImageFields, FollowStereoImageProc) {
  StereoMatcherConfig config;
  config.correlation_window_size = 15;
  config.disparity_range = 64;
  const StereoGeometry geometry{487.6, 0.12, 0.0};
  DisparityImageFields fields = disparityImageFields(config, geometry, 640, 480);
  EXPECT_DOUBLE_EQ(fields.f, 487.6);
  EXPECT_DOUBLE_EQ(fields.T, 0.12);
  EXPECT_FLOAT_EQ(fields.min_disparity, 0.0f);
  EXPECT_FLOAT_EQ(fields.max_disparity, 63.0f);
  EXPECT_FLOAT_EQ(fields.delta_d, 0.0625f);
  // border 7: x from 64 + 0 + 7 - 1 = 70 to 639 - 7 = 632, y from 7 to 472.
  EXPECT_EQ(fields.valid_window.x_offset, 70);
  EXPECT_EQ(fields.valid_window.y_offset, 7);
  EXPECT_EQ(fields.valid_window.width, 562);
  EXPECT_EQ(fields.valid_window.height, 465);

  // Verged cameras: a negative min_disparity moves the right margin out to -min_disparity.
  config.correlation_window_size = 5;
  config.min_disparity = -16;
  config.disparity_range = 32;
  fields = disparityImageFields(config, {487.6, 0.12, 3.0}, 640, 480);
  EXPECT_FLOAT_EQ(fields.min_disparity, -19.0f);
  EXPECT_FLOAT_EQ(fields.max_disparity, 12.0f);
  EXPECT_EQ(fields.valid_window.x_offset, 17);  // 32 - 16 + 2 - 1
  EXPECT_EQ(fields.valid_window.width, 606);    // 639 - 16 - 17
  EXPECT_EQ(fields.valid_window.height, 475);   // 477 - 2

  // Too narrow for the searched range.
  config.min_disparity = 0;
  config.disparity_range = 256;
  EXPECT_THROW(disparityImageFields(config, geometry, 200, 100), std::invalid_argument);
}

TEST(StereoGeometry, FromTheRtabmapCalibration) {
  const CameraCalibration left = test::rtabmapCalibration(kData, "left");
  CameraCalibration right = test::rtabmapCalibration(kData, "right");
  const StereoGeometry geometry = stereoGeometryOf(left, right);
  EXPECT_NEAR(geometry.focal_px, 487.6087, 1e-4);
  EXPECT_NEAR(geometry.baseline_m, 58.3627 / 487.6087, 1e-6);
  EXPECT_DOUBLE_EQ(geometry.principal_point_offset, 0.0);

  // Left and right swapped: the baseline comes out negative.
  EXPECT_THROW(stereoGeometryOf(right, left), std::invalid_argument);
  CameraCalibration swapped = right;
  swapped.P[3] = 58.3627;
  try {
    stereoGeometryOf(left, swapped);
    FAIL() << "a negative baseline was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("baseline"), std::string::npos) << error.what();
  }
  right.width = 320;
  EXPECT_THROW(stereoGeometryOf(left, right), std::invalid_argument);
}

TEST(StereoMatcherConfig, ValidateNamesTheField) {
  StereoMatcherConfig config;
  config.correlation_window_size = 6;
  EXPECT_THROW(config.validate(), std::invalid_argument);
  config = StereoMatcherConfig{};
  config.disparity_range = 40;
  try {
    config.validate();
    FAIL() << "disparity_range 40 was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("disparity_range"), std::string::npos);
  }
  config = StereoMatcherConfig{};
  config.p2 = config.p1;
  EXPECT_THROW(config.validate(), std::invalid_argument);
}

// Parameters from a map, as the ROS parameter server or a YAML file would give them.
class MapSource : public ParameterSource {
 public:
  std::map<std::string, double> numbers;
  std::map<std::string, std::string> strings;
  bool get(const std::string& key, double* value) const override {
    const auto it = numbers.find(key);
    if (it == numbers.end()) return false;
    *value = it->second;
    return true;
  }
  bool get(const std::string& key, int* value) const override {
    const auto it = numbers.find(key);
    if (it == numbers.end()) return false;
    *value = static_cast<int>(it->second);
    return true;
  }
  bool get(const std::string&, bool*) const override { return false; }
  bool get(const std::string& key, std::string* value) const override {
    const auto it = strings.find(key);
    if (it == strings.end()) return false;
    *value = it->second;
    return true;
  }
  bool get(const std::string&, std::vector<std::string>*) const override { return false; }
  bool get(const std::string&, std::vector<double>*) const override { return false; }
};

TEST(StereoMatcherConfigReader, ReadsStereoImageProcNamesAndLimits) {
  MapSource source;
  source.numbers = {{"stereo_algorithm", 0},
                    {"correlation_window_size", 21},
                    {"disparity_range", 96},
                    {"uniqueness_ratio", 15},
                    {"P1", 300},
                    {"P2", 1200},
                    {"disp12MaxDiff", 2}};
  source.strings = {{"sgbm_mode", "hh"}};
  StereoMatcherConfig config = readStereoMatcherConfig(source);
  EXPECT_EQ(config.algorithm, StereoAlgorithm::kBlockMatching);
  EXPECT_EQ(config.sgbm_mode, SgbmMode::kFullDp);
  EXPECT_EQ(config.correlation_window_size, 21);
  EXPECT_EQ(config.disparity_range, 96);
  EXPECT_EQ(config.uniqueness_ratio, 15);
  EXPECT_EQ(config.p1, 300);
  EXPECT_EQ(config.p2, 1200);
  EXPECT_EQ(config.disp12_max_diff, 2);

  // stereo_image_proc's limit (32..256) and OpenCV's (a multiple of 16), each named.
  for (double range : {512.0, 100.0}) {
    source.numbers["disparity_range"] = range;
    try {
      readStereoMatcherConfig(source);
      FAIL() << "disparity_range " << range << " was accepted";
    } catch (const std::invalid_argument& error) {
      EXPECT_EQ(std::string(error.what()).rfind("disparity_range", 0), 0u) << error.what();
    }
  }
  source.numbers["disparity_range"] = 64;
  source.numbers["uniqueness_ratio"] = 12.5;
  EXPECT_THROW(readStereoMatcherConfig(source), std::invalid_argument);
  source.numbers["uniqueness_ratio"] = 10;
  source.strings["sgbm_mode"] = "fast";
  EXPECT_THROW(readStereoMatcherConfig(source), std::invalid_argument);
}

// Raw images of a calibrated camera made from a rectified one: each raw pixel shows what the
// rectified image holds where that pixel's ray lands (cv::undistortPoints with K, D, R, P, to
// convergence), so rectifying them back must give the rectified image.
cv::Mat distort(const cv::Mat& rectified, const CameraCalibration& calibration) {
  std::vector<cv::Point2f> raw_pixels;
  for (int v = 0; v < rectified.rows; ++v) {
    for (int u = 0; u < rectified.cols; ++u) raw_pixels.emplace_back(u, v);
  }
  std::vector<cv::Point2f> rectified_pixels;
  cv::undistortPoints(raw_pixels, rectified_pixels, cv::Matx33d(calibration.K.data()),
                      calibration.D, cv::Matx33d(calibration.R.data()),
                      cv::Matx34d(calibration.P.data()).get_minor<3, 3>(0, 0),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-6));
  cv::Mat map_x(rectified.size(), CV_32FC1), map_y(rectified.size(), CV_32FC1);
  for (int v = 0; v < rectified.rows; ++v) {
    for (int u = 0; u < rectified.cols; ++u) {
      const cv::Point2f& p = rectified_pixels[static_cast<std::size_t>(v) * rectified.cols + u];
      map_x.at<float>(v, u) = p.x;
      map_y.at<float>(v, u) = p.y;
    }
  }
  cv::Mat raw;
  cv::remap(rectified, raw, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  return raw;
}

// A raw camera that differs from the rectified one: another focal length and principal point,
// barrel distortion and a rotation of about a degree (what rectification undoes).
CameraCalibration rawCalibration(const CameraCalibration& rectified, double yaw) {
  CameraCalibration raw = rectified;
  raw.K = {470.0, 0.0, 322.5, 0.0, 472.0, 245.0, 0.0, 0.0, 1.0};
  raw.D = {-0.28, 0.09, 0.0008, -0.0006, 0.0};
  cv::Matx33d rotation;
  cv::Rodrigues(cv::Vec3d(0.004, yaw, -0.003), rotation);
  for (int i = 0; i < 9; ++i) raw.R[i] = rotation.val[i];
  return raw;
}

TEST(Rectification, CoordinatesComeBackWithinATenthOfAPixel) {
  // An image whose pixels hold their own coordinates: rectifying its distorted version must put
  // every coordinate back at its pixel.
  const CameraCalibration calibration =
      rawCalibration(test::rtabmapCalibration(kData, "left"), 0.015);
  cv::Mat coordinates(calibration.height, calibration.width, CV_32FC2);
  for (int v = 0; v < coordinates.rows; ++v) {
    for (int u = 0; u < coordinates.cols; ++u)
      coordinates.at<cv::Vec2f>(v, u) = {1.0f * u, 1.0f * v};
  }
  const cv::Mat raw = distort(coordinates, calibration);
  CachedRectification rectification;
  cv::Mat rectified;
  rectification.rectify(calibration, raw, &rectified);
  // Compare where the rectified pixel's raw position lies well inside the raw image, and the
  // raw pixels around it came from inside the rectified one.
  double worst = 0.0, worst_unrectified = 0.0, sum = 0.0;
  std::size_t compared = 0;
  for (int v = 20; v < coordinates.rows - 20; ++v) {
    for (int u = 20; u < coordinates.cols - 20; ++u) {
      const cv::Vec2f back = rectified.at<cv::Vec2f>(v, u);
      const cv::Vec2f unrectified = raw.at<cv::Vec2f>(v, u);
      if (back[0] == 0.0f && back[1] == 0.0f) continue;  // outside the raw image
      const double error = std::hypot(back[0] - u, back[1] - v);
      worst = std::max(worst, error);
      if (unrectified[0] != 0.0f || unrectified[1] != 0.0f) {
        worst_unrectified =
            std::max(worst_unrectified, double{std::hypot(unrectified[0] - u, unrectified[1] - v)});
      }
      sum += error;
      ++compared;
    }
  }
  std::printf("rectified back: worst %.3f px, mean %.4f px over %zu pixels; raw: worst %.1f px\n",
              worst, sum / compared, compared, worst_unrectified);
  ASSERT_GT(compared, 0.8 * coordinates.total());
  EXPECT_LT(worst, 0.1);
  EXPECT_LT(sum / compared, 0.02);
  // The raw image is far from the rectified one: the test's distortion is real.
  EXPECT_GT(worst_unrectified, 20.0);
}

TEST(Rectification, TheRtabmapPairComesBackWithinAPixel) {
  const cv::Mat left = test::rtabmapImage(kData, "left", "50");
  const cv::Mat right = test::rtabmapImage(kData, "right", "50");
  cv::Mat left_grey;
  cv::cvtColor(left, left_grey, cv::COLOR_BGR2GRAY);
  const CameraCalibration left_raw = rawCalibration(test::rtabmapCalibration(kData, "left"), 0.015);
  const CameraCalibration right_raw =
      rawCalibration(test::rtabmapCalibration(kData, "right"), -0.012);
  const cv::Mat left_distorted = distort(left_grey, left_raw);
  const cv::Mat right_distorted = distort(right, right_raw);

  CachedRectification left_rectification, right_rectification;
  cv::Mat left_back, right_back;
  left_rectification.rectify(left_raw, left_distorted, &left_back);
  right_rectification.rectify(right_raw, right_distorted, &right_back);

  // Matched from the rectified-back pair and from the original pair, the disparities agree
  // within a pixel almost everywhere both are matched; the raw pair does not match like that.
  StereoMatcher matcher(StereoMatcherConfig{});
  cv::Mat original, recovered, unrectified;
  matcher.match(left_grey, right, 0.0, &original);
  matcher.match(left_back, right_back, 0.0, &recovered);
  matcher.match(left_distorted, right_distorted, 0.0, &unrectified);
  const DisparityImageFields fields = disparityImageFields(
      matcher.config(), stereoGeometryOf(left_raw, right_raw), left.cols, left.rows);
  const auto agreement = [&](const cv::Mat& other, std::size_t* both_matched) {
    std::size_t agree = 0;
    *both_matched = 0;
    const DisparityWindow& w = fields.valid_window;
    // 40 px in from the valid window: rectification leaves black borders where the raw image
    // ends.
    for (int v = w.y_offset + 40; v < w.y_offset + w.height - 40; ++v) {
      for (int u = w.x_offset + 40; u < w.x_offset + w.width - 40; ++u) {
        const float a = original.at<float>(v, u), b = other.at<float>(v, u);
        if (a < fields.min_disparity || b < fields.min_disparity) continue;
        ++*both_matched;
        agree += std::abs(a - b) <= 1.0f ? 1 : 0;
      }
    }
    return static_cast<double>(agree) / std::max<std::size_t>(*both_matched, 1);
  };
  std::size_t matched_recovered = 0, matched_unrectified = 0;
  const double recovered_agreement = agreement(recovered, &matched_recovered);
  const double unrectified_agreement = agreement(unrectified, &matched_unrectified);
  std::printf(
      "disparity within 1 px of the original pair's: %.3f of %zu pixels rectified back, "
      "%.3f of %zu raw\n",
      recovered_agreement, matched_recovered, unrectified_agreement, matched_unrectified);
  EXPECT_GT(matched_recovered, 50000u);
  EXPECT_GT(recovered_agreement, 0.95);
  EXPECT_LT(unrectified_agreement, 0.5);

  // Intensities: the rectified-back image differs from the original by the interpolation only.
  cv::Mat difference;
  cv::absdiff(left_back(cv::Rect(60, 60, 520, 360)), left_grey(cv::Rect(60, 60, 520, 360)),
              difference);
  std::printf("mean grey difference after rectification %.2f\n", cv::mean(difference)[0]);
  EXPECT_LT(cv::mean(difference)[0], 2.0);
}

TEST(Rectification, MapsAreBuiltOncePerCalibration) {
  CameraCalibration calibration = rawCalibration(test::rtabmapCalibration(kData, "left"), 0.01);
  const cv::Mat raw(calibration.height, calibration.width, CV_8UC1, cv::Scalar(100));
  CachedRectification rectification;
  cv::Mat rectified;
  rectification.rectify(calibration, raw, &rectified);
  rectification.rectify(calibration, raw, &rectified);
  EXPECT_EQ(rectification.mapsBuilt(), 1u);
  calibration.D[0] = -0.2;
  rectification.rectify(calibration, raw, &rectified);
  EXPECT_EQ(rectification.mapsBuilt(), 2u);
  // An image of another size than its calibration is refused.
  EXPECT_THROW(rectification.rectify(calibration, cv::Mat(240, 320, CV_8UC1), &rectified),
               std::invalid_argument);
  calibration.distortion_model = "equidistant";
  calibration.D.resize(4);
  EXPECT_THROW(rectification.rectify(calibration, raw, &rectified), std::invalid_argument);
}

}  // namespace
}  // namespace occupancy_fusion
