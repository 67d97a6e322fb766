#include "occupancy_fusion/sim/odometry_drift.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "occupancy_fusion/sim/deterministic_random.h"

namespace occupancy_fusion {
namespace sim {
namespace {

// Keys of the noise components of one step, so each draws its own sequence.
enum NoiseComponent : std::uint64_t { kAlong = 1, kAcross = 2, kHeading = 3 };

void requireNonNegative(const char* name, double value) {
  if (!(value >= 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string("odometry drift ") + name + " must be >= 0");
  }
}

}  // namespace

OdometryDriftConfig OdometryDriftConfig::scaled(double factor) const {
  requireNonNegative("scale factor", factor);
  OdometryDriftConfig result = *this;
  result.translation_noise *= factor;
  result.scale_error *= factor;
  result.heading_drift *= factor;
  result.heading_noise *= factor;
  return result;
}

void OdometryDriftConfig::validate() const {
  requireNonNegative("translation_noise", translation_noise);
  requireNonNegative("heading_noise", heading_noise);
  // Signed: a bias either way; a scale error of -1 or less would reverse the motion.
  if (!(scale_error > -1.0) || !std::isfinite(scale_error)) {
    throw std::invalid_argument("odometry drift scale_error must be > -1");
  }
  if (!std::isfinite(heading_drift)) {
    throw std::invalid_argument("odometry drift heading_drift must be finite");
  }
}

double yawOf(const Eigen::Isometry3d& pose) {
  return std::atan2(pose.linear()(1, 0), pose.linear()(0, 0));
}

std::vector<Eigen::Isometry3d> driftedOdometry(
    const std::vector<Eigen::Isometry3d>& T_map_base_truth, const OdometryDriftConfig& config) {
  config.validate();
  std::vector<Eigen::Isometry3d> odometry;
  odometry.reserve(T_map_base_truth.size());
  if (T_map_base_truth.empty()) return odometry;
  // The planar state is integrated on its own; the pose then takes the truth's z, roll and pitch.
  Eigen::Vector2d position = T_map_base_truth.front().translation().head<2>();
  double yaw = yawOf(T_map_base_truth.front());
  odometry.push_back(T_map_base_truth.front());
  for (std::size_t k = 1; k < T_map_base_truth.size(); ++k) {
    const Eigen::Isometry3d& previous = T_map_base_truth[k - 1];
    const Eigen::Isometry3d& current = T_map_base_truth[k];
    const double true_yaw = yawOf(previous);
    // The true step in the previous body's heading frame, as wheels measure it.
    const Eigen::Vector2d step =
        Eigen::Rotation2Dd(-true_yaw) * (current.translation() - previous.translation()).head<2>();
    const double turn = std::remainder(yawOf(current) - true_yaw, 2.0 * M_PI);
    const double distance = step.norm();
    const double root = std::sqrt(distance);
    auto normal = [&](NoiseComponent component) {
      return standardNormal(hashKey({config.seed, k, component}));
    };
    const Eigen::Vector2d measured =
        (1.0 + config.scale_error) * step +
        config.translation_noise * root * Eigen::Vector2d(normal(kAlong), normal(kAcross));
    const double measured_turn =
        turn + config.heading_drift * distance + config.heading_noise * root * normal(kHeading);
    position += Eigen::Rotation2Dd(yaw) * measured;
    yaw += measured_turn;
    Eigen::Isometry3d pose = current;
    pose.translation().head<2>() = position;
    // The heading error turns the true attitude about the vertical.
    pose.linear() =
        Eigen::AngleAxisd(yaw - yawOf(current), Eigen::Vector3d::UnitZ()) * current.linear();
    odometry.push_back(pose);
  }
  return odometry;
}

}  // namespace sim
}  // namespace occupancy_fusion
