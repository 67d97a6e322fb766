#include "occupancy_fusion/ros/conversions.h"

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

#include <sensor_msgs/point_cloud2_iterator.h>

namespace occupancy_fusion {
namespace {

// Reads each of the width x height points at v * row_step + u * point_step (rows may be padded),
// not through PointCloud2ConstIterator: that walks the data in point_step strides to its end, so
// it reads padding as points and runs past the end of data that is no whole number of points.
template <typename Scalar>
void appendTransformed(const sensor_msgs::PointCloud2& cloud, const std::uint32_t offsets[3],
                       const Eigen::Isometry3d& target_T_cloud,
                       std::vector<Eigen::Vector3f>* points) {
  const Eigen::Isometry3f transform = target_T_cloud.cast<float>();
  for (std::uint32_t v = 0; v < cloud.height; ++v) {
    for (std::uint32_t u = 0; u < cloud.width; ++u) {
      const std::uint8_t* point = cloud.data.data() + static_cast<std::size_t>(v) * cloud.row_step +
                                  static_cast<std::size_t>(u) * cloud.point_step;
      Scalar xyz[3];
      for (int axis = 0; axis < 3; ++axis) {
        std::memcpy(&xyz[axis], point + offsets[axis], sizeof(Scalar));
      }
      const Eigen::Vector3f local(static_cast<float>(xyz[0]), static_cast<float>(xyz[1]),
                                  static_cast<float>(xyz[2]));
      points->push_back(transform * local);
    }
  }
}

// Throws std::invalid_argument unless every field of every point lies inside the data.
void requireConsistentLayout(const sensor_msgs::PointCloud2& cloud, const std::uint32_t offsets[3],
                             std::size_t scalar_bytes) {
  const std::string name = "point cloud in frame '" + cloud.header.frame_id + "'";
  for (int axis = 0; axis < 3; ++axis) {
    if (static_cast<std::uint64_t>(offsets[axis]) + scalar_bytes > cloud.point_step) {
      throw std::invalid_argument(name + ": a field ends beyond point_step " +
                                  std::to_string(cloud.point_step));
    }
  }
  const std::uint64_t row_bytes = static_cast<std::uint64_t>(cloud.width) * cloud.point_step;
  if (cloud.height > 0 && cloud.width > 0 &&
      (row_bytes > cloud.row_step ||
       static_cast<std::uint64_t>(cloud.row_step) * (cloud.height - 1) + row_bytes >
           cloud.data.size())) {
    throw std::invalid_argument(name + ": " + std::to_string(cloud.width) + "x" +
                                std::to_string(cloud.height) + " points of " +
                                std::to_string(cloud.point_step) + " bytes, rows of " +
                                std::to_string(cloud.row_step) + " bytes, do not fit in " +
                                std::to_string(cloud.data.size()) + " bytes of data");
  }
}

// The datatype shared by x, y and z, or 0 when one is missing or they differ; their offsets.
std::uint8_t xyzDatatype(const sensor_msgs::PointCloud2& cloud, std::uint32_t offsets[3]) {
  std::uint8_t types[3] = {0, 0, 0};
  const char* names[3] = {"x", "y", "z"};
  for (const sensor_msgs::PointField& field : cloud.fields) {
    for (int axis = 0; axis < 3; ++axis) {
      if (field.name == names[axis] && field.count == 1) {
        types[axis] = field.datatype;
        offsets[axis] = field.offset;
      }
    }
  }
  return types[0] == types[1] && types[1] == types[2] ? types[0] : 0;
}

}  // namespace

FrameHeader frameHeaderOf(const std_msgs::Header& header, const std::string& kind,
                          const std::string& source) {
  FrameHeader frame;
  frame.kind = kind;
  frame.source = source;
  frame.frame_id = header.frame_id;
  frame.stamp = header.stamp.toSec();
  return frame;
}

std::vector<Eigen::Vector3f> transformedPoints(const sensor_msgs::PointCloud2& cloud,
                                               const Eigen::Isometry3d& target_T_cloud) {
  std::uint32_t offsets[3] = {0, 0, 0};
  const std::uint8_t datatype = xyzDatatype(cloud, offsets);
  if (datatype != sensor_msgs::PointField::FLOAT32 &&
      datatype != sensor_msgs::PointField::FLOAT64) {
    throw std::invalid_argument("point cloud in frame '" + cloud.header.frame_id +
                                "' has no FLOAT32 or FLOAT64 x, y, z fields");
  }
  const bool single = datatype == sensor_msgs::PointField::FLOAT32;
  requireConsistentLayout(cloud, offsets, single ? sizeof(float) : sizeof(double));
  std::vector<Eigen::Vector3f> points;
  if (cloud.width == 0 || cloud.height == 0) return points;              // not 4e9 empty rows
  points.reserve(static_cast<std::size_t>(cloud.width) * cloud.height);  // checked: fits the data
  if (single) {
    appendTransformed<float>(cloud, offsets, target_T_cloud, &points);
  } else {
    appendTransformed<double>(cloud, offsets, target_T_cloud, &points);
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
