// The shipped RTAB-Map stereo pairs (test/data/rtabmap_stereo, see its README): images and the
// calibration of their camera_info-style YAML files, for the unit tests and the rostest.
#pragma once

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "occupancy_fusion/sensors/stereo_rectification.h"

namespace occupancy_fusion {
namespace test {

// "left" or "right" image of frame "50" or "60" (as stored: left colour, right grey).
// `folder`: test/data/rtabmap_stereo.
inline cv::Mat rtabmapImage(const std::string& folder, const std::string& side,
                            const std::string& frame) {
  const std::string path = folder + "/" + side + "/" + frame + ".jpg";
  cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) throw std::runtime_error("cannot read " + path);
  return image;
}

// The calibration of stereo_<side>.yaml (OpenCV FileStorage, camera_calibration_parsers' keys).
inline CameraCalibration rtabmapCalibration(const std::string& folder, const std::string& side) {
  const std::string path = folder + "/stereo_" + side + ".yaml";
  cv::FileStorage file(path, cv::FileStorage::READ);
  if (!file.isOpened()) throw std::runtime_error("cannot read " + path);
  CameraCalibration calibration;
  calibration.width = static_cast<int>(file["image_width"]);
  calibration.height = static_cast<int>(file["image_height"]);
  calibration.distortion_model = static_cast<std::string>(file["distortion_model"]);
  file["distortion_coefficients"]["data"] >> calibration.D;
  const auto read = [&](const char* key, std::size_t count, double* out) {
    std::vector<double> values;
    file[key]["data"] >> values;
    if (values.size() != count) throw std::runtime_error(path + ": " + key + " size");
    std::copy(values.begin(), values.end(), out);
  };
  read("camera_matrix", 9, calibration.K.data());
  read("rectification_matrix", 9, calibration.R.data());
  read("projection_matrix", 12, calibration.P.data());
  calibration.validate();
  return calibration;
}

}  // namespace test
}  // namespace occupancy_fusion
