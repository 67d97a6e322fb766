#include "occupancy_fusion/sensors/seven_scenes_folder.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;
const std::string kDepthSuffix = ".depth.png";

std::string readFile(const fs::path& path) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error("cannot read " + path.string());
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

template <int N>
Eigen::Matrix<double, N, N> parseMatrix(const std::string& text, const std::string& what) {
  std::istringstream stream(text);
  Eigen::Matrix<double, N, N> matrix;
  for (int row = 0; row < N; ++row) {
    for (int col = 0; col < N; ++col) {
      if (!(stream >> matrix(row, col))) {
        throw std::runtime_error(what + ": expected " + std::to_string(N * N) + " numbers");
      }
    }
  }
  return matrix;
}

cv::Mat readDepthPng(const std::string& path) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_ANYDEPTH);
  if (image.empty()) throw std::runtime_error("cannot read depth image " + path);
  if (image.type() != CV_16UC1) {
    throw std::runtime_error(path + ": expected a 16-bit single-channel PNG (millimetres)");
  }
  return image;
}

}  // namespace

CameraIntrinsics parseCameraMatrix(const std::string& text, int width, int height) {
  const Eigen::Matrix3d K = parseMatrix<3>(text, "camera matrix");
  CameraIntrinsics camera;
  camera.width = width;
  camera.height = height;
  camera.fx = K(0, 0);
  camera.fy = K(1, 1);
  camera.cx = K(0, 2);
  camera.cy = K(1, 2);
  camera.validate();
  return camera;
}

Eigen::Isometry3d parsePoseMatrix(const std::string& text) {
  const Eigen::Matrix4d matrix = parseMatrix<4>(text, "pose matrix");
  if (!matrix.allFinite()) throw std::runtime_error("pose matrix: not finite");
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  // Nearest rotation: Isometry3d::inverse() transposes the linear part.
  pose.linear() = Eigen::Quaterniond(matrix.topLeftCorner<3, 3>()).normalized().toRotationMatrix();
  pose.translation() = matrix.topRightCorner<3, 1>();
  return pose;
}

SevenScenesFolder::SevenScenesFolder(const std::string& folder) {
  const fs::path root(folder);
  const fs::path frames = fs::is_directory(root / "frames") ? root / "frames" : root;
  if (!fs::is_directory(frames)) throw std::runtime_error("not a folder: " + folder);
  for (const fs::directory_entry& entry : fs::directory_iterator(frames)) {
    const std::string file = entry.path().filename().string();
    if (file.size() <= kDepthSuffix.size() ||
        file.compare(file.size() - kDepthSuffix.size(), kDepthSuffix.size(), kDepthSuffix) != 0) {
      continue;
    }
    const std::string name = file.substr(0, file.size() - kDepthSuffix.size());
    if (!fs::exists(frames / (name + ".pose.txt"))) continue;  // depth without pose: unusable
    names_.push_back(name);
  }
  if (names_.empty()) throw std::runtime_error(folder + ": no frame-*.depth.png with a pose");
  std::sort(names_.begin(), names_.end());
  for (const std::string& name : names_) stems_.push_back((frames / name).string());
  const cv::Mat first = readDepthPng(stems_.front() + kDepthSuffix);
  camera_ = parseCameraMatrix(readFile(root / "camera-intrinsics.txt"), first.cols, first.rows);
}

SevenScenesFrame SevenScenesFolder::frame(std::size_t index) const {
  const std::string& stem = stems_.at(index);
  const cv::Mat image = readDepthPng(stem + kDepthSuffix);
  if (image.cols != camera_.width || image.rows != camera_.height) {
    throw std::runtime_error(stem + kDepthSuffix + ": size differs from the first frame's");
  }
  SevenScenesFrame frame;
  frame.name = names_[index];
  frame.depth.resize(static_cast<std::size_t>(camera_.width) * camera_.height);
  for (int v = 0; v < camera_.height; ++v) {
    const std::vector<float> row =
        depthFromMillimetres(image.ptr<std::uint16_t>(v), static_cast<std::size_t>(camera_.width));
    std::copy(row.begin(), row.end(), frame.depth.begin() + static_cast<long>(v) * camera_.width);
  }
  try {
    frame.T_world_camera = parsePoseMatrix(readFile(stem + ".pose.txt"));
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(stem + ".pose.txt: " + error.what());
  }
  return frame;
}

}  // namespace occupancy_fusion
