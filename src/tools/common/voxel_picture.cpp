#include "occupancy_fusion/tools/voxel_picture.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

namespace occupancy_fusion {
namespace {

// The view's axes in the map frame: right, up (in the picture) and forward (into it).
struct ViewAxes {
  Eigen::Vector3d right, up, forward;
};

ViewAxes viewAxes(double yaw, double pitch) {
  ViewAxes axes;
  axes.forward = Eigen::Vector3d(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                                 -std::sin(pitch));
  axes.right = axes.forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  axes.up = axes.right.cross(axes.forward);
  return axes;
}

// OpenCV's TURBO colour map as a 256-entry table (blue = 0, red = 255).
cv::Mat turboTable() {
  cv::Mat levels(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) levels.at<std::uint8_t>(0, i) = static_cast<std::uint8_t>(i);
  cv::Mat table;
  cv::applyColorMap(levels, table, cv::COLORMAP_TURBO);
  return table;
}

}  // namespace

void VoxelPictureConfig::validate() const {
  if (width < 16) throw std::invalid_argument("VoxelPictureConfig.width must be >= 16");
  if (height < 16) throw std::invalid_argument("VoxelPictureConfig.height must be >= 16");
  if (!(pitch > 0.0 && pitch < M_PI / 2)) {
    throw std::invalid_argument("VoxelPictureConfig.pitch must be in (0, pi/2)");
  }
  if (!std::isfinite(yaw)) throw std::invalid_argument("VoxelPictureConfig.yaw must be finite");
  if (!(min_z < max_z)) throw std::invalid_argument("VoxelPictureConfig.min_z must be < max_z");
}

VoxelPicture renderOccupiedVoxels(const VoxelMap& map, const VoxelPictureConfig& config) {
  config.validate();
  std::vector<Eigen::Vector3d> centres;
  map.forEachOccupiedVoxel([&](const VoxelIndex& index, float) {
    const Eigen::Vector3d centre = map.centerOf(index);
    if (centre.z() >= config.min_z && centre.z() <= config.max_z) centres.push_back(centre);
  });
  VoxelPicture picture;
  picture.image = cv::Mat(config.height, config.width, CV_8UC3, cv::Scalar(255, 255, 255));
  picture.voxels = centres.size();
  if (centres.empty()) return picture;
  const ViewAxes axes = viewAxes(config.yaw, config.pitch);
  // Picture-plane extent and height range of the voxels.
  double u_min = std::numeric_limits<double>::infinity(), u_max = -u_min;
  double v_min = u_min, v_max = -u_min, z_min = u_min, z_max = -u_min;
  for (const Eigen::Vector3d& c : centres) {
    u_min = std::min(u_min, c.dot(axes.right)), u_max = std::max(u_max, c.dot(axes.right));
    v_min = std::min(v_min, c.dot(axes.up)), v_max = std::max(v_max, c.dot(axes.up));
    z_min = std::min(z_min, c.z()), z_max = std::max(z_max, c.z());
  }
  const double margin = 0.05;
  const double scale = std::min((1 - 2 * margin) * config.width / std::max(u_max - u_min, 1e-3),
                                (1 - 2 * margin) * config.height / std::max(v_max - v_min, 1e-3));
  const double u_centre = 0.5 * (u_min + u_max), v_centre = 0.5 * (v_min + v_max);
  // Painter's order: far voxels first, near ones drawn over them.
  std::sort(centres.begin(), centres.end(),
            [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
              return a.dot(axes.forward) > b.dot(axes.forward);
            });
  const double half = std::max(0.5, 0.5 * map.resolution() * scale);
  const cv::Mat table = turboTable();
  for (const Eigen::Vector3d& c : centres) {
    const double x = 0.5 * config.width + (c.dot(axes.right) - u_centre) * scale;
    const double y = 0.5 * config.height - (c.dot(axes.up) - v_centre) * scale;
    const double fraction = std::clamp((c.z() - z_min) / std::max(z_max - z_min, 1e-6), 0.0, 1.0);
    const cv::Vec3b colour = table.at<cv::Vec3b>(0, static_cast<int>(std::lround(255 * fraction)));
    const cv::Rect square(
        cv::Point(static_cast<int>(std::lround(x - half)), static_cast<int>(std::lround(y - half))),
        cv::Point(static_cast<int>(std::lround(x + half)) + 1,
                  static_cast<int>(std::lround(y + half)) + 1));
    cv::rectangle(picture.image, square, cv::Scalar(colour[0], colour[1], colour[2]), cv::FILLED);
    if (half >= 2.0) {
      cv::rectangle(picture.image, square,
                    cv::Scalar(colour[0] * 0.6, colour[1] * 0.6, colour[2] * 0.6), 1);
    }
  }
  return picture;
}

}  // namespace occupancy_fusion
