// Conversions between ROS messages and the core's plain types, for the tools.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>

#include "occupancy_fusion/ros/transform_message.h"  // transformMessage for the tools, too

namespace occupancy_fusion {

// x, y, z of every point with finite coordinates. Accepts FLOAT32 or FLOAT64 x/y/z fields;
// throws std::invalid_argument naming the message's frame when they are missing or of another
// type.
std::vector<Eigen::Vector3f> pointsFromCloud(const sensor_msgs::PointCloud2& cloud);

// An unorganised (height 1) cloud with FLOAT32 x, y, z fields.
sensor_msgs::PointCloud2 cloudFromPoints(const std::vector<Eigen::Vector3f>& points,
                                         const std::string& frame_id, const ros::Time& stamp);

}  // namespace occupancy_fusion
