// Rectification of raw camera images from their calibration (what a sensor_msgs/CameraInfo holds:
// K, D, R, P), as image_proc's rectify does, with the pixel maps cached per calibration, and the
// stereo geometry that a rectified pair's two calibrations give the disparity image.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "occupancy_fusion/sensors/stereo_matcher.h"

namespace occupancy_fusion {

// One camera's calibration in the sensor_msgs/CameraInfo convention (row-major matrices).
struct CameraCalibration {
  int width = 0;
  int height = 0;
  // "plumb_bob" (k1 k2 p1 p2 k3) or "rational_polynomial" (k1 k2 p1 p2 k3 k4 k5 k6): the models
  // OpenCV's undistortion takes; an empty D means no distortion.
  std::string distortion_model = "plumb_bob";
  std::vector<double> D;
  std::array<double, 9> K{};  // raw camera's intrinsics
  std::array<double, 9> R{};  // rotation into the rectified frame
  std::array<double, 12>
      P{};  // rectified camera's projection [fx' 0 cx' Tx; 0 fy' cy' Ty; 0 0 1 0]

  // Throws std::invalid_argument naming the problem: no size, K or P without a positive focal
  // length, an unsupported distortion model, or a coefficient count that does not fit it.
  void validate() const;
  bool operator==(const CameraCalibration& other) const;
  bool operator!=(const CameraCalibration& other) const { return !(*this == other); }
};

// f, T and the principal points' offset of a rectified pair (see StereoGeometry). Throws
// std::invalid_argument when the two images differ in size, or when the baseline is zero or of
// the wrong sign (the right camera must be to the right of the left one: P_right[0][3] < 0).
StereoGeometry stereoGeometryOf(const CameraCalibration& left, const CameraCalibration& right);

// Rectifies one camera's raw images: cv::initUndistortRectifyMap(K, D, R, P) and cv::remap with
// bilinear interpolation (image_proc's default). The maps take a few milliseconds to build and
// depend only on the calibration, so they are rebuilt only when it changes.
class CachedRectification {
 public:
  // `rectified` gets raw's size and type; pixels that map outside the raw image are 0. Throws
  // std::invalid_argument when the calibration is invalid or its size is not the image's.
  void rectify(const CameraCalibration& calibration, const cv::Mat& raw, cv::Mat* rectified);
  // How often the maps were built (once per distinct calibration in a row).
  std::size_t mapsBuilt() const { return maps_built_; }

 private:
  CameraCalibration cached_;
  bool has_maps_ = false;
  cv::Mat map_xy_, map_interpolation_;  // CV_16SC2 + CV_16UC1: OpenCV's fast fixed-point maps
  std::size_t maps_built_ = 0;
};

}  // namespace occupancy_fusion
