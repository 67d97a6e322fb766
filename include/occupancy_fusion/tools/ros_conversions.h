// Conversions between ROS messages and the core's plain types, for the tools.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <stereo_msgs/DisparityImage.h>

#include "occupancy_fusion/sensors/depth_image.h"
#include "occupancy_fusion/sensors/disparity_image.h"

#include "occupancy_fusion/ros/camera_info_message.h"  // cameraInfoMessage for the tools, too
#include "occupancy_fusion/ros/transform_message.h"    // transformMessage for the tools, too

namespace occupancy_fusion {

// x, y, z of every point with finite coordinates. Accepts FLOAT32 or FLOAT64 x/y/z fields;
// throws std::invalid_argument naming the message's frame when they are missing or of another
// type.
std::vector<Eigen::Vector3f> pointsFromCloud(const sensor_msgs::PointCloud2& cloud);

// An unorganised (height 1) cloud with FLOAT32 x, y, z fields.
sensor_msgs::PointCloud2 cloudFromPoints(const std::vector<Eigen::Vector3f>& points,
                                         const std::string& frame_id, const ros::Time& stamp);

// True for the encodings depthFromImage reads: 16UC1 / mono16 (mm) and 32FC1 (m).
bool isDepthEncoding(const std::string& encoding);

// Row-major z-depth in metres of a depth image (16UC1 or mono16 in millimetres, 32FC1 in
// metres; 0 and NaN stay "no measurement"), either byte order. Throws std::invalid_argument
// naming the encoding or the size when it cannot be read.
std::vector<float> depthFromImage(const sensor_msgs::Image& image);

// Intrinsics of a rectified image: P's fx, fy, cx, cy where P is set (the projection of the
// rectified image, what depth_image_proc uses), else K's. Throws std::invalid_argument for a
// zero focal length or for binning / a region of interest (not supported).
CameraIntrinsics intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info);

// Disparity in pixels of a stereo_msgs/DisparityImage (32FC1), NaN where the value lies outside
// [min_disparity, max_disparity] or is not finite (stereo_image_proc writes unmatched pixels
// below min_disparity). Throws std::invalid_argument for another encoding or a short buffer.
std::vector<float> disparityFromMessage(const stereo_msgs::DisparityImage& message);

// The stereo camera of a DisparityImage: f and T from it, the principal point (and fy, scaled
// to f) from the left camera's info.
StereoCamera stereoCameraFrom(const stereo_msgs::DisparityImage& message,
                              const sensor_msgs::CameraInfo& left_info);

// The same without camera_info: principal point at the image centre ((width - 1) / 2,
// (height - 1) / 2), fy = f.
StereoCamera stereoCameraAtImageCentre(const stereo_msgs::DisparityImage& message);

// Messages for simulated recordings (cameraInfoMessage: ros/camera_info_message.h).
// A 16UC1 image in millimetres (0 = no measurement, depths rounded to the nearest mm) or a
// 32FC1 image in metres (NaN = no measurement) of row-major z-depths in metres (NaN = none).
sensor_msgs::Image depthImageMessage(const std::vector<float>& depth, int width, int height,
                                     bool millimetres, const std::string& frame_id,
                                     const ros::Time& stamp);
// A DisparityImage as stereo_image_proc publishes it: invalid (NaN) pixels written as -1, below
// min_disparity.
stereo_msgs::DisparityImage disparityMessage(const std::vector<float>& disparity, int width,
                                             int height, const StereoCamera& camera,
                                             double min_disparity, double max_disparity,
                                             const std::string& frame_id, const ros::Time& stamp);

}  // namespace occupancy_fusion
