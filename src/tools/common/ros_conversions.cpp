#include "occupancy_fusion/tools/ros_conversions.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include <sensor_msgs/point_cloud2_iterator.h>

#include "occupancy_fusion/ros/image_bytes.h"

namespace occupancy_fusion {

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

StereoCamera stereoCameraAtImageCentre(const stereo_msgs::DisparityImage& message) {
  StereoCamera camera;
  camera.fx = message.f;
  camera.fy = message.f;
  camera.cx = (static_cast<double>(message.image.width) - 1.0) / 2.0;
  camera.cy = (static_cast<double>(message.image.height) - 1.0) / 2.0;
  camera.baseline = message.T;
  camera.validate();
  return camera;
}

sensor_msgs::Image depthImageMessage(const std::vector<float>& depth, int width, int height,
                                     bool millimetres, const std::string& frame_id,
                                     const ros::Time& stamp) {
  sensor_msgs::Image image;
  image.header.frame_id = frame_id;
  image.header.stamp = stamp;
  image.width = static_cast<std::uint32_t>(width);
  image.height = static_cast<std::uint32_t>(height);
  image.is_bigendian = hostByteOrderFlag();
  const std::size_t bytes = millimetres ? sizeof(std::uint16_t) : sizeof(float);
  image.encoding = millimetres ? "16UC1" : "32FC1";
  image.step = static_cast<std::uint32_t>(width * bytes);
  image.data.resize(static_cast<std::size_t>(image.step) * height);
  for (std::size_t i = 0; i < depth.size(); ++i) {
    if (millimetres) {
      const float mm = std::isfinite(depth[i]) ? std::round(depth[i] * 1e3f) : 0.0f;
      const std::uint16_t value = static_cast<std::uint16_t>(std::clamp(mm, 0.0f, 65535.0f));
      std::memcpy(image.data.data() + i * bytes, &value, bytes);
    } else {
      std::memcpy(image.data.data() + i * bytes, &depth[i], bytes);
    }
  }
  return image;
}

stereo_msgs::DisparityImage disparityMessage(const std::vector<float>& disparity, int width,
                                             int height, const StereoCamera& camera,
                                             double min_disparity, double max_disparity,
                                             const std::string& frame_id, const ros::Time& stamp) {
  stereo_msgs::DisparityImage message;
  message.header.frame_id = frame_id;
  message.header.stamp = stamp;
  std::vector<float> written = disparity;
  for (float& value : written) {
    if (!std::isfinite(value)) value = -1.0f;
  }
  message.image = depthImageMessage(written, width, height, false, frame_id, stamp);
  message.f = static_cast<float>(camera.fx);
  message.T = static_cast<float>(camera.baseline);
  message.min_disparity = static_cast<float>(min_disparity);
  message.max_disparity = static_cast<float>(max_disparity);
  message.delta_d = 1.0f / 16.0f;  // the sub-pixel step of OpenCV's block matchers
  message.valid_window.width = static_cast<std::uint32_t>(width);
  message.valid_window.height = static_cast<std::uint32_t>(height);
  return message;
}

}  // namespace occupancy_fusion
