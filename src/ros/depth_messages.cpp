#include "occupancy_fusion/ros/depth_messages.h"

#include <cstdint>
#include <cstring>

#include <sensor_msgs/image_encodings.h>

#include "occupancy_fusion/ros/image_bytes.h"

namespace occupancy_fusion {

DepthImageView depthInMetres(const sensor_msgs::Image& image, std::vector<float>* storage) {
  namespace enc = sensor_msgs::image_encodings;
  const bool millimetres = image.encoding == enc::TYPE_16UC1 || image.encoding == enc::MONO16;
  const bool metres = image.encoding == enc::TYPE_32FC1;
  if (!millimetres && !metres) {
    throw DepthImageRejected(
        DepthImageRejected::Reason::kEncoding,
        "encoding '" + image.encoding + "' is not a depth encoding (16UC1 in mm or 32FC1 in m)");
  }
  if (needsByteSwap(image)) {
    throw DepthImageRejected(DepthImageRejected::Reason::kEncoding,
                             "encoding '" + image.encoding + "' with foreign byte order");
  }
  if (isEmptyImage(image)) {
    throw DepthImageRejected(DepthImageRejected::Reason::kEncoding, "the image is empty");
  }
  const std::size_t pixel_bytes = millimetres ? 2 : 4;
  if (!rowsFitData(image, pixel_bytes)) {
    throw DepthImageRejected(DepthImageRejected::Reason::kEncoding,
                             "encoding '" + image.encoding + "': step or data size too small");
  }
  const int width = static_cast<int>(image.width);
  const int height = static_cast<int>(image.height);
  if (metres && image.step % sizeof(float) == 0) {
    // Zero copy: the message's buffer is suitably aligned (std::allocator) and rows are whole
    // floats apart.
    return {width, height, reinterpret_cast<const float*>(image.data.data()),
            static_cast<int>(image.step / sizeof(float))};
  }
  const std::size_t row_bytes = static_cast<std::size_t>(width) * pixel_bytes;
  if (metres) {  // rows padded to a step that is no whole number of floats
    storage->resize(static_cast<std::size_t>(width) * height);
    for (int v = 0; v < height; ++v) {
      std::memcpy(storage->data() + static_cast<std::size_t>(v) * width,
                  image.data.data() + static_cast<std::size_t>(v) * image.step, row_bytes);
    }
  } else {
    std::vector<std::uint16_t> millimetres_dense(static_cast<std::size_t>(width) * height);
    for (int v = 0; v < height; ++v) {
      std::memcpy(millimetres_dense.data() + static_cast<std::size_t>(v) * width,
                  image.data.data() + static_cast<std::size_t>(v) * image.step, row_bytes);
    }
    *storage = depthFromMillimetres(millimetres_dense.data(), millimetres_dense.size());
  }
  return {width, height, storage->data(), width};
}

CameraIntrinsics depthCameraIntrinsics(const sensor_msgs::CameraInfo& info,
                                       const sensor_msgs::Image& image) {
  using Reason = DepthImageRejected::Reason;
  if (info.width != image.width || info.height != image.height) {
    throw DepthImageRejected(Reason::kCameraInfo,
                             "camera_info is " + std::to_string(info.width) + "x" +
                                 std::to_string(info.height) + " but the image " +
                                 std::to_string(image.width) + "x" + std::to_string(image.height));
  }
  if (info.binning_x > 1 || info.binning_y > 1 || info.roi.width != 0 || info.roi.height != 0) {
    throw DepthImageRejected(Reason::kCameraInfo,
                             "camera_info with binning or ROI is not supported");
  }
  CameraIntrinsics camera;
  camera.width = static_cast<int>(info.width);
  camera.height = static_cast<int>(info.height);
  camera.fx = info.K[0];
  camera.fy = info.K[4];
  camera.cx = info.K[2];
  camera.cy = info.K[5];
  if (!(camera.fx > 0.0) || !(camera.fy > 0.0)) {
    throw DepthImageRejected(Reason::kCameraInfo,
                             "camera_info has focal length fx = " + std::to_string(camera.fx) +
                                 ", fy = " + std::to_string(camera.fy));
  }
  try {
    camera.validate();
  } catch (const std::invalid_argument& error) {
    throw DepthImageRejected(Reason::kCameraInfo, std::string("camera_info: ") + error.what());
  }
  return camera;
}

}  // namespace occupancy_fusion
