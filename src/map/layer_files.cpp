#include "occupancy_fusion/map/layer_files.h"

#include <yaml-cpp/yaml.h>
#include <boost/crc.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <limits>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "occupancy_fusion/map/map_files.h"

namespace occupancy_fusion {
namespace {

// What the yaml says of the array.
struct LayerHeader {
  std::string npy_name;
  std::optional<std::uint32_t> npy_crc32;  // of the whole .npy file, when the yaml gives it
  double resolution = 0.0;
  CellIndex origin_cell = CellIndex::Zero();
  int width = 0;
  int height = 0;
};

struct NpyMatrix {
  long long rows = 0;
  long long columns = 0;
  std::size_t data_offset = 0;
};

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what); }

// The shortest of 15 or 17 significant digits that reads back as the same double.
std::string numberText(double value) {
  for (const int digits : {15, 17}) {
    std::ostringstream text;
    text << std::setprecision(digits) << value;
    if (digits == 17 || std::stod(text.str()) == value) return text.str();
  }
  return {};
}

template <typename T>
T requiredScalar(const YAML::Node& yaml, const char* key) {
  const YAML::Node node = yaml[key];
  if (!node || !node.IsScalar()) fail(std::string("laser layer yaml: '") + key + "' is missing");
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    fail(std::string("laser layer yaml: '") + key + "' is not a valid value: " + node.Scalar());
  }
}

template <typename T>
std::array<T, 2> requiredPair(const YAML::Node& yaml, const char* key) {
  const YAML::Node node = yaml[key];
  if (!node || !node.IsSequence() || node.size() != 2) {
    fail(std::string("laser layer yaml: '") + key + "' must be a list of two numbers");
  }
  try {
    return {node[0].as<T>(), node[1].as<T>()};
  } catch (const YAML::Exception&) {
    fail(std::string("laser layer yaml: '") + key + "' must be a list of two numbers");
  }
}

// log_odds_crc32, optional: a hexadecimal 32-bit number.
std::optional<std::uint32_t> optionalCrc32(const YAML::Node& yaml) {
  if (!yaml["log_odds_crc32"]) return std::nullopt;
  const std::string text = requiredScalar<std::string>(yaml, "log_odds_crc32");
  std::size_t used = 0;
  unsigned long value = 0;
  try {
    value = std::stoul(text, &used, 16);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || value > 0xffffffffUL) {
    fail("laser layer yaml: 'log_odds_crc32' is not a 32-bit hexadecimal number: " + text);
  }
  return static_cast<std::uint32_t>(value);
}

void requireWindowInRange(const LayerHeader& header) {
  if (header.width < 0 || header.height < 0) fail("laser layer yaml: negative width or height");
  constexpr long long kLimit = GridLayer2D::kMaxCoordinateCells;
  for (int axis = 0; axis < 2; ++axis) {
    const long long first = header.origin_cell[axis];
    const long long end = first + (axis == 0 ? header.width : header.height);
    if (first < -kLimit || end > kLimit) {
      fail("laser layer yaml: the window lies outside the layer's coordinate range");
    }
  }
}

// origin is for readers of the files; it must agree with origin_cell, or one was edited.
void requireOriginMatchesCell(const YAML::Node& yaml, const LayerHeader& header) {
  const std::array<double, 2> origin = requiredPair<double>(yaml, "origin");
  for (int axis = 0; axis < 2; ++axis) {
    if (!(std::abs(origin[axis] - header.origin_cell[axis] * header.resolution) <=
          1e-3 * header.resolution)) {
      fail("laser layer yaml: origin does not equal origin_cell x resolution");
    }
  }
}

LayerHeader parseLayerYaml(const std::string& yaml_text) {
  YAML::Node yaml;
  try {
    yaml = YAML::Load(yaml_text);
  } catch (const YAML::Exception& error) {
    fail(std::string("laser layer yaml: not YAML: ") + error.what());
  }
  if (!yaml.IsMap()) fail("laser layer yaml: not a YAML mapping");
  LayerHeader header;
  header.npy_name = requiredScalar<std::string>(yaml, "log_odds");
  header.npy_crc32 = optionalCrc32(yaml);
  header.resolution = requiredScalar<double>(yaml, "resolution");
  if (!(header.resolution > 0.0) || !std::isfinite(header.resolution)) {
    fail("laser layer yaml: resolution must be a positive number of metres");
  }
  const std::array<int, 2> cell = requiredPair<int>(yaml, "origin_cell");
  header.origin_cell = CellIndex(cell[0], cell[1]);
  header.width = requiredScalar<int>(yaml, "width");
  header.height = requiredScalar<int>(yaml, "height");
  requireWindowInRange(header);
  requireOriginMatchesCell(yaml, header);
  return header;
}

std::uint32_t littleEndian(const std::string& bytes, std::size_t at, int count) {
  std::uint32_t value = 0;
  for (int i = count - 1; i >= 0; --i) {
    value = (value << 8) | static_cast<unsigned char>(bytes[at + static_cast<std::size_t>(i)]);
  }
  return value;
}

// NumPy format 1.0 / 2.0 / 3.0 header of a 2D little-endian float32 C-order array.
NpyMatrix parseNpyHeader(const std::string& bytes) {
  constexpr char kMagic[] = "\x93NUMPY";
  if (bytes.size() < 10 || bytes.compare(0, 6, kMagic, 6) != 0) fail("laser layer npy: not .npy");
  const int major = static_cast<unsigned char>(bytes[6]);
  if (major < 1 || major > 3) fail("laser layer npy: unknown format version");
  const int length_bytes = major == 1 ? 2 : 4;
  const std::size_t header_start = 8 + static_cast<std::size_t>(length_bytes);
  if (bytes.size() < header_start) fail("laser layer npy: truncated header");
  const std::size_t header_length = littleEndian(bytes, 8, length_bytes);
  if (header_length > bytes.size() - header_start) fail("laser layer npy: truncated header");
  const std::string header = bytes.substr(header_start, header_length);
  static const std::regex kDescr(R"('descr'\s*:\s*'<f4')");
  static const std::regex kOrder(R"('fortran_order'\s*:\s*False)");
  static const std::regex kShape(R"('shape'\s*:\s*\(\s*(\d{1,10})\s*,\s*(\d{1,10})\s*,?\s*\))");
  std::smatch shape;
  if (!std::regex_search(header, kDescr)) fail("laser layer npy: dtype is not '<f4' (float32)");
  if (!std::regex_search(header, kOrder)) fail("laser layer npy: not C order");
  if (!std::regex_search(header, shape, kShape)) fail("laser layer npy: not a 2D array");
  NpyMatrix matrix;
  matrix.rows = std::stoll(shape[1].str());
  matrix.columns = std::stoll(shape[2].str());
  matrix.data_offset = header_start + header_length;
  return matrix;
}

// CRC-32 (IEEE 802.3, as zlib's and PNG's): Python's zlib.crc32 gives the same value.
std::uint32_t crc32Of(const std::string& bytes) {
  boost::crc_32_type crc;
  crc.process_bytes(bytes.data(), bytes.size());
  return crc.checksum();
}

std::string hexText(std::uint32_t value) {
  std::ostringstream text;
  text << "0x" << std::hex << std::setw(8) << std::setfill('0') << value;
  return text.str();
}

LogOddsRaster parseLayerArray(const LayerHeader& header, const std::string& npy_bytes) {
  if (header.npy_crc32 && crc32Of(npy_bytes) != *header.npy_crc32) {
    fail("laser layer: the array's CRC-32 is " + hexText(crc32Of(npy_bytes)) + ", the yaml's " +
         hexText(*header.npy_crc32) + ": the files come from different saves");
  }
  const NpyMatrix matrix = parseNpyHeader(npy_bytes);
  if (matrix.rows != header.height || matrix.columns != header.width) {
    fail("laser layer: the array's shape (" + std::to_string(matrix.rows) + ", " +
         std::to_string(matrix.columns) + ") is not the yaml's (height " +
         std::to_string(header.height) + ", width " + std::to_string(header.width) +
         "): the files come from different saves");
  }
  const std::size_t count = static_cast<std::size_t>(header.width) * header.height;
  if (npy_bytes.size() - matrix.data_offset != count * sizeof(float)) {
    fail("laser layer npy: " + std::to_string(npy_bytes.size() - matrix.data_offset) +
         " data bytes, the shape needs " + std::to_string(count * sizeof(float)));
  }
  LogOddsRaster raster;
  raster.resolution = header.resolution;
  raster.origin_cell = header.origin_cell;
  raster.width = header.width;
  raster.height = header.height;
  raster.data.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t bits = littleEndian(npy_bytes, matrix.data_offset + 4 * i, 4);
    std::memcpy(&raster.data[i], &bits, sizeof(float));
    if (std::isinf(raster.data[i])) {
      fail("laser layer npy: cell [" + std::to_string(i / header.width) + ", " +
           std::to_string(i % header.width) + "] is infinite");
    }
  }
  return raster;
}

std::string readWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(std::string("cannot open: ") + std::strerror(errno));
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) fail("read error");
  return bytes;
}

}  // namespace

LayerFilePaths layerFilePaths(const std::string& prefix) {
  return {prefix + ".laser.yaml", prefix + ".laser.npy"};
}

namespace {

// The .npy's bytes go out in pieces; the CRC-32 follows them.
class ChecksummedOutput {
 public:
  explicit ChecksummedOutput(std::ostream& out) : out_(out) {}
  void write(const std::string& bytes) {
    crc_.process_bytes(bytes.data(), bytes.size());
    out_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  std::uint32_t checksum() const { return crc_.checksum(); }

 private:
  std::ostream& out_;
  boost::crc_32_type crc_;
};

void writeLayerYaml(const LayerFilePaths& paths, std::uint32_t npy_crc32, double resolution,
                    const CellIndex& origin_cell, int width, int height) {
  writeFileAtomically(paths.yaml, [&](std::ostream& out) {
    out << "# occupancy_fusion 2D laser layer: log-odds per cell in the .npy, NaN = unknown,\n"
        << "# array[y, x] is cell origin_cell + (x, y); row 0 is the lowest y.\n"
        << "log_odds: " << std::filesystem::path(paths.npy).filename().string() << "\n"
        << "log_odds_crc32: " << hexText(npy_crc32) << "  # of the whole .npy file\n"
        << "resolution: " << numberText(resolution) << "\n"
        << "origin_cell: [" << origin_cell.x() << ", " << origin_cell.y() << "]\n"
        << std::setprecision(15)  // origin is for readers: -23.4, not -23.400000000000002
        << "origin: [" << origin_cell.x() * resolution << ", " << origin_cell.y() * resolution
        << "]\n"
        << "width: " << width << "\n"
        << "height: " << height << "\n";
  });
}

}  // namespace

LayerFilePaths writeLayerFiles(const LogOddsRaster& raster, const std::string& prefix) {
  LayerFilePaths paths = layerFilePaths(prefix);
  const std::string npy_bytes = encodeNpy(raster);
  writeFileAtomically(paths.npy, [&](std::ostream& out) {
    out.write(npy_bytes.data(), static_cast<std::streamsize>(npy_bytes.size()));
  });
  writeLayerYaml(paths, crc32Of(npy_bytes), raster.resolution, raster.origin_cell, raster.width,
                 raster.height);
  return paths;
}

LayerFilePaths writeLayerFiles(const GridLayer2D& layer, const std::string& prefix) {
  LayerFilePaths paths = layerFilePaths(prefix);
  const std::optional<CellBox> box = layer.knownBounds();
  const CellIndex origin = box ? box->min : CellIndex::Zero();
  const int width = box ? box->width() : 0, height = box ? box->height() : 0;
  std::uint32_t crc = 0;
  writeFileAtomically(paths.npy, [&](std::ostream& out) {
    ChecksummedOutput npy(out);
    npy.write(npyFloatHeader(height, width));
    // One row of tiles at a time: a layer larger than memory (its tiles in the map's store) is
    // written holding one strip of the window.
    std::string bytes;
    for (int y = 0; y < height; y += GridTile::kSide) {
      const int rows = std::min(GridTile::kSide, height - y);
      bytes.clear();
      appendLittleEndianFloats(layer.window(origin + CellIndex(0, y), width, rows), &bytes);
      npy.write(bytes);
    }
    crc = npy.checksum();
  });
  writeLayerYaml(paths, crc, layer.resolution(), origin, width, height);
  return paths;
}

LogOddsRaster parseLayerFiles(const std::string& yaml_text, const std::string& npy_bytes) {
  return parseLayerArray(parseLayerYaml(yaml_text), npy_bytes);
}

LogOddsRaster readLayerFiles(const std::string& yaml_path) {
  LayerHeader header;
  try {
    header = parseLayerYaml(readWholeFile(yaml_path));
  } catch (const std::runtime_error& error) {
    fail(yaml_path + ": " + error.what());
  }
  std::filesystem::path npy_path(header.npy_name);
  if (npy_path.is_relative()) npy_path = std::filesystem::path(yaml_path).parent_path() / npy_path;
  try {
    return parseLayerArray(header, readWholeFile(npy_path.string()));
  } catch (const std::runtime_error& error) {
    fail(npy_path.string() + ": " + error.what());
  }
}

}  // namespace occupancy_fusion
