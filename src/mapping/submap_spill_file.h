// Where the oldest submaps' changes go when the submaps have a memory bound
// (reanchoring/max_memory_mb): an unnamed temporary file, appended to and read back at offsets.
// It is memory's overflow, not a save: checkpoints and `.submaps` files hold every submap.
#pragma once

#include <cstdint>
#include <mutex>
#include <string>

namespace occupancy_fusion {

class SubmapSpillFile {
 public:
  // A new file in `folder` (empty: the system's temporary folder), removed from the folder at
  // once (it lives as long as this object). Throws std::runtime_error when it cannot be made.
  explicit SubmapSpillFile(const std::string& folder);
  ~SubmapSpillFile();
  SubmapSpillFile(const SubmapSpillFile&) = delete;
  SubmapSpillFile& operator=(const SubmapSpillFile&) = delete;

  // Writes `bytes` at the end; returns their offset. Throws std::runtime_error on a failed write
  // (a full disk). Thread-safe.
  std::uint64_t append(const std::string& bytes);
  // The `size` bytes at `offset` into *out. Throws std::runtime_error on a failed read. May run
  // alongside other reads and appends.
  void read(std::uint64_t offset, std::uint32_t size, std::string* out) const;
  std::uint64_t bytes() const;  // written so far

 private:
  int fd_ = -1;
  mutable std::mutex mutex_;  // the end
  std::uint64_t end_ = 0;
};

}  // namespace occupancy_fusion
