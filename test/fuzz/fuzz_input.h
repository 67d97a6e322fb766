// The byte layout shared by the message harnesses and their seed writer: fields are taken in a
// fixed order from the front of the input (little-endian as on the host, missing bytes read as
// zero), strings and byte arrays with a length prefix. Each harness describes its message once,
// in a function templated on FuzzReader / FuzzWriter, so its seeds are valid messages by
// construction.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <type_traits>
#include <vector>

namespace occupancy_fusion {
namespace fuzz {

class FuzzReader {
 public:
  FuzzReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  template <typename T>
  void field(T* value) {
    static_assert(std::is_trivially_copyable<T>::value, "plain fields only");
    std::uint8_t bytes[sizeof(T)] = {};
    const std::size_t count = std::min(sizeof(T), size_ - at_);
    std::memcpy(bytes, data_ + at_, count);
    at_ += count;
    std::memcpy(value, bytes, sizeof(T));
  }
  // A string of at most 255 bytes (one length byte).
  void field(std::string* text) {
    std::uint8_t length = 0;
    field(&length);
    const std::size_t count = std::min<std::size_t>(length, size_ - at_);
    text->assign(reinterpret_cast<const char*>(data_ + at_), count);
    at_ += count;
  }
  // A byte array with a 16-bit length (bounded by what is left).
  template <typename Byte>
  void bytes(std::vector<Byte>* out) {
    static_assert(sizeof(Byte) == 1, "bytes only");
    std::uint16_t length = 0;
    field(&length);
    const std::size_t count = std::min<std::size_t>(length, size_ - at_);
    out->assign(data_ + at_, data_ + at_ + count);
    at_ += count;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

class FuzzWriter {
 public:
  template <typename T>
  void field(T* value) {
    static_assert(std::is_trivially_copyable<T>::value, "plain fields only");
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(value);
    out_.insert(out_.end(), bytes, bytes + sizeof(T));
  }
  void field(std::string* text) {
    auto length = static_cast<std::uint8_t>(std::min<std::size_t>(text->size(), 255));
    field(&length);
    out_.insert(out_.end(), text->begin(), text->begin() + length);
  }
  template <typename Byte>
  void bytes(std::vector<Byte>* in) {
    auto length = static_cast<std::uint16_t>(std::min<std::size_t>(in->size(), 65535));
    field(&length);
    out_.insert(out_.end(), in->begin(), in->begin() + length);
  }
  const std::vector<std::uint8_t>& data() const { return out_; }

 private:
  std::vector<std::uint8_t> out_;
};

// The input bytes that give `fields` (for seeds): `describe` is the harness's description of its
// message, instantiated for the writer (describe<FuzzWriter>).
template <typename... Fields>
std::vector<std::uint8_t> encodeFields(void (*describe)(FuzzWriter*, Fields*...),
                                       Fields*... fields) {
  FuzzWriter writer;
  describe(&writer, fields...);
  return writer.data();
}

// Fills `fields` from the fuzzer's input in the same layout (describe<FuzzReader>).
template <typename... Fields>
void decodeFields(void (*describe)(FuzzReader*, Fields*...), const std::uint8_t* data,
                  std::size_t size, Fields*... fields) {
  FuzzReader reader(data, size);
  describe(&reader, fields...);
}

// Writes `encoded` as <$FUZZ_SEED_DIR>/<name> when that variable is set (scripts/fuzz.sh sets it
// to the run's corpus folder), so generated seeds join the checked-in ones.
inline void writeSeed(const std::string& name, const std::vector<std::uint8_t>& encoded) {
  const char* folder = std::getenv("FUZZ_SEED_DIR");
  if (folder == nullptr || *folder == '\0') return;
  std::ofstream(std::string(folder) + "/" + name, std::ios::binary)
      .write(reinterpret_cast<const char*>(encoded.data()),
             static_cast<std::streamsize>(encoded.size()));
}

// Writes the harness's generated seeds (with writeSeed). Each harness that generates seeds defines
// it; harness_init.cpp calls it from libFuzzer's LLVMFuzzerInitialize, before the first input.
void writeSeeds();

}  // namespace fuzz
}  // namespace occupancy_fusion
