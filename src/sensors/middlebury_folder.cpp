#include "occupancy_fusion/sensors/middlebury_folder.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "occupancy_fusion/sensors/seven_scenes_folder.h"  // parsePoseMatrix

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

const std::string kDisparityPrefix = "disp0";
const std::string kGroundTruthMarker = "GT";

std::string readBinaryFile(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error("cannot read " + path);
  std::stringstream bytes;
  bytes << file.rdbuf();
  return bytes.str();
}

bool startsWith(const std::string& text, const std::string& prefix) {
  return text.compare(0, prefix.size(), prefix) == 0;
}

bool endsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// --- PFM ---------------------------------------------------------------------------------------

// Reads the next white-space separated token of the header from position *at.
std::string nextHeaderToken(const std::string& bytes, std::size_t* at) {
  while (*at < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[*at]))) ++*at;
  const std::size_t begin = *at;
  while (*at < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[*at]))) ++*at;
  if (begin == *at) throw std::runtime_error("PFM: header ends early");
  return bytes.substr(begin, *at - begin);
}

int positiveHeaderInt(const std::string& token, const char* what) {
  std::size_t used = 0;
  long value = 0;
  try {
    value = std::stol(token, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != token.size() || value < 1 || value > (1 << 20)) {
    throw std::runtime_error(std::string("PFM: bad ") + what + " '" + token + "'");
  }
  return static_cast<int>(value);
}

// The float whose four bytes start at data, in the file's byte order (independent of the host's).
float decodeFloat(const unsigned char* data, bool little_endian) {
  std::uint32_t bits = 0;
  for (int i = 0; i < 4; ++i) {
    const int shift = little_endian ? 8 * i : 8 * (3 - i);
    bits |= static_cast<std::uint32_t>(data[i]) << shift;
  }
  float value;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

// --- calib.txt ---------------------------------------------------------------------------------

// "key=value" pairs; a value is a bracketed matrix or one token. Keys and values may be separated
// from "=" by white space, and entries by spaces or new lines (the files mix both).
std::map<std::string, std::string> calibrationEntries(const std::string& text) {
  std::map<std::string, std::string> entries;
  std::size_t at = 0;
  const auto skipSpace = [&] {
    while (at < text.size() && std::isspace(static_cast<unsigned char>(text[at]))) ++at;
  };
  while (true) {
    skipSpace();
    if (at >= text.size()) break;
    const std::size_t equals = text.find('=', at);
    if (equals == std::string::npos) {
      throw std::runtime_error("calib.txt: expected key=value near '" + text.substr(at, 20) + "'");
    }
    std::string key = text.substr(at, equals - at);
    while (!key.empty() && std::isspace(static_cast<unsigned char>(key.back()))) key.pop_back();
    if (key.empty() || key.find_first_of(" \t\r\n") != std::string::npos) {
      throw std::runtime_error("calib.txt: bad key '" + key + "'");
    }
    at = equals + 1;
    skipSpace();
    std::size_t end = at;
    if (at < text.size() && text[at] == '[') {
      end = text.find(']', at);
      if (end == std::string::npos) throw std::runtime_error("calib.txt: " + key + ": missing ]");
      ++end;
    } else {
      while (end < text.size() && !std::isspace(static_cast<unsigned char>(text[end]))) ++end;
    }
    entries[key] = text.substr(at, end - at);
    at = end;
  }
  return entries;
}

double numberEntry(const std::map<std::string, std::string>& entries, const std::string& key) {
  const std::string& token = entries.at(key);
  std::size_t used = 0;
  double value = std::numeric_limits<double>::quiet_NaN();
  try {
    value = std::stod(token, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != token.size() || !std::isfinite(value)) {
    throw std::runtime_error("calib.txt: " + key + ": not a number: '" + token + "'");
  }
  return value;
}

// "[ fx 0 cx ; 0 fy cy ; 0 0 1 ]" -> the 3 x 3 matrix.
Eigen::Matrix3d matrixEntry(const std::map<std::string, std::string>& entries,
                            const std::string& key) {
  std::string text = entries.at(key);
  if (text.size() < 2 || text.front() != '[' || text.back() != ']') {
    throw std::runtime_error("calib.txt: " + key + ": expected [ ... ; ... ; ... ]");
  }
  std::replace(text.begin(), text.end(), ';', ' ');
  std::istringstream stream(text.substr(1, text.size() - 2));
  Eigen::Matrix3d matrix;
  for (int i = 0; i < 9; ++i) {
    if (!(stream >> matrix(i / 3, i % 3))) {
      throw std::runtime_error("calib.txt: " + key + ": expected 9 numbers");
    }
  }
  std::string rest;
  if (stream >> rest) throw std::runtime_error("calib.txt: " + key + ": more than 9 numbers");
  return matrix;
}

}  // namespace

// --- PFM ---------------------------------------------------------------------------------------

PfmImage parsePfm(const std::string& bytes) {
  std::size_t at = 0;
  const std::string magic = nextHeaderToken(bytes, &at);
  PfmImage image;
  if (magic == "Pf") {
    image.channels = 1;
  } else if (magic == "PF") {
    image.channels = 3;
  } else {
    throw std::runtime_error("PFM: expected Pf or PF, got '" + magic.substr(0, 8) + "'");
  }
  image.width = positiveHeaderInt(nextHeaderToken(bytes, &at), "width");
  image.height = positiveHeaderInt(nextHeaderToken(bytes, &at), "height");
  const std::string scale_token = nextHeaderToken(bytes, &at);
  double scale = 0.0;
  try {
    scale = std::stod(scale_token);
  } catch (const std::exception&) {
    scale = 0.0;
  }
  if (!(std::isfinite(scale) && scale != 0.0)) {
    throw std::runtime_error("PFM: bad scale '" + scale_token +
                             "' (its sign gives the byte order)");
  }
  const bool little_endian = scale < 0.0;
  ++at;  // the single white-space byte that ends the header

  const std::size_t row_values = static_cast<std::size_t>(image.width) * image.channels;
  const std::size_t count = row_values * image.height;
  if (at > bytes.size() || bytes.size() - at < 4 * count) {
    throw std::runtime_error("PFM: expected " + std::to_string(4 * count) + " bytes of data");
  }
  image.values.resize(count);
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data() + at);
  for (int stored_row = 0; stored_row < image.height; ++stored_row) {
    const int v = image.height - 1 - stored_row;  // stored bottom to top
    for (std::size_t i = 0; i < row_values; ++i) {
      image.values[v * row_values + i] =
          decodeFloat(data + 4 * (stored_row * row_values + i), little_endian);
    }
  }
  return image;
}

PfmImage readPfm(const std::string& path) {
  try {
    return parsePfm(readBinaryFile(path));
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(path + ": " + error.what());
  }
}

// --- calib.txt ---------------------------------------------------------------------------------

StereoCamera MiddleburyCalibration::camera() const {
  StereoCamera camera;
  camera.fx = fx;
  camera.fy = fy;
  camera.cx = cx0;
  camera.cy = cy0;
  camera.baseline = baseline_m;
  camera.validate();
  return camera;
}

MiddleburyCalibration parseMiddleburyCalibration(const std::string& text) {
  const std::map<std::string, std::string> entries = calibrationEntries(text);
  for (const char* required : {"cam0", "baseline"}) {
    if (entries.count(required) == 0) {
      throw std::runtime_error(std::string("calib.txt: missing ") + required);
    }
  }
  const auto optionalNumber = [&](const std::string& key, double fallback) {
    return entries.count(key) != 0 ? numberEntry(entries, key) : fallback;
  };
  MiddleburyCalibration calibration;
  const Eigen::Matrix3d K0 = matrixEntry(entries, "cam0");
  calibration.fx = K0(0, 0);
  calibration.fy = K0(1, 1);
  calibration.cx0 = K0(0, 2);
  calibration.cy0 = K0(1, 2);
  calibration.cx1 =
      entries.count("cam1") != 0 ? matrixEntry(entries, "cam1")(0, 2) : calibration.cx0;
  calibration.doffs = optionalNumber("doffs", calibration.cx1 - calibration.cx0);
  calibration.baseline_m = 1e-3 * numberEntry(entries, "baseline");
  // Checked before the conversion to int, which is undefined for values out of its range.
  const auto optionalCount = [&](const std::string& key) {
    const double value = optionalNumber(key, 0.0);
    if (!(value >= 0.0 && value <= std::numeric_limits<int>::max())) {
      throw std::runtime_error("calib.txt: " + key + " must be a count of pixels, got " +
                               entries.at(key));
    }
    return static_cast<int>(value);
  };
  calibration.width = optionalCount("width");
  calibration.height = optionalCount("height");
  calibration.ndisp = optionalCount("ndisp");
  calibration.vmin = optionalNumber("vmin", 0.0);
  calibration.vmax = optionalNumber("vmax", 0.0);
  if (!(calibration.fx > 0.0 && calibration.fy > 0.0)) {
    throw std::runtime_error("calib.txt: cam0: focal length must be positive");
  }
  if (!(calibration.baseline_m > 0.0)) {
    throw std::runtime_error("calib.txt: baseline must be positive");
  }
  if (calibration.width < 0 || calibration.height < 0) {
    throw std::runtime_error("calib.txt: width and height must not be negative");
  }
  return calibration;
}

MiddleburyCalibration readMiddleburyCalibration(const std::string& path) {
  try {
    return parseMiddleburyCalibration(readBinaryFile(path));
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(path + ": " + error.what());
  }
}

// --- Scene folders -----------------------------------------------------------------------------

std::string middleburyViewId(const std::string& disparity_stem) {
  if (!startsWith(disparity_stem, kDisparityPrefix)) {
    throw std::invalid_argument("not a left-image disparity name: " + disparity_stem);
  }
  std::string id = disparity_stem.substr(kDisparityPrefix.size());
  if (endsWith(id, kGroundTruthMarker)) id.resize(id.size() - kGroundTruthMarker.size());
  return id;
}

MiddleburyFolder::MiddleburyFolder(const std::string& folder) : folder_(folder) {
  if (!fs::is_directory(folder)) throw std::runtime_error("not a folder: " + folder);
  calibration_ = readMiddleburyCalibration((fs::path(folder) / "calib.txt").string());
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    const std::string file = entry.path().filename().string();
    if (entry.is_regular_file() && startsWith(file, kDisparityPrefix) && endsWith(file, ".pfm")) {
      names_.push_back(entry.path().stem().string());
    }
  }
  if (names_.empty()) throw std::runtime_error(folder + ": no disp0*.pfm");
  std::sort(names_.begin(), names_.end());
}

std::string MiddleburyFolder::siblingPath(std::size_t index, const std::string& prefix,
                                          const std::string& extension) const {
  const fs::path path = fs::path(folder_) / (prefix + middleburyViewId(name(index)) + extension);
  return fs::exists(path) ? path.string() : std::string();
}

std::string MiddleburyFolder::leftImagePath(std::size_t index) const {
  return siblingPath(index, "im0", ".png");
}

std::string MiddleburyFolder::rightImagePath(std::size_t index) const {
  return siblingPath(index, "im1", ".png");
}

MiddleburyFrame MiddleburyFolder::frame(std::size_t index) const {
  const std::string path = (fs::path(folder_) / (name(index) + ".pfm")).string();
  PfmImage image = readPfm(path);
  if (image.channels != 1) throw std::runtime_error(path + ": expected a 1-channel (Pf) map");
  if ((calibration_.width > 0 && image.width != calibration_.width) ||
      (calibration_.height > 0 && image.height != calibration_.height)) {
    throw std::runtime_error(path + ": size " + std::to_string(image.width) + "x" +
                             std::to_string(image.height) + " differs from calib.txt's");
  }
  MiddleburyFrame frame;
  frame.name = name(index);
  frame.width = image.width;
  frame.height = image.height;
  frame.disparity = std::move(image.values);
  const float doffs = static_cast<float>(calibration_.doffs);
  for (float& d : frame.disparity) {
    // inf marks unknown; the ROS convention (and disparityToPoints) wants a non-finite value.
    d = std::isfinite(d) ? d + doffs : std::numeric_limits<float>::quiet_NaN();
  }
  const std::string pose_path = siblingPath(index, "pose0", ".txt");
  if (!pose_path.empty()) {
    try {
      frame.T_world_camera = parsePoseMatrix(readBinaryFile(pose_path));
    } catch (const std::runtime_error& error) {
      throw std::runtime_error(pose_path + ": " + error.what());
    }
  }
  return frame;
}

std::vector<std::string> findMiddleburyScenes(const std::string& path) {
  const fs::path root(path);
  if (fs::exists(root / "calib.txt")) return {root.string()};
  std::vector<std::string> scenes;
  if (fs::is_directory(root)) {
    for (const fs::directory_entry& entry : fs::directory_iterator(root)) {
      if (entry.is_directory() && fs::exists(entry.path() / "calib.txt")) {
        scenes.push_back(entry.path().string());
      }
    }
  }
  if (scenes.empty()) throw std::runtime_error(path + ": no calib.txt in it or its sub-folders");
  std::sort(scenes.begin(), scenes.end());
  return scenes;
}

}  // namespace occupancy_fusion
