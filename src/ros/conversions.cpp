#include "occupancy_fusion/ros/conversions.h"

#include <stdexcept>

#include <sensor_msgs/point_cloud2_iterator.h>

namespace occupancy_fusion {
namespace {

template <typename Scalar>
void appendTransformed(const sensor_msgs::PointCloud2& cloud,
                       const Eigen::Isometry3d& target_T_cloud,
                       std::vector<Eigen::Vector3f>* points) {
  const Eigen::Isometry3f transform = target_T_cloud.cast<float>();
  sensor_msgs::PointCloud2ConstIterator<Scalar> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  for (; x != x.end(); ++x, ++y, ++z) {
    const Eigen::Vector3f point(static_cast<float>(*x), static_cast<float>(*y),
                                static_cast<float>(*z));
    points->push_back(transform * point);
  }
}

// The datatype shared by x, y and z, or 0 when one is missing or they differ.
std::uint8_t xyzDatatype(const sensor_msgs::PointCloud2& cloud) {
  std::uint8_t types[3] = {0, 0, 0};
  const char* names[3] = {"x", "y", "z"};
  for (const sensor_msgs::PointField& field : cloud.fields) {
    for (int axis = 0; axis < 3; ++axis) {
      if (field.name == names[axis] && field.count == 1) types[axis] = field.datatype;
    }
  }
  return types[0] == types[1] && types[1] == types[2] ? types[0] : 0;
}

}  // namespace

std::vector<Eigen::Vector3f> transformedPoints(const sensor_msgs::PointCloud2& cloud,
                                               const Eigen::Isometry3d& target_T_cloud) {
  std::vector<Eigen::Vector3f> points;
  points.reserve(static_cast<std::size_t>(cloud.width) * cloud.height);
  switch (xyzDatatype(cloud)) {
    case sensor_msgs::PointField::FLOAT32:
      appendTransformed<float>(cloud, target_T_cloud, &points);
      break;
    case sensor_msgs::PointField::FLOAT64:
      appendTransformed<double>(cloud, target_T_cloud, &points);
      break;
    default:
      throw std::invalid_argument("point cloud in frame '" + cloud.header.frame_id +
                                  "' has no FLOAT32 or FLOAT64 x, y, z fields");
  }
  return points;
}

void resizeXyzCloud(std::size_t count, sensor_msgs::PointCloud2* cloud) {
  sensor_msgs::PointCloud2Modifier modifier(*cloud);
  modifier.setPointCloud2FieldsByString(1, "xyz");
  cloud->height = 1;  // resize() keeps an unorganised cloud's row layout only when height is 1
  modifier.resize(count);
  cloud->is_dense = true;
}

void toOccupancyGridMessage(const OccupancyRaster& raster, const std::string& frame_id,
                            const ros::Time& stamp, nav_msgs::OccupancyGrid* grid) {
  grid->header.frame_id = frame_id;
  grid->header.stamp = stamp;
  grid->info.map_load_time = stamp;
  grid->info.resolution = static_cast<float>(raster.resolution);
  grid->info.width = static_cast<std::uint32_t>(raster.width);
  grid->info.height = static_cast<std::uint32_t>(raster.height);
  grid->info.origin.position.x = raster.origin_x;
  grid->info.origin.position.y = raster.origin_y;
  grid->info.origin.position.z = 0.0;
  grid->info.origin.orientation.w = 1.0;
  grid->data = raster.data;
}

}  // namespace occupancy_fusion
