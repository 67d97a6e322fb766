#include "occupancy_fusion/ros/depth_messages.h"

#include <cstdint>
#include <cstring>

#include <sensor_msgs/image_encodings.h>

#include "occupancy_fusion/ros/camera_info_message.h"
#include "occupancy_fusion/ros/image_bytes.h"

namespace occupancy_fusion {

DepthImageView depthInMetres(const sensor_msgs::Image& image, std::vector<float>* storage) {
  namespace enc = sensor_msgs::image_encodings;
  const bool millimetres = image.encoding == enc::TYPE_16UC1 || image.encoding == enc::MONO16;
  const bool metres = image.encoding == enc::TYPE_32FC1;
  if (!isDepthEncoding(image.encoding)) {
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
  if (binnedWidth(info) != image.width || binnedHeight(info) != image.height) {
    throw DepthImageRejected(Reason::kCameraInfo,
                             "camera_info is " + std::to_string(binnedWidth(info)) + "x" +
                                 std::to_string(binnedHeight(info)) + " but the image " +
                                 std::to_string(image.width) + "x" + std::to_string(image.height));
  }
  try {
    return intrinsicsOf(info);
  } catch (const std::invalid_argument& error) {
    throw DepthImageRejected(Reason::kCameraInfo, error.what());
  }
}

bool isDepthEncoding(const std::string& encoding) {
  namespace enc = sensor_msgs::image_encodings;
  return encoding == enc::TYPE_16UC1 || encoding == enc::MONO16 || encoding == enc::TYPE_32FC1;
}

}  // namespace occupancy_fusion
