#include "occupancy_fusion/map/log_odds_deltas.h"

#include <lz4.h>

#include <cstring>
#include <stdexcept>
#include <vector>

namespace occupancy_fusion {
namespace detail {

std::unique_ptr<char[]> compressChanges(const char* raw, int raw_size, std::uint32_t* packed_size) {
  const int bound = LZ4_compressBound(raw_size);
  thread_local std::vector<char> buffer;  // the bound, reused: blocks close by the thousand
  buffer.resize(static_cast<std::size_t>(bound));
  const int size = LZ4_compress_default(raw, buffer.data(), raw_size, bound);
  if (size <= 0) throw std::runtime_error("LZ4 could not compress a block's changes");
  // Kept at its compressed size: the bound is larger than the raw bytes.
  auto packed = std::make_unique<char[]>(static_cast<std::size_t>(size));
  std::memcpy(packed.get(), buffer.data(), static_cast<std::size_t>(size));
  *packed_size = static_cast<std::uint32_t>(size);
  return packed;
}

void expandChanges(const char* packed, std::uint32_t packed_size, char* raw, int raw_size) {
  const int size = LZ4_decompress_safe(packed, raw, static_cast<int>(packed_size), raw_size);
  if (size != raw_size) throw std::runtime_error("a block's changes are damaged");
}

}  // namespace detail
}  // namespace occupancy_fusion
