// The StereoMatcher nodelet's message conversions: camera images (mono8, bgr8, rgb8) to the grey
// cv::Mat the core matcher takes, sensor_msgs/CameraInfo to the core's CameraCalibration, and the
// core's disparity with its fields to a stereo_msgs/DisparityImage. Each bad input throws
// std::invalid_argument with a message that says what is wrong, for the nodelet to drop it.
#pragma once

#include <opencv2/core.hpp>

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <stereo_msgs/DisparityImage.h>

#include "occupancy_fusion/sensors/stereo_matcher.h"
#include "occupancy_fusion/sensors/stereo_rectification.h"

namespace occupancy_fusion {

// The image as 8-bit grey (CV_8UC1), converted from mono8, bgr8 or rgb8 (stereo_image_proc
// matches grey images too); `what` ("left image") names it in errors. Throws for any other
// encoding, an empty image, or data that does not hold height rows of step bytes.
cv::Mat greyImageOf(const sensor_msgs::Image& image, const char* what);

// K, D, R, P, size and distortion model of a camera_info. Throws for binning or a region of
// interest (the images would not be the calibrated size) and for an invalid calibration.
CameraCalibration calibrationOf(const sensor_msgs::CameraInfo& info, const char* what);

// The DisparityImage of a matched pair: header (both the message's and its image's) from the left
// image, a 32FC1 image of the disparity (CV_32FC1) in host byte order, and the fields.
stereo_msgs::DisparityImage disparityImageOf(const cv::Mat& disparity,
                                             const DisparityImageFields& fields,
                                             const std_msgs::Header& left_header);

}  // namespace occupancy_fusion
