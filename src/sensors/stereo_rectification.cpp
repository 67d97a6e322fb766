#include "occupancy_fusion/sensors/stereo_rectification.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace occupancy_fusion {

void CameraCalibration::validate() const {
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("camera calibration without an image size (" +
                                std::to_string(width) + "x" + std::to_string(height) + ")");
  }
  if (!(K[0] > 0.0 && K[4] > 0.0 && std::isfinite(K[0]) && std::isfinite(K[4]))) {
    throw std::invalid_argument("camera calibration K has no positive focal length");
  }
  if (!(P[0] > 0.0 && P[5] > 0.0 && std::isfinite(P[0]) && std::isfinite(P[5]))) {
    throw std::invalid_argument(
        "camera calibration P has no positive focal length (not a calibrated camera)");
  }
  if (D.empty()) return;
  if (distortion_model == "plumb_bob") {
    if (D.size() != 5 && D.size() != 4) {
      throw std::invalid_argument("plumb_bob distortion takes 5 coefficients, not " +
                                  std::to_string(D.size()));
    }
  } else if (distortion_model == "rational_polynomial") {
    if (D.size() != 8) {
      throw std::invalid_argument("rational_polynomial distortion takes 8 coefficients, not " +
                                  std::to_string(D.size()));
    }
  } else {
    throw std::invalid_argument("distortion model '" + distortion_model +
                                "' is not supported (plumb_bob, rational_polynomial)");
  }
}

bool CameraCalibration::operator==(const CameraCalibration& other) const {
  return width == other.width && height == other.height &&
         distortion_model == other.distortion_model && D == other.D && K == other.K &&
         R == other.R && P == other.P;
}

StereoGeometry stereoGeometryOf(const CameraCalibration& left, const CameraCalibration& right) {
  left.validate();
  right.validate();
  if (left.width != right.width || left.height != right.height) {
    throw std::invalid_argument("left camera_info is " + std::to_string(left.width) + "x" +
                                std::to_string(left.height) + " px, right " +
                                std::to_string(right.width) + "x" + std::to_string(right.height));
  }
  StereoGeometry geometry;
  geometry.focal_px = right.P[0];
  // P_right[0][3] = -fx' * B (image_geometry's Tx): the right camera sits at +B along x.
  geometry.baseline_m = -right.P[3] / right.P[0];
  if (!(geometry.baseline_m > 0.0) || !std::isfinite(geometry.baseline_m)) {
    throw std::invalid_argument(
        "right camera_info's P[3] = " + std::to_string(right.P[3]) + " gives baseline " +
        std::to_string(geometry.baseline_m) +
        " m: it must be -fx * baseline < 0 (left and right swapped, or not a stereo calibration)");
  }
  geometry.principal_point_offset = left.P[2] - right.P[2];
  return geometry;
}

void CachedRectification::rectify(const CameraCalibration& calibration, const cv::Mat& raw,
                                  cv::Mat* rectified) {
  if (raw.cols != calibration.width || raw.rows != calibration.height) {
    throw std::invalid_argument("image of " + std::to_string(raw.cols) + "x" +
                                std::to_string(raw.rows) + " px, its camera_info says " +
                                std::to_string(calibration.width) + "x" +
                                std::to_string(calibration.height));
  }
  if (!has_maps_ || calibration != cached_) {
    calibration.validate();
    const cv::Matx33d K(calibration.K.data());
    // An all-zero R is a camera_info that leaves rectification out (a monocular driver's): no
    // rotation.
    bool r_unset = true;
    for (double r : calibration.R) r_unset = r_unset && r == 0.0;
    const cv::Matx33d R = r_unset ? cv::Matx33d::eye() : cv::Matx33d(calibration.R.data());
    const cv::Matx34d P(calibration.P.data());
    const cv::Mat D(calibration.D, true);
    // Only P's left 3x3 block is the new camera matrix; its last column is the stereo offset.
    cv::initUndistortRectifyMap(K, D, R, P.get_minor<3, 3>(0, 0),
                                cv::Size(calibration.width, calibration.height), CV_16SC2, map_xy_,
                                map_interpolation_);
    cached_ = calibration;
    has_maps_ = true;
    ++maps_built_;
  }
  cv::remap(raw, *rectified, map_xy_, map_interpolation_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
}

}  // namespace occupancy_fusion
