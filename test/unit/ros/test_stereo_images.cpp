// The StereoMatcher nodelet's message conversions: images of each supported encoding to the same
// grey image, rejections named, camera_info to calibration, and the DisparityImage written.
#include <cstring>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "occupancy_fusion/ros/stereo_images.h"

namespace occupancy_fusion {
namespace {

// A 3x2 colour image in `encoding` (bgr8 or rgb8) with one padding byte per row.
sensor_msgs::Image colourImage(const std::string& encoding) {
  sensor_msgs::Image image;
  image.width = 3;
  image.height = 2;
  image.encoding = encoding;
  image.step = 3 * 3 + 1;
  image.data.assign(image.step * 2, 0);
  const std::uint8_t rgb[6][3] = {{255, 0, 0},  {0, 255, 0},    {0, 0, 255},
                                  {10, 20, 30}, {200, 100, 50}, {90, 90, 90}};
  for (int i = 0; i < 6; ++i) {
    std::uint8_t* pixel = &image.data[(i / 3) * image.step + (i % 3) * 3];
    for (int c = 0; c < 3; ++c) pixel[c] = rgb[i][encoding == "rgb8" ? c : 2 - c];
  }
  return image;
}

TEST(StereoImages, ColourOfEitherOrderGivesTheSameGrey) {
  const cv::Mat from_bgr = greyImageOf(colourImage("bgr8"), "left image");
  const cv::Mat from_rgb = greyImageOf(colourImage("rgb8"), "left image");
  ASSERT_EQ(from_bgr.type(), CV_8UC1);
  ASSERT_EQ(from_bgr.cols, 3);
  ASSERT_EQ(from_bgr.rows, 2);
  EXPECT_EQ(cv::countNonZero(from_bgr != from_rgb), 0);
  // ITU-R BT.601 weights (OpenCV's): pure red 0.299 * 255 = 76, green 150, blue 29.
  EXPECT_EQ(from_bgr.at<std::uint8_t>(0, 0), 76);
  EXPECT_EQ(from_bgr.at<std::uint8_t>(0, 1), 150);
  EXPECT_EQ(from_bgr.at<std::uint8_t>(0, 2), 29);
  EXPECT_EQ(from_bgr.at<std::uint8_t>(1, 2), 90);
}

TEST(StereoImages, MonoRowsAreReadThroughTheirStep) {
  sensor_msgs::Image image;
  image.width = 2;
  image.height = 2;
  image.encoding = "mono8";
  image.step = 4;
  image.data = {1, 2, 99, 99, 3, 4, 99, 99};
  const cv::Mat grey = greyImageOf(image, "right image");
  EXPECT_EQ(grey.at<std::uint8_t>(0, 1), 2);
  EXPECT_EQ(grey.at<std::uint8_t>(1, 0), 3);
  EXPECT_EQ(grey.at<std::uint8_t>(1, 1), 4);
}

TEST(StereoImages, BadImagesAreRefusedWithTheirReason) {
  sensor_msgs::Image image = colourImage("bgr8");
  image.encoding = "mono16";
  try {
    greyImageOf(image, "right image");
    FAIL() << "mono16 was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("right image has encoding 'mono16'"),
              std::string::npos)
        << error.what();
  }
  image = colourImage("rgb8");
  image.data.resize(image.data.size() - 1);  // one byte short of height * step
  EXPECT_THROW(greyImageOf(image, "left image"), std::invalid_argument);
  image = colourImage("rgb8");
  image.step = 8;  // shorter than 3 pixels of 3 bytes
  EXPECT_THROW(greyImageOf(image, "left image"), std::invalid_argument);
}

TEST(StereoImages, CameraInfoToCalibration) {
  sensor_msgs::CameraInfo info;
  info.width = 640;
  info.height = 480;
  info.distortion_model = "plumb_bob";
  info.D = {-0.2, 0.05, 0.0, 0.0, 0.0};
  info.K = {500, 0, 320, 0, 500, 240, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {480, 0, 310, -48, 0, 480, 235, 0, 0, 0, 1, 0};
  const CameraCalibration calibration = calibrationOf(info, "right camera_info");
  EXPECT_EQ(calibration.width, 640);
  EXPECT_EQ(calibration.D, info.D);
  EXPECT_DOUBLE_EQ(calibration.K[2], 320.0);
  EXPECT_DOUBLE_EQ(calibration.P[3], -48.0);
  EXPECT_DOUBLE_EQ(calibration.P[6], 235.0);
  info.binning_x = 2;
  EXPECT_THROW(calibrationOf(info, "right camera_info"), std::invalid_argument);
  info.binning_x = 0;
  info.P = {};  // an uncalibrated camera
  EXPECT_THROW(calibrationOf(info, "right camera_info"), std::invalid_argument);
}

TEST(StereoImages, DisparityImageCarriesTheFieldsAndValues) {
  cv::Mat disparity(2, 3, CV_32FC1);
  for (int i = 0; i < 6; ++i) disparity.at<float>(i / 3, i % 3) = 0.5f * i - 1.0f;
  DisparityImageFields fields;
  fields.f = 487.6;
  fields.T = 0.12;
  fields.min_disparity = 0.0f;
  fields.max_disparity = 63.0f;
  fields.valid_window = {1, 0, 2, 2};
  std_msgs::Header header;
  header.frame_id = "left_optical";
  header.stamp = ros::Time(12.5);
  const stereo_msgs::DisparityImage message = disparityImageOf(disparity, fields, header);
  EXPECT_EQ(message.header.frame_id, "left_optical");
  EXPECT_EQ(message.image.header.stamp, ros::Time(12.5));
  EXPECT_EQ(message.image.encoding, "32FC1");
  EXPECT_EQ(message.image.step, 12u);
  EXPECT_FLOAT_EQ(message.f, 487.6f);
  EXPECT_FLOAT_EQ(message.T, 0.12f);
  EXPECT_FLOAT_EQ(message.max_disparity, 63.0f);
  EXPECT_FLOAT_EQ(message.delta_d, 0.0625f);
  EXPECT_EQ(message.valid_window.x_offset, 1u);
  EXPECT_EQ(message.valid_window.width, 2u);
  float last;
  std::memcpy(&last, &message.image.data[5 * 4], 4);
  EXPECT_FLOAT_EQ(last, 1.5f);
}

}  // namespace
}  // namespace occupancy_fusion
