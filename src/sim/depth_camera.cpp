#include "occupancy_fusion/sim/depth_camera.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace occupancy_fusion {
namespace sim {
namespace {

void requireMaxRange(double max_range) {
  if (!(max_range > 0)) throw std::invalid_argument("max_range must be positive");
}

}  // namespace

PinholeCamera pirkerSyntheticCamera() {
  PinholeCamera camera;
  camera.width = 400;
  camera.height = 400;
  camera.fx = camera.fy = 400.0;
  camera.cx = camera.cy = 200.0;
  return camera;
}

DepthImage renderDepth(const Scene& scene, const PinholeCamera& camera,
                       const Eigen::Isometry3d& T_world_camera, double max_range) {
  camera.validate();
  requireMaxRange(max_range);
  DepthImage image;
  image.width = camera.width;
  image.height = camera.height;
  image.depth.assign(static_cast<std::size_t>(camera.width) * camera.height,
                     std::numeric_limits<float>::quiet_NaN());
  const Eigen::Matrix3d R_world_camera = T_world_camera.linear();
  const Eigen::Vector3d origin = T_world_camera.translation();
#pragma omp parallel for schedule(dynamic, 4)
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d ray = camera.pixelRay(u, v);
      const double length_per_z = ray.norm();  // ray length per metre of z-depth
      const std::optional<double> t =
          scene.castRay(origin, R_world_camera * (ray / length_per_z), max_range * length_per_z);
      if (t) image.depth[static_cast<std::size_t>(v) * camera.width + u] = *t / length_per_z;
    }
  }
  return image;
}

std::vector<Eigen::Vector3d> depthToPointCloud(const DepthImage& image,
                                               const PinholeCamera& camera) {
  if (image.width != camera.width || image.height != camera.height) {
    throw std::invalid_argument("depthToPointCloud: image size differs from the camera's");
  }
  std::vector<Eigen::Vector3d> points;
  points.reserve(image.depth.size());
  for (int v = 0; v < image.height; ++v) {
    for (int u = 0; u < image.width; ++u) {
      const float z = image.at(u, v);
      if (std::isfinite(z)) points.push_back(z * camera.pixelRay(u, v));
    }
  }
  return points;
}

std::vector<Eigen::Vector3d> renderPointCloud(const Scene& scene, const PinholeCamera& camera,
                                              const Eigen::Isometry3d& T_world_camera,
                                              double max_range) {
  return depthToPointCloud(renderDepth(scene, camera, T_world_camera, max_range), camera);
}

}  // namespace sim
}  // namespace occupancy_fusion
