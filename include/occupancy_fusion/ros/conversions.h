// Conversions between ROS messages and the core's plain types, used by the nodelets and
// offline_mapper's bag reader.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include <nav_msgs/OccupancyGrid.h>
#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>

#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/mapping/frames.h"

namespace occupancy_fusion {

// The mapping session's header of a message of sensor `kind` ("point_cloud", "depth", "disparity",
// "laser") from `source` (its topic): the message's frame_id and stamp.
FrameHeader frameHeaderOf(const std_msgs::Header& header, const std::string& kind,
                          const std::string& source);

// Every point of the cloud (x, y, z of type FLOAT32 or FLOAT64), mapped by target_T_cloud.
// Non-finite points are kept: the integrators skip and count them. Throws std::invalid_argument
// naming the cloud's frame when x, y or z is missing or of another type, or when the width x
// height points (point_step, row_step; rows may be padded) do not fit in the data.
std::vector<Eigen::Vector3f> transformedPoints(const sensor_msgs::PointCloud2& cloud,
                                               const Eigen::Isometry3d& target_T_cloud);

// An unorganised (height 1) cloud with FLOAT32 x, y, z fields, sized for `count` points; fill it
// with sensor_msgs::PointCloud2Iterator<float>.
void resizeXyzCloud(std::size_t count, sensor_msgs::PointCloud2* cloud);

// The raster as an occupancy grid (same layout: row 0 is the lowest y, -1/0/100).
void toOccupancyGridMessage(const OccupancyRaster& raster, const std::string& frame_id,
                            const ros::Time& stamp, nav_msgs::OccupancyGrid* grid);

}  // namespace occupancy_fusion
