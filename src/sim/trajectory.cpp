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

namespace {

// One piece of a rounded rectangle: a straight, or a left-turning arc of `radius`, entered at
// `start` with heading `yaw`.
struct LoopPiece {
  Eigen::Vector2d start;
  double yaw;
  double length;
  double radius;  // 0: straight

  Eigen::Vector2d positionAt(double d) const {
    if (radius == 0.0) return start + d * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
    const Eigen::Vector2d center = start + radius * Eigen::Vector2d(-std::sin(yaw), std::cos(yaw));
    const double angle = yaw + d / radius;
    return center + radius * Eigen::Vector2d(std::sin(angle), -std::cos(angle));
  }
  double yawAt(double d) const { return radius == 0.0 ? yaw : yaw + d / radius; }
};

// The pieces counter-clockwise from the bottom side's left end: straight, arc, per side.
std::vector<LoopPiece> roundedRectanglePieces(const Eigen::AlignedBox2d& rectangle, double radius) {
  const Eigen::Vector2d size = rectangle.sizes();
  if (!(radius > 0.0) || !(2.0 * radius <= size.minCoeff())) {
    throw std::invalid_argument(
        "roundedRectanglePath corner_radius must be > 0 and at most half the shorter side");
  }
  std::vector<LoopPiece> pieces;
  Eigen::Vector2d at(rectangle.min().x() + radius, rectangle.min().y());
  for (int side = 0; side < 4; ++side) {
    const double yaw = side * kPi / 2;
    pieces.push_back({at, yaw, size[side % 2] - 2.0 * radius, 0.0});
    pieces.push_back(
        {pieces.back().positionAt(pieces.back().length), yaw, kPi / 2 * radius, radius});
    at = pieces.back().positionAt(pieces.back().length);
  }
  return pieces;
}

}  // namespace

double roundedRectangleLength(const Eigen::AlignedBox2d& rectangle, double corner_radius) {
  double length = 0.0;
  for (const LoopPiece& piece : roundedRectanglePieces(rectangle, corner_radius)) {
    length += piece.length;
  }
  return length;
}

std::vector<Eigen::Isometry3d> roundedRectanglePath(const Eigen::AlignedBox2d& rectangle,
                                                    double corner_radius, double start_x,
                                                    double step_m, double laps) {
  const std::vector<LoopPiece> pieces = roundedRectanglePieces(rectangle, corner_radius);
  if (!(step_m > 0.0)) throw std::invalid_argument("roundedRectanglePath step_m must be > 0");
  if (!(laps >= 0.0) || !std::isfinite(laps)) {
    throw std::invalid_argument("roundedRectanglePath laps must be >= 0");
  }
  const double offset = start_x - pieces.front().start.x();
  if (!(offset >= 0.0 && offset <= pieces.front().length)) {
    throw std::invalid_argument(
        "roundedRectanglePath start_x must lie on the straight part of the bottom side");
  }
  const double length = roundedRectangleLength(rectangle, corner_radius);
  const auto count = static_cast<long>(std::floor(laps * length / step_m + 1e-9)) + 1;
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(count);
  for (long k = 0; k < count; ++k) {
    double d = std::fmod(offset + k * step_m, length);
    std::size_t i = 0;
    while (i + 1 < pieces.size() && d > pieces[i].length) d -= pieces[i++].length;
    const Eigen::Vector2d position = pieces[i].positionAt(d);
    poses.push_back(
        poseAt(Eigen::Vector3d(position.x(), position.y(), 0.0),
               Eigen::AngleAxisd(pieces[i].yawAt(d), Eigen::Vector3d::UnitZ()).toRotationMatrix()));
  }
  return poses;
}

}  // namespace sim
}  // namespace occupancy_fusion
