#include "occupancy_fusion/tools/ros_conversions.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>

#include <sensor_msgs/point_cloud2_iterator.h>

#include "occupancy_fusion/ros/image_bytes.h"

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

namespace occupancy_fusion {
namespace {

void checkImageSize(const sensor_msgs::Image& image, std::size_t bytes_per_pixel) {
  if (isEmptyImage(image)) {
    throw std::invalid_argument("image '" + image.header.frame_id + "' is empty");
  }
  if (!rowsFitData(image, bytes_per_pixel)) {
    throw std::invalid_argument("image '" + image.header.frame_id + "' has " +
                                std::to_string(image.data.size()) + " bytes, too few for " +
                                std::to_string(image.width) + " x " + std::to_string(image.height) +
                                " " + image.encoding);
  }
}

template <typename T>
std::vector<float> convertImage(const sensor_msgs::Image& image, float scale) {
  checkImageSize(image, sizeof(T));
  const bool swap = needsByteSwap(image);
  std::vector<float> values(static_cast<std::size_t>(image.width) * image.height);
  for (std::uint32_t v = 0; v < image.height; ++v) {
    const std::uint8_t* row = image.data.data() + static_cast<std::size_t>(v) * image.step;
    for (std::uint32_t u = 0; u < image.width; ++u) {
      values[static_cast<std::size_t>(v) * image.width + u] =
          scale * static_cast<float>(readValue<T>(row + u * sizeof(T), swap));
    }
  }
  return values;
}

}  // namespace

bool isDepthEncoding(const std::string& encoding) {
  return encoding == "16UC1" || encoding == "mono16" || encoding == "32FC1";
}

std::vector<float> depthFromImage(const sensor_msgs::Image& image) {
  if (image.encoding == "16UC1" || image.encoding == "mono16") {
    return convertImage<std::uint16_t>(image, 1e-3f);
  }
  if (image.encoding == "32FC1") return convertImage<float>(image, 1.0f);
  throw std::invalid_argument("depth image encoding '" + image.encoding +
                              "' is not supported (16UC1 in mm or 32FC1 in m)");
}

CameraIntrinsics intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info) {
  if (info.binning_x > 1 || info.binning_y > 1 || info.roi.width != 0 || info.roi.height != 0) {
    throw std::invalid_argument("camera_info of '" + info.header.frame_id +
                                "' uses binning or a region of interest (not supported)");
  }
  CameraIntrinsics camera;
  camera.width = static_cast<int>(info.width);
  camera.height = static_cast<int>(info.height);
  const bool has_projection = info.P[0] != 0.0;
  camera.fx = has_projection ? info.P[0] : info.K[0];
  camera.fy = has_projection ? info.P[5] : info.K[4];
  camera.cx = has_projection ? info.P[2] : info.K[2];
  camera.cy = has_projection ? info.P[6] : info.K[5];
  if (!(camera.fx > 0.0) || !(camera.fy > 0.0)) {
    throw std::invalid_argument("camera_info of '" + info.header.frame_id +
                                "' has no focal length (K and P are zero)");
  }
  camera.validate();
  return camera;
}

std::vector<float> disparityFromMessage(const stereo_msgs::DisparityImage& message) {
  if (message.image.encoding != "32FC1") {
    throw std::invalid_argument("disparity image encoding '" + message.image.encoding +
                                "' is not 32FC1");
  }
  std::vector<float> disparity = convertImage<float>(message.image, 1.0f);
  for (float& value : disparity) {
    if (!std::isfinite(value) || value < message.min_disparity || value > message.max_disparity) {
      value = std::numeric_limits<float>::quiet_NaN();
    }
  }
  return disparity;
}

StereoCamera stereoCameraFrom(const stereo_msgs::DisparityImage& message,
                              const sensor_msgs::CameraInfo& left_info) {
  const CameraIntrinsics left = intrinsicsFromCameraInfo(left_info);
  if (left_info.width != message.image.width || left_info.height != message.image.height) {
    throw std::invalid_argument(
        "camera_info is for " + std::to_string(left_info.width) + "x" +
        std::to_string(left_info.height) + " images, the disparity image is " +
        std::to_string(message.image.width) + "x" + std::to_string(message.image.height));
  }
  StereoCamera camera;
  camera.fx = message.f;
  camera.fy = message.f * left.fy / left.fx;
  camera.cx = left.cx;
  camera.cy = left.cy;
  camera.baseline = message.T;
  camera.validate();
  return camera;
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
