#include "submap_spill_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace occupancy_fusion {

SubmapSpillFile::SubmapSpillFile(const std::string& folder) {
  const std::filesystem::path where =
      folder.empty() ? std::filesystem::temp_directory_path() : std::filesystem::path(folder);
  std::string name = (where / "occupancy_fusion_submaps_XXXXXX").string();
  std::vector<char> path(name.begin(), name.end());
  path.push_back('\0');
  fd_ = ::mkstemp(path.data());
  if (fd_ < 0) {
    throw std::runtime_error("submaps: cannot make a spill file in " + where.string() + ": " +
                             std::strerror(errno));
  }
  ::unlink(path.data());  // gone with the process, whatever the end
}

SubmapSpillFile::~SubmapSpillFile() {
  if (fd_ >= 0) ::close(fd_);
}

std::uint64_t SubmapSpillFile::append(const std::string& bytes) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::pwrite(fd_, bytes.data() + written, bytes.size() - written,
                               static_cast<off_t>(end_ + written));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      throw std::runtime_error(std::string("submaps: writing the spill file failed: ") +
                               std::strerror(errno));
    }
    written += static_cast<std::size_t>(n);
  }
  const std::uint64_t offset = end_;
  end_ += bytes.size();
  return offset;
}

void SubmapSpillFile::read(std::uint64_t offset, std::uint32_t size, std::string* out) const {
  out->resize(size);
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n =
        ::pread(fd_, out->data() + done, size - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      throw std::runtime_error(std::string("submaps: reading the spill file failed: ") +
                               (n == 0 ? "it ends early" : std::strerror(errno)));
    }
    done += static_cast<std::size_t>(n);
  }
}

std::uint64_t SubmapSpillFile::bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return end_;
}

}  // namespace occupancy_fusion
