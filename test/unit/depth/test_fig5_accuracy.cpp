// The paper's Fig. 2 / Fig. 5 setup: a 400 x 400 camera (f = 400) facing obstacles at 6 m and
// 10 m, r = 0.1 m, k = sigma = 0.6. Occupancy along the optical axis for the ideal model
// (Eq. 8-9), the pyramid (Eq. 10-17) and Andert's scheme; the pyramid must be clearly closer
// to the ideal than Andert.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include "occupancy_fusion/integrators/pyramid_depth_integrator.h"

namespace occupancy_fusion {
namespace {

constexpr double kResolution = 0.1;

struct Profile {
  std::vector<double> distance;
  std::vector<std::optional<float>> log_odds;
};

// Pixels u < boundary see a wall at z-depth 6 m, the others one at 10 m. The principal point
// lies between pixels 199 and 200, so with boundary = 200 the edge runs along the optical axis
// and the voxels on the axis see both obstacles, as the green voxel of Fig. 2a.
Profile axisProfile(DepthMethod method, int boundary) {
  CameraIntrinsics camera;
  camera.width = camera.height = 400;
  camera.fx = camera.fy = 400.0;
  camera.cx = camera.cy = 199.5;
  std::vector<float> depth(400 * 400);
  for (int v = 0; v < 400; ++v) {
    for (int u = 0; u < 400; ++u) depth[v * 400 + u] = u < boundary ? 6.0f : 10.0f;
  }
  PyramidDepthConfig config;  // k = sigma = 0.6
  config.method = method;
  config.max_range = 20.0;
  const PyramidDepthIntegrator integrator(config);
  // The camera sits at the centre of a voxel column in x and y: the map's voxels on the axis
  // are centred on it, at z = 0.05 + 0.1 k.
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  T_map_camera.translation() = Eigen::Vector3d(0.05, 0.05, 0.0);
  const DepthFrame frame =
      integrator.prepare({400, 400, depth.data()}, camera, T_map_camera, kResolution);
  Profile profile;
  for (int k = 1; k < 125; ++k) {  // 0.15 ... 12.35 m
    const Eigen::Vector3d center(0.05, 0.05, (k + 0.5) * kResolution);
    profile.distance.push_back(center.z());
    profile.log_odds.push_back(integrator.voxelLogOdds(frame, center));
  }
  return profile;
}

double probability(const std::optional<float>& log_odds) {  // Eq. 5; unknown reads as 0.5
  return log_odds ? 1.0 / (1.0 + std::exp(-*log_odds)) : 0.5;
}

struct Errors {
  double mean = 0.0;
  double max = 0.0;
};

// Absolute occupancy-probability error against the ideal over the voxels the ideal observes.
Errors errorsAgainst(const Profile& ideal, const Profile& method) {
  Errors errors;
  int count = 0;
  for (std::size_t i = 0; i < ideal.log_odds.size(); ++i) {
    if (!ideal.log_odds[i]) continue;
    const double error = std::abs(probability(method.log_odds[i]) - probability(ideal.log_odds[i]));
    errors.mean += error;
    errors.max = std::max(errors.max, error);
    ++count;
  }
  errors.mean /= std::max(count, 1);
  return errors;
}

void printProfiles(const Profile& ideal, const Profile& pyramid, const Profile& andert) {
  std::printf("  z [m]   ideal  pyramid  andert\n");
  for (std::size_t i = 4; i < ideal.distance.size(); i += 5) {
    std::printf("  %5.2f   %.3f  %.3f    %.3f\n", ideal.distance[i], probability(ideal.log_odds[i]),
                probability(pyramid.log_odds[i]), probability(andert.log_odds[i]));
  }
}

std::optional<float> valueAt(const Profile& profile, double z) {
  const auto it =
      std::min_element(profile.distance.begin(), profile.distance.end(),
                       [z](double a, double b) { return std::abs(a - z) < std::abs(b - z); });
  return profile.log_odds[it - profile.distance.begin()];
}

TEST(Fig5Accuracy, IdealProfileAveragesBothObstaclesOnTheAxis) {
  // With the edge on the axis, half of each axis voxel's rays meet 6 m and half 10 m, with
  // equal lengths inside the voxel, so Eq. 8 is the mean of the two Eq. 7 log-odds (Fig. 2b);
  // beyond 10 m + 3 sigma the voxel stays unknown.
  const Profile ideal = axisProfile(DepthMethod::kIdeal, 200);
  const DepthInverseModel model{PyramidDepthConfig()};
  for (double z : {2.05, 5.55, 6.05, 8.45, 9.95, 11.05}) {
    const std::optional<float> value = valueAt(ideal, z);
    ASSERT_TRUE(value.has_value()) << z;
    EXPECT_NEAR(*value, 0.5 * (model.logOdds(z, 6.0) + model.logOdds(z, 10.0)), 2e-3) << z;
  }
  EXPECT_FALSE(valueAt(ideal, 11.95).has_value());
}

TEST(Fig5Accuracy, PyramidIsClearlyCloserToIdealThanAndert) {
  // The paper's setup: the edge between the obstacles on the optical axis. (An edge a few
  // pixels off the axis is another matter: the pyramid's coarse layer, two cells of up to four
  // times the voxel's footprint, then also sees the obstacle beside the voxel, and Andert's
  // single cell can be closer to the ideal.)
  const Profile ideal = axisProfile(DepthMethod::kIdeal, 200);
  const Profile pyramid = axisProfile(DepthMethod::kPyramid, 200);
  const Profile andert = axisProfile(DepthMethod::kAndert, 200);
  const Errors pyramid_errors = errorsAgainst(ideal, pyramid);
  const Errors andert_errors = errorsAgainst(ideal, andert);
  std::printf("Fig. 5: |p - p_ideal| over %zu axis voxels from 0.15 m\n", ideal.distance.size());
  std::printf("  pyramid: mean %.4f max %.4f\n", pyramid_errors.mean, pyramid_errors.max);
  std::printf("  andert:  mean %.4f max %.4f\n", andert_errors.mean, andert_errors.max);
  printProfiles(ideal, pyramid, andert);
  EXPECT_LT(pyramid_errors.mean, 0.1 * andert_errors.mean);
  EXPECT_LT(pyramid_errors.max, 0.1 * andert_errors.max);
  EXPECT_GT(andert_errors.mean, 0.05);  // the baseline really misses the far obstacle
}

}  // namespace
}  // namespace occupancy_fusion
