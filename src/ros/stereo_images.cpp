#include "occupancy_fusion/ros/stereo_images.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include <sensor_msgs/image_encodings.h>
#include <opencv2/imgproc.hpp>

#include "occupancy_fusion/ros/image_bytes.h"

namespace occupancy_fusion {

cv::Mat greyImageOf(const sensor_msgs::Image& image, const char* what) {
  namespace enc = sensor_msgs::image_encodings;
  const std::string& encoding = image.encoding;
  const bool colour = encoding == enc::BGR8 || encoding == enc::RGB8;
  if (!colour && encoding != enc::MONO8) {
    throw std::invalid_argument(std::string(what) + " has encoding '" + encoding +
                                "' (mono8, bgr8 and rgb8 are matched)");
  }
  if (isEmptyImage(image)) throw std::invalid_argument(std::string(what) + " is empty");
  if (!rowsFitData(image, colour ? 3 : 1)) {
    throw std::invalid_argument(std::string(what) + " of " + std::to_string(image.width) + "x" +
                                std::to_string(image.height) + " px has step " +
                                std::to_string(image.step) + " and " +
                                std::to_string(image.data.size()) + " bytes: they do not fit");
  }
  // A view of the message's bytes (8-bit data has no byte order); the conversion copies.
  const cv::Mat view(static_cast<int>(image.height), static_cast<int>(image.width),
                     colour ? CV_8UC3 : CV_8UC1, const_cast<std::uint8_t*>(image.data.data()),
                     image.step);
  cv::Mat grey;
  if (encoding == enc::MONO8) {
    view.copyTo(grey);
  } else {
    cv::cvtColor(view, grey, encoding == enc::BGR8 ? cv::COLOR_BGR2GRAY : cv::COLOR_RGB2GRAY);
  }
  return grey;
}

CameraCalibration calibrationOf(const sensor_msgs::CameraInfo& info, const char* what) {
  if (info.binning_x > 1 || info.binning_y > 1) {
    throw std::invalid_argument(std::string(what) + " has binning, which is not supported");
  }
  if (info.roi.width != 0 && (info.roi.width != info.width || info.roi.height != info.height)) {
    throw std::invalid_argument(std::string(what) +
                                " has a region of interest, which is not supported");
  }
  CameraCalibration calibration;
  calibration.width = static_cast<int>(info.width);
  calibration.height = static_cast<int>(info.height);
  calibration.distortion_model = info.distortion_model;
  calibration.D = info.D;
  std::copy(info.K.begin(), info.K.end(), calibration.K.begin());
  std::copy(info.R.begin(), info.R.end(), calibration.R.begin());
  std::copy(info.P.begin(), info.P.end(), calibration.P.begin());
  try {
    calibration.validate();
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(std::string(what) + ": " + error.what());
  }
  return calibration;
}

stereo_msgs::DisparityImage disparityImageOf(const cv::Mat& disparity,
                                             const DisparityImageFields& fields,
                                             const std_msgs::Header& left_header) {
  CV_Assert(disparity.type() == CV_32FC1);
  stereo_msgs::DisparityImage message;
  message.header = left_header;
  message.image.header = left_header;
  message.image.width = static_cast<std::uint32_t>(disparity.cols);
  message.image.height = static_cast<std::uint32_t>(disparity.rows);
  message.image.encoding = sensor_msgs::image_encodings::TYPE_32FC1;
  message.image.is_bigendian = hostByteOrderFlag();
  message.image.step = message.image.width * sizeof(float);
  message.image.data.resize(static_cast<std::size_t>(message.image.step) * message.image.height);
  for (int v = 0; v < disparity.rows; ++v) {
    std::memcpy(&message.image.data[static_cast<std::size_t>(v) * message.image.step],
                disparity.ptr<float>(v), message.image.step);
  }
  message.f = static_cast<float>(fields.f);
  message.T = static_cast<float>(fields.T);
  message.min_disparity = fields.min_disparity;
  message.max_disparity = fields.max_disparity;
  message.delta_d = fields.delta_d;
  message.valid_window.x_offset = static_cast<std::uint32_t>(fields.valid_window.x_offset);
  message.valid_window.y_offset = static_cast<std::uint32_t>(fields.valid_window.y_offset);
  message.valid_window.width = static_cast<std::uint32_t>(fields.valid_window.width);
  message.valid_window.height = static_cast<std::uint32_t>(fields.valid_window.height);
  return message;
}

}  // namespace occupancy_fusion
