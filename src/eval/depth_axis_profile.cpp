#include "occupancy_fusion/eval/depth_axis_profile.h"

#include <algorithm>
#include <cmath>

namespace occupancy_fusion {
namespace {

constexpr double kResolution = 0.1;
constexpr int kSide = 400;

}  // namespace

AxisProfile fig5AxisProfile(DepthMethod method, double edge_offset, int finer_layers) {
  const bool half = std::abs(edge_offset - std::round(edge_offset)) > 0.25;
  CameraIntrinsics camera;
  camera.width = camera.height = kSide;
  camera.fx = camera.fy = 400.0;
  camera.cx = half ? 199.0 : 199.5;
  camera.cy = 199.5;
  // Pixels u < boundary see 6 m: the edge lies between columns boundary - 1 and boundary.
  const int boundary = static_cast<int>(std::lround(camera.cx + 0.5 + edge_offset));
  std::vector<float> depth(kSide * kSide);
  for (int v = 0; v < kSide; ++v) {
    for (int u = 0; u < kSide; ++u) depth[v * kSide + u] = u < boundary ? 6.0f : 10.0f;
  }
  PyramidDepthConfig config;  // k = sigma = 0.6, the paper's values
  config.method = method;
  config.max_range = 20.0;
  config.finer_layers = finer_layers;
  const PyramidDepthIntegrator integrator(config);
  // The camera sits at the centre of a voxel column, so the axis voxels are centred on it.
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  T_map_camera.translation() = Eigen::Vector3d(0.05, 0.05, 0.0);
  const DepthFrame frame =
      integrator.prepare({kSide, kSide, depth.data()}, camera, T_map_camera, kResolution);
  AxisProfile profile;
  for (int k = 1; k < 125; ++k) {
    const Eigen::Vector3d center(0.05, 0.05, (k + 0.5) * kResolution);
    profile.distance.push_back(center.z());
    profile.log_odds.push_back(integrator.voxelLogOdds(frame, center));
  }
  return profile;
}

double profileProbability(const std::optional<float>& log_odds) {
  return log_odds ? 1.0 / (1.0 + std::exp(-*log_odds)) : 0.5;
}

ProfileErrors errorsAgainstIdeal(const AxisProfile& ideal, const AxisProfile& method) {
  ProfileErrors errors;
  int count = 0;
  for (std::size_t i = 0; i < ideal.log_odds.size(); ++i) {
    if (!ideal.log_odds[i]) continue;
    const double error =
        std::abs(profileProbability(method.log_odds[i]) - profileProbability(ideal.log_odds[i]));
    errors.mean += error;
    errors.max = std::max(errors.max, error);
    ++count;
  }
  errors.mean /= std::max(count, 1);
  return errors;
}

}  // namespace occupancy_fusion
