#include "occupancy_fusion/tools/ros_conversions.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <sensor_msgs/point_cloud2_iterator.h>

namespace occupancy_fusion {
namespace {

const sensor_msgs::PointField* findField(const sensor_msgs::PointCloud2& cloud,
                                         const std::string& name) {
  for (const sensor_msgs::PointField& field : cloud.fields) {
    if (field.name == name) return &field;
  }
  return nullptr;
}

template <typename T>
std::vector<Eigen::Vector3f> finitePoints(const sensor_msgs::PointCloud2& cloud) {
  std::vector<Eigen::Vector3f> points;
  points.reserve(static_cast<std::size_t>(cloud.width) * cloud.height);
  sensor_msgs::PointCloud2ConstIterator<T> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  for (; x != x.end(); ++x, ++y, ++z) {
    const Eigen::Vector3f point(static_cast<float>(*x), static_cast<float>(*y),
                                static_cast<float>(*z));
    if (point.allFinite()) points.push_back(point);
  }
  return points;
}

}  // namespace

std::vector<Eigen::Vector3f> pointsFromCloud(const sensor_msgs::PointCloud2& cloud) {
  const sensor_msgs::PointField* fields[3] = {findField(cloud, "x"), findField(cloud, "y"),
                                              findField(cloud, "z")};
  const std::string where = "PointCloud2 in frame '" + cloud.header.frame_id + "'";
  for (const sensor_msgs::PointField* field : fields) {
    if (field == nullptr) throw std::invalid_argument(where + " has no x, y and z fields");
    if (field->datatype != fields[0]->datatype) {
      throw std::invalid_argument(where + ": x, y and z have different types");
    }
  }
  if (fields[0]->datatype == sensor_msgs::PointField::FLOAT32) return finitePoints<float>(cloud);
  if (fields[0]->datatype == sensor_msgs::PointField::FLOAT64) return finitePoints<double>(cloud);
  throw std::invalid_argument(where + ": x, y, z must be FLOAT32 or FLOAT64");
}

sensor_msgs::PointCloud2 cloudFromPoints(const std::vector<Eigen::Vector3f>& points,
                                         const std::string& frame_id, const ros::Time& stamp) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header.frame_id = frame_id;
  cloud.header.stamp = stamp;
  sensor_msgs::PointCloud2Modifier modifier(cloud);
  modifier.setPointCloud2FieldsByString(1, "xyz");
  modifier.resize(points.size());
  sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  for (const Eigen::Vector3f& point : points) {
    *x = point.x();
    *y = point.y();
    *z = point.z();
    ++x, ++y, ++z;
  }
  cloud.is_dense = std::all_of(points.begin(), points.end(),
                               [](const Eigen::Vector3f& point) { return point.allFinite(); });
  return cloud;
}

}  // namespace occupancy_fusion
