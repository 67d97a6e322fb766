// Reader of depth recordings in the Microsoft 7-Scenes folder layout:
//   <folder>/camera-intrinsics.txt            3 x 3 K of the depth camera
//   <folder>/frames/frame-NNNNNN.depth.png    16-bit depth in millimetres, 0 = invalid
//   <folder>/frames/frame-NNNNNN.pose.txt     4 x 4 camera-to-world transform, metres
// (the frame files may also lie directly in <folder>). ROS-free, for the offline mapper and the
// benchmark.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

#include "occupancy_fusion/sensors/depth_image.h"

namespace occupancy_fusion {

struct SevenScenesFrame {
  std::string name;          // "frame-000150"
  std::vector<float> depth;  // z-depth in metres, row-major, 0 = no measurement
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // optical frame in world

  DepthImageView view(const CameraIntrinsics& camera) const {
    return {camera.width, camera.height, depth.data(), 0};
  }
};

class SevenScenesFolder {
 public:
  // Reads the intrinsics and lists the frames that have both a depth image and a pose, in the
  // order of their names. Throws std::runtime_error naming the file that is missing or bad.
  explicit SevenScenesFolder(const std::string& folder);

  const CameraIntrinsics& camera() const { return camera_; }
  std::size_t size() const { return stems_.size(); }
  const std::string& name(std::size_t index) const { return names_.at(index); }
  // Loads one frame. The pose's rotation is re-orthonormalised (the files' matrices are
  // orthonormal to about 1e-4 only); the image size is checked against the intrinsics.
  SevenScenesFrame frame(std::size_t index) const;

 private:
  CameraIntrinsics camera_;
  std::vector<std::string> stems_;  // paths without ".depth.png"
  std::vector<std::string> names_;
};

// Parses a 3 x 3 camera matrix (9 numbers) into intrinsics of the given image size.
CameraIntrinsics parseCameraMatrix(const std::string& text, int width, int height);
// Parses a 4 x 4 row-major homogeneous transform (16 numbers), rotation re-orthonormalised.
Eigen::Isometry3d parsePoseMatrix(const std::string& text);

}  // namespace occupancy_fusion
