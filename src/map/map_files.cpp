#include "occupancy_fusion/map/map_files.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "occupancy_fusion/map/octomap_conversion.h"
#include "occupancy_fusion/map/octree_files.h"

namespace occupancy_fusion {
namespace {

// map_server's pixel values (map_saver): p = (255 - pixel) / 255 with negate 0, so 0 reads as
// occupied (p = 1 > 0.65), 254 as free (p = 0.004 < 0.196) and 205 as unknown (p = 0.196...).
constexpr std::uint8_t kPgmOccupied = 0;
constexpr std::uint8_t kPgmFree = 254;
constexpr std::uint8_t kPgmUnknown = 205;
constexpr double kOccupiedThreshold = 0.65;
constexpr double kFreeThreshold = 0.196;

constexpr std::uint8_t kPngOccupied = 0;
constexpr std::uint8_t kPngFree = 255;
constexpr std::uint8_t kPngUnknown = 128;

std::string fileName(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string extensionOf(const std::string& path) {
  const std::string name = fileName(path);
  const std::size_t dot = name.find_last_of('.');
  return dot == std::string::npos ? std::string() : name.substr(dot);
}

void requireNonEmpty(const OccupancyRaster& raster, const char* what) {
  if (raster.empty()) throw std::invalid_argument(std::string(what) + ": the raster is empty");
  if (raster.data.size() != static_cast<std::size_t>(raster.width) * raster.height) {
    throw std::invalid_argument(std::string(what) + ": data size does not match width x height");
  }
}

void writeLittleEndianFloat(std::ostream& out, float value) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  const char bytes[4] = {static_cast<char>(bits & 0xff), static_cast<char>((bits >> 8) & 0xff),
                         static_cast<char>((bits >> 16) & 0xff),
                         static_cast<char>((bits >> 24) & 0xff)};
  out.write(bytes, sizeof(bytes));
}

std::uint8_t pgmValue(std::int8_t cell) {
  if (cell < 0) return kPgmUnknown;
  if (cell >= kOccupiedThreshold * 100.0) return kPgmOccupied;
  if (cell <= kFreeThreshold * 100.0) return kPgmFree;
  return kPgmUnknown;
}

std::uint8_t pngValue(std::int8_t cell) {
  if (cell < 0) return kPngUnknown;
  return cell >= kOccupiedThreshold * 100.0 ? kPngOccupied : kPngFree;
}

// A number in its shortest exact-enough text form (no trailing zeros).
std::string numberText(double value) {
  std::ostringstream text;
  text << std::setprecision(15) << value;
  return text.str();
}

std::size_t writeTree(const VoxelMap& map, const std::string& path, bool binary) {
  const OctreeFilePaths paths{binary ? "" : path, binary ? path : ""};
  return writeOctreeFiles(blockSourceOf(map), map.resolution(), map.model(), paths).skipped_voxels;
}

// Makes a file's data, or a folder's entries, durable: without it a power cut shortly after a
// save can leave the renamed file empty on file systems that order metadata before data.
bool syncToDisk(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) return false;
  const int result = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  errno = error;  // the caller reports fsync's error, not close's
  return result == 0;
}

std::string folderOf(const std::string& path) {
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  return folder.empty() ? "." : folder.string();
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  static std::atomic<unsigned> counter{0};
  const std::string temporary =
      path + ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
  try {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(std::strerror(errno));
    write(out);
    out.flush();
    if (!out) throw std::runtime_error("write failed");
    out.close();
    if (out.fail()) throw std::runtime_error("close failed");
    if (!syncToDisk(temporary)) {
      throw std::runtime_error(std::string("fsync failed: ") + std::strerror(errno));
    }
    if (std::rename(temporary.c_str(), path.c_str()) != 0) {
      throw std::runtime_error(std::string("rename failed: ") + std::strerror(errno));
    }
    // The rename itself: best effort, as some file systems cannot fsync a folder.
    syncToDisk(folderOf(path));
  } catch (const std::exception& error) {
    std::remove(temporary.c_str());
    throw std::runtime_error("cannot write " + path + ": " + error.what());
  }
}

std::size_t writeBt(const VoxelMap& map, const std::string& path) {
  return writeTree(map, path, /*binary=*/true);
}

std::size_t writeOt(const VoxelMap& map, const std::string& path) {
  return writeTree(map, path, /*binary=*/false);
}

std::unique_ptr<VoxelMap> readOctomapFile(const std::string& path, const VoxelMapConfig& base) {
  std::unique_ptr<octomap::OcTree> tree = readOcTreeFile(path, base.model);
  VoxelMapConfig config = base;
  config.resolution = tree->getResolution();
  try {
    auto map = std::make_unique<VoxelMap>(config);
    fromOcTree(*tree, map.get());
    return map;
  } catch (const std::invalid_argument& error) {  // e.g. leaves covering too many voxels
    throw std::runtime_error(path + ": " + error.what());
  }
}

void writeMapServerFiles(const OccupancyRaster& raster, const std::string& prefix) {
  requireNonEmpty(raster, "writeMapServerFiles");
  const std::string pgm_path = prefix + ".pgm";
  writeFileAtomically(pgm_path, [&](std::ostream& out) {
    out << "P5\n# occupancy_fusion map, " << numberText(raster.resolution) << " m/pixel\n"
        << raster.width << ' ' << raster.height << "\n255\n";
    std::vector<char> row(static_cast<std::size_t>(raster.width));
    // The image's first row is the map's top (highest y).
    for (int y = raster.height - 1; y >= 0; --y) {
      for (int x = 0; x < raster.width; ++x) row[x] = static_cast<char>(pgmValue(raster.at(x, y)));
      out.write(row.data(), static_cast<std::streamsize>(row.size()));
    }
  });
  writeFileAtomically(prefix + ".yaml", [&](std::ostream& out) {
    out << "image: " << fileName(pgm_path) << "\n"
        << "resolution: " << numberText(raster.resolution) << "\n"
        << "origin: [" << numberText(raster.origin_x) << ", " << numberText(raster.origin_y)
        << ", 0.0]\n"
        << "negate: 0\n"
        << "occupied_thresh: " << numberText(kOccupiedThreshold) << "\n"
        << "free_thresh: " << numberText(kFreeThreshold) << "\n";
  });
}

std::string npyFloatHeader(int rows, int columns) {
  // Format 1.0: magic, version, uint16 header length, then a Python dict literal padded with
  // spaces and ended by '\n' so that the data starts at a multiple of 64 bytes.
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" +
                       std::to_string(rows) + ", " + std::to_string(columns) + "), }";
  constexpr std::size_t kPreamble = 10;  // magic (6) + version (2) + length (2)
  const std::size_t unpadded = kPreamble + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header.push_back('\n');
  std::string bytes("\x93NUMPY\x01\x00", 8);
  bytes.push_back(static_cast<char>(header.size() & 0xff));
  bytes.push_back(static_cast<char>((header.size() >> 8) & 0xff));
  return bytes + header;
}

void appendLittleEndianFloats(const std::vector<float>& values, std::string* bytes) {
  std::ostringstream out;
  for (const float value : values) writeLittleEndianFloat(out, value);
  bytes->append(out.str());
}

std::string encodeNpy(const LogOddsRaster& raster) {
  if (raster.width < 0 || raster.height < 0 ||
      raster.data.size() != static_cast<std::size_t>(raster.width) * raster.height) {
    throw std::invalid_argument("encodeNpy: data size does not match width x height");
  }
  std::string bytes = npyFloatHeader(raster.height, raster.width);
  appendLittleEndianFloats(raster.data, &bytes);
  return bytes;
}

void writeNpy(const LogOddsRaster& raster, const std::string& path) {
  std::string bytes;
  try {
    bytes = encodeNpy(raster);
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(std::string(error.what()) + " for " + path);
  }
  writeFileAtomically(path, [&](std::ostream& out) {
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  });
}

void writePcd(const VoxelMap& map, const std::string& path, PcdEncoding encoding) {
  struct Point {
    VoxelIndex index;
    Eigen::Vector3f center;
    float probability;
  };
  std::vector<Point> points;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    points.push_back({index, map.centerOf(index).cast<float>(),
                      static_cast<float>(probabilityFromLogOdds(log_odds))});
  });
  // In voxel order (z, then y, then x), not the block table's, which follows the order in which
  // the mappers' threads created the blocks: the same map gives the same file.
  std::sort(points.begin(), points.end(), [](const Point& a, const Point& b) {
    return std::tie(a.index.z(), a.index.y(), a.index.x()) <
           std::tie(b.index.z(), b.index.y(), b.index.x());
  });
  writeFileAtomically(path, [&](std::ostream& out) {
    out << "# .PCD v0.7 - Point Cloud Data file format\n"
        << "VERSION 0.7\n"
        << "FIELDS x y z probability\n"
        << "SIZE 4 4 4 4\n"
        << "TYPE F F F F\n"
        << "COUNT 1 1 1 1\n"
        << "WIDTH " << points.size() << "\n"
        << "HEIGHT 1\n"
        << "VIEWPOINT 0 0 0 1 0 0 0\n"
        << "POINTS " << points.size() << "\n"
        << "DATA " << (encoding == PcdEncoding::kBinary ? "binary" : "ascii") << "\n";
    if (encoding == PcdEncoding::kBinary) {
      for (const Point& point : points) {
        for (int axis = 0; axis < 3; ++axis) writeLittleEndianFloat(out, point.center[axis]);
        writeLittleEndianFloat(out, point.probability);
      }
    } else {
      out << std::setprecision(9);  // enough digits to read every float back exactly
      for (const Point& point : points) {
        out << point.center.x() << ' ' << point.center.y() << ' ' << point.center.z() << ' '
            << point.probability << '\n';
      }
    }
  });
}

void writePng(const OccupancyRaster& raster, const std::string& path, int scale) {
  requireNonEmpty(raster, "writePng");
  if (scale < 1) throw std::invalid_argument("writePng: scale must be at least 1");
  cv::Mat image(raster.height * scale, raster.width * scale, CV_8UC1);
  for (int row = 0; row < image.rows; ++row) {
    const int y = raster.height - 1 - row / scale;  // y up: the top row is the highest y
    auto* pixels = image.ptr<std::uint8_t>(row);
    for (int column = 0; column < image.cols; ++column) {
      pixels[column] = pngValue(raster.at(column / scale, y));
    }
  }
  std::string extension = extensionOf(path);
  if (extension.empty()) extension = ".png";
  std::vector<std::uint8_t> encoded;
  bool ok = false;
  try {
    ok = cv::imencode(extension, image, encoded);
  } catch (const cv::Exception& error) {
    throw std::runtime_error("cannot encode " + path + ": " + error.what());
  }
  if (!ok) throw std::runtime_error("cannot encode " + path + " as " + extension);
  writeFileAtomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(encoded.data()),
              static_cast<std::streamsize>(encoded.size()));
  });
}

}  // namespace occupancy_fusion
