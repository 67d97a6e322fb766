// Messages the tools write (simulated recordings), and the bag reader's fallback for a disparity
// topic without camera_info. Reading sensor messages is ros/*_messages.h's, shared with the
// nodelets.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <ros/message_traits.h>
#include <ros/time.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <stereo_msgs/DisparityImage.h>
#include <boost/make_shared.hpp>
#include <boost/shared_ptr.hpp>

#include "occupancy_fusion/sensors/depth_image.h"
#include "occupancy_fusion/sensors/disparity_image.h"

#include "occupancy_fusion/ros/camera_info_message.h"  // cameraInfoMessage for the tools, too
#include "occupancy_fusion/ros/transform_message.h"    // transformMessage for the tools, too

namespace occupancy_fusion {

// An unorganised (height 1) cloud with FLOAT32 x, y, z fields.
sensor_msgs::PointCloud2 cloudFromPoints(const std::vector<Eigen::Vector3f>& points,
                                         const std::string& frame_id, const ros::Time& stamp);

// The stereo camera of a DisparityImage recorded without camera_info (stereoCameraOf in
// ros/disparity_messages.h is the rule with one): f and T from the message, the principal point
// at the image centre ((width - 1) / 2, (height - 1) / 2), fy = f.
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

// The connection header of a latched topic as `rosbag record` keeps it (/tf_static from a
// static_transform_publisher), for rosbag::Bag::write: `rosbag play` latches a topic only when its
// connection says so, and a node started after the playback began would otherwise never get the
// static transforms (the sensors' mounts) and drop every frame.
template <class Message>
boost::shared_ptr<ros::M_string> latchedConnectionHeader(const std::string& caller_id) {
  auto header = boost::make_shared<ros::M_string>();
  (*header)["type"] = ros::message_traits::datatype<Message>();
  (*header)["md5sum"] = ros::message_traits::md5sum<Message>();
  (*header)["message_definition"] = ros::message_traits::definition<Message>();
  (*header)["callerid"] = caller_id;
  (*header)["latching"] = "1";
  return header;
}

}  // namespace occupancy_fusion
