// sensor_msgs/PointCloud2 -> points in the map frame (transformedPoints, src/ros/conversions.cpp),
// as the point cloud mapper converts every cloud. Any input must be rejected with
// std::invalid_argument or give at most one point per width x height cell, each read from inside
// the message's data (AddressSanitizer checks the reads).
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "fuzz_input.h"
#include "occupancy_fusion/ros/conversions.h"

namespace occupancy_fusion {
namespace fuzz {
namespace {

template <typename Codec>
void describe(Codec* codec, sensor_msgs::PointCloud2* cloud) {
  codec->field(&cloud->width);
  codec->field(&cloud->height);
  codec->field(&cloud->point_step);
  codec->field(&cloud->row_step);
  codec->field(&cloud->is_bigendian);
  std::uint8_t field_count = static_cast<std::uint8_t>(cloud->fields.size());
  codec->field(&field_count);
  cloud->fields.resize(field_count);
  for (sensor_msgs::PointField& field : cloud->fields) {
    codec->field(&field.name);
    codec->field(&field.offset);
    codec->field(&field.datatype);
    codec->field(&field.count);
  }
  codec->bytes(&cloud->data);
}

}  // namespace

void writeSeeds() {
  sensor_msgs::PointCloud2 cloud;
  resizeXyzCloud(3, &cloud);
  for (std::size_t i = 0; i < cloud.data.size(); ++i) cloud.data[i] = static_cast<std::uint8_t>(i);
  writeSeed("seed_xyz32", encodeFields(describe<FuzzWriter>, &cloud));

  // An organised 2 x 2 cloud of FLOAT64 x, y, z after an intensity, rows padded.
  sensor_msgs::PointCloud2 padded;
  padded.width = 2;
  padded.height = 2;
  padded.point_step = 32;
  padded.row_step = 72;
  const char* names[] = {"intensity", "x", "y", "z"};
  for (int i = 0; i < 4; ++i) {
    sensor_msgs::PointField field;
    field.name = names[i];
    field.offset = i == 0 ? 0 : 8 * i;
    field.datatype = i == 0 ? sensor_msgs::PointField::FLOAT32 : sensor_msgs::PointField::FLOAT64;
    field.count = 1;
    padded.fields.push_back(field);
  }
  padded.data.assign(static_cast<std::size_t>(padded.row_step) * padded.height, 0x40);
  writeSeed("seed_xyz64_padded", encodeFields(describe<FuzzWriter>, &padded));
}

}  // namespace fuzz
}  // namespace occupancy_fusion

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occupancy_fusion;
  sensor_msgs::PointCloud2 cloud;
  fuzz::decodeFields(fuzz::describe<fuzz::FuzzReader>, data, size, &cloud);
  Eigen::Isometry3d target_T_cloud = Eigen::Isometry3d::Identity();
  target_T_cloud.translation() = Eigen::Vector3d(1.0, -2.0, 0.5);
  try {
    const std::vector<Eigen::Vector3f> points = transformedPoints(cloud, target_T_cloud);
    if (points.size() > static_cast<std::size_t>(cloud.width) * cloud.height) std::abort();
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
