// Reading the bytes of a sensor_msgs/Image: its byte order against the host's and whether its
// declared size fits its data. Header only, so that the nodelets' conversions and the tools'
// (occupancy_fusion_tools, which does not link the nodelets) share one definition; each caller
// throws its own exception with its own message.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include <sensor_msgs/Image.h>

namespace occupancy_fusion {

inline bool hostIsBigEndian() {
  const std::uint16_t probe = 1;
  std::uint8_t first_byte = 0;
  std::memcpy(&first_byte, &probe, 1);
  return first_byte == 0;
}

// The value to write into an outgoing image's is_bigendian.
inline std::uint8_t hostByteOrderFlag() { return hostIsBigEndian() ? 1 : 0; }

// True when the image's values are stored in the other byte order than the host's.
inline bool needsByteSwap(const sensor_msgs::Image& image) {
  return (image.is_bigendian != 0) != hostIsBigEndian();
}

// The T stored at `bytes` (any alignment), byte-swapped when `swap`.
template <typename T>
T readValue(const std::uint8_t* bytes, bool swap) {
  std::uint8_t ordered[sizeof(T)];
  std::memcpy(ordered, bytes, sizeof(T));
  if (swap) std::reverse(ordered, ordered + sizeof(T));
  T value;
  std::memcpy(&value, ordered, sizeof(T));
  return value;
}

inline bool isEmptyImage(const sensor_msgs::Image& image) {
  return image.width == 0 || image.height == 0;
}

// Whether rows of `width` pixels of `bytes_per_pixel` fit in the step, and `height` steps in the
// data: every pixel can then be read without reading past the message.
inline bool rowsFitData(const sensor_msgs::Image& image, std::size_t bytes_per_pixel) {
  return image.step >= image.width * bytes_per_pixel &&
         image.data.size() >= static_cast<std::size_t>(image.step) * image.height;
}

}  // namespace occupancy_fusion
