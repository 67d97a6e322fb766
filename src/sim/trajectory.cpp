#include "occupancy_fusion/sim/trajectory.h"

#include <cmath>
#include <stdexcept>

namespace occupancy_fusion {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

void requireCount(int n, int minimum) {
  if (n < minimum) {
    throw std::invalid_argument("trajectory pose count n must be >= " + std::to_string(minimum));
  }
}

Eigen::Isometry3d poseAt(const Eigen::Vector3d& position, const Eigen::Matrix3d& rotation) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation;
  pose.translation() = position;
  return pose;
}

}  // namespace

Eigen::Isometry3d opticalFrameInBody() {
  Eigen::Matrix3d R_body_optical;
  // Columns: optical x (right) = body -y, optical y (down) = body -z, optical z = body +x.
  R_body_optical << 0, 0, 1,  //
      -1, 0, 0,               //
      0, -1, 0;
  return poseAt(Eigen::Vector3d::Zero(), R_body_optical);
}

Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                         const Eigen::Vector3d& up) {
  const Eigen::Vector3d forward = target - eye;
  if (!(forward.norm() > 0)) throw std::invalid_argument("lookAt: target equals eye");
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d right = z.cross(up);
  if (!(right.norm() > 1e-9)) throw std::invalid_argument("lookAt: view direction parallel to up");
  const Eigen::Vector3d x = right.normalized();
  Eigen::Matrix3d rotation;
  rotation.col(0) = x;
  rotation.col(1) = z.cross(x);  // down
  rotation.col(2) = z;
  return poseAt(eye, rotation);
}

std::vector<Eigen::Isometry3d> orbitTrajectory(const Eigen::Vector3d& center, double radius,
                                               double height, int n,
                                               const Eigen::Vector3d& look_at) {
  requireCount(n, 1);
  if (!(radius > 0)) throw std::invalid_argument("orbitTrajectory radius must be positive");
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(n);
  for (int k = 0; k < n; ++k) {
    const double angle = 2 * kPi * k / n;
    const Eigen::Vector3d eye =
        center + Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), height);
    poses.push_back(lookAt(eye, look_at));
  }
  return poses;
}

std::vector<Eigen::Isometry3d> rotationSweep(const Eigen::Vector3d& position, int n,
                                             double step_deg,
                                             const Eigen::Matrix3d& R_world_start) {
  requireCount(n, 1);
  const double step = step_deg * kPi / 180.0;
  const int about_x = n / 2;  // ceil((n - 1) / 2)
  std::vector<Eigen::Isometry3d> poses{poseAt(position, R_world_start)};
  for (int k = 1; k < n; ++k) {
    const bool first_axis = k <= about_x;
    const int steps = first_axis ? k : k - about_x;
    const Eigen::Vector3d axis = first_axis ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    // Right-multiplied: a turn about the camera's own axis.
    poses.push_back(
        poseAt(position, R_world_start * Eigen::AngleAxisd(steps * step, axis).toRotationMatrix()));
  }
  return poses;
}

std::vector<Eigen::Isometry3d> straightLinePath(const Eigen::Vector3d& start,
                                                const Eigen::Vector3d& end, int n, double yaw_start,
                                                double yaw_end) {
  requireCount(n, 2);
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(n);
  for (int k = 0; k < n; ++k) {
    const double s = static_cast<double>(k) / (n - 1);
    const double yaw = yaw_start + s * (yaw_end - yaw_start);
    poses.push_back(poseAt(start + s * (end - start),
                           Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix()));
  }
  return poses;
}

}  // namespace sim
}  // namespace occupancy_fusion
