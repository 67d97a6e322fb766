// stereo_msgs/DisparityImage and the left camera's sensor_msgs/CameraInfo to the core's
// DisparityImageView + StereoCamera: the one conversion of the DisparityMapper nodelet and
// offline_mapper's bag reader; and back (the simulated stereo camera).
#pragma once

#include <string>
#include <vector>

#include <sensor_msgs/CameraInfo.h>
#include <stereo_msgs/DisparityImage.h>

#include "occupancy_fusion/sensors/disparity_image.h"

namespace occupancy_fusion {

// The disparities of a 32FC1 DisparityImage as a dense row-major buffer (either byte order), with
// every pixel the message marks invalid set to NaN: non-finite values, values below
// min_disparity ("any disparity less than min_disparity is invalid"), values above
// max_disparity (outside the searched range; ignored when max_disparity <= min_disparity, i.e.
// not filled in), and pixels outside valid_window when it is set. Throws std::invalid_argument
// for any other encoding and for an image whose step or data size does not match its size.
std::vector<float> validDisparities(const stereo_msgs::DisparityImage& message);

// The stereo camera of a disparity image: fx = f and baseline = T from the message (they
// describe the disparity image itself); fy, cx, cy from the left camera_info by intrinsicsOf's
// rule (P where set, else K, divided by the binning; camera_info_message.h). Throws
// std::invalid_argument when the camera_info's image size (after binning) differs from the
// disparity image's, for what intrinsicsOf rejects, or when the result is not a valid camera (f,
// T or fy not positive).
StereoCamera stereoCameraOf(const stereo_msgs::DisparityImage& message,
                            const sensor_msgs::CameraInfo& left_info);

// Messages as stereo_image_proc publishes them: 32FC1, invalid (NaN) pixels written as -1 (below
// min_disparity = 0), max_disparity = image width (the largest disparity a matcher can find),
// valid_window the whole image, delta_d = 1/16 px (semi-global matching's sub-pixel step).
stereo_msgs::DisparityImage disparityImageMessage(const std::vector<float>& disparity, int width,
                                                  int height, const StereoCamera& camera);
// The left camera's rectified camera_info (no distortion, P = [K | 0]).
sensor_msgs::CameraInfo leftCameraInfoMessage(const StereoCamera& camera, int width, int height);

}  // namespace occupancy_fusion
