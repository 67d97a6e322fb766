// Simulated depth camera: a pinhole model rendered by ray casting one ray per pixel.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "occupancy_fusion/sensors/camera_intrinsics.h"
#include "occupancy_fusion/sim/scene.h"

namespace occupancy_fusion {
namespace sim {

// The simulator's cameras use the sensors' pinhole intrinsics, so a rendered image feeds the
// depth integrator directly. The ray of pixel (u, v) is ((u - cx) / fx, (v - cy) / fy, 1).
using PinholeCamera = CameraIntrinsics;

// The camera of the depth paper's synthetic experiments (Sec. 5.1): 400 x 400 pixels, focal
// length 400 px, principal point (200, 200).
PinholeCamera pirkerSyntheticCamera();

// Row-major image of z-depth in metres (the z coordinate in the optical frame, as a depth
// camera reports it, not the length of the ray); NaN where nothing was seen.
struct DepthImage {
  int width = 0;
  int height = 0;
  std::vector<float> depth;  // depth[v * width + u]

  float at(int u, int v) const { return depth[static_cast<std::size_t>(v) * width + u]; }
};

// Renders the scene as seen from T_world_camera (pose of the optical frame in the world).
// max_range (m) limits the z-depth: pixels whose surface lies farther away (or that see
// nothing) are NaN. Rows are rendered in parallel with OpenMP.
DepthImage renderDepth(const Scene& scene, const PinholeCamera& camera,
                       const Eigen::Isometry3d& T_world_camera, double max_range);

// The points of renderDepth's valid pixels, in the camera's optical frame, in row-major pixel
// order: pixel (u, v) with depth z gives z * camera.pixelRay(u, v). This is the input of the
// point-cloud mapper.
std::vector<Eigen::Vector3d> renderPointCloud(const Scene& scene, const PinholeCamera& camera,
                                              const Eigen::Isometry3d& T_world_camera,
                                              double max_range);

// The points of a depth image, in the camera's optical frame (NaN pixels skipped).
std::vector<Eigen::Vector3d> depthToPointCloud(const DepthImage& image,
                                               const PinholeCamera& camera);

}  // namespace sim
}  // namespace occupancy_fusion
