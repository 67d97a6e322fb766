#include "occupancy_fusion/mapping/trajectory_corrections.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace occupancy_fusion {
namespace {

bool earlier(const StampedPose& a, const StampedPose& b) { return a.stamp < b.stamp; }

// The pose at `stamp` between the stamp-ordered poses around it; nullopt outside their span or
// across a gap wider than max_gap (infinite: none).
std::optional<Eigen::Isometry3d> interpolateAt(const std::vector<StampedPose>& poses, double stamp,
                                               double max_gap) {
  if (poses.empty() || stamp < poses.front().stamp || stamp > poses.back().stamp) {
    return std::nullopt;
  }
  const auto after = std::lower_bound(poses.begin(), poses.end(), StampedPose{stamp, {}}, earlier);
  if (after->stamp == stamp) return after->pose;
  const auto before = after - 1;
  const double gap = after->stamp - before->stamp;
  if (gap > max_gap) return std::nullopt;
  return interpolatePose(before->pose, after->pose, (stamp - before->stamp) / gap);
}

}  // namespace

Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                                  double t) {
  const Eigen::Quaterniond qa(a.linear()), qb(b.linear());
  Eigen::Isometry3d result = Eigen::Isometry3d::Identity();
  result.linear() = qa.slerp(t, qb).toRotationMatrix();
  result.translation() = (1.0 - t) * a.translation() + t * b.translation();
  return result;
}

Eigen::Isometry3d meanPose(const std::vector<Eigen::Isometry3d>& poses) {
  if (poses.empty()) throw std::invalid_argument("meanPose: no poses");
  const Eigen::Quaterniond first(poses.front().linear());
  Eigen::Vector4d sum = Eigen::Vector4d::Zero();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  for (const Eigen::Isometry3d& pose : poses) {
    const Eigen::Quaterniond q(pose.linear());
    sum += (q.dot(first) < 0 ? -1.0 : 1.0) * q.coeffs();  // q and -q are one rotation
    translation += pose.translation();
  }
  Eigen::Isometry3d mean = Eigen::Isometry3d::Identity();
  mean.linear() = Eigen::Quaterniond(sum.normalized()).toRotationMatrix();
  mean.translation() = translation / static_cast<double>(poses.size());
  return mean;
}

void OdometryTrack::add(double stamp, const Eigen::Isometry3d& T_odom_base) {
  if (!poses_.empty() && stamp < poses_.back().stamp) return;
  if (!poses_.empty() && stamp == poses_.back().stamp) {
    poses_.back().pose = T_odom_base;
    return;
  }
  poses_.push_back({stamp, T_odom_base});
}

std::optional<Eigen::Isometry3d> OdometryTrack::at(double stamp, double max_gap) const {
  return interpolateAt(poses_, stamp, max_gap);
}

void TrajectoryCorrectionConfig::validate() const {
  if (!(max_odometry_gap > 0.0)) {
    throw std::invalid_argument("max_odometry_gap must be > 0 s, got " +
                                std::to_string(max_odometry_gap));
  }
}

std::vector<StampedPose> correctionsAlongPath(const std::vector<StampedPose>& path,
                                              const OdometryTrack& odometry,
                                              const TrajectoryCorrectionConfig& config) {
  std::vector<StampedPose> corrections;
  for (const StampedPose& keyframe : path) {
    const std::optional<Eigen::Isometry3d> T_odom_base =
        odometry.at(keyframe.stamp, config.max_odometry_gap);
    if (!T_odom_base || !keyframe.pose.matrix().allFinite()) continue;
    corrections.push_back({keyframe.stamp, keyframe.pose * T_odom_base->inverse()});
  }
  std::sort(corrections.begin(), corrections.end(), earlier);
  return corrections;
}

std::optional<Eigen::Isometry3d> correctionAt(const std::vector<StampedPose>& corrections,
                                              double stamp) {
  if (corrections.empty()) return std::nullopt;
  const double clamped =
      std::min(std::max(stamp, corrections.front().stamp), corrections.back().stamp);
  return interpolateAt(corrections, clamped, INFINITY);
}

std::vector<std::pair<int, Eigen::Isometry3d>> placementsFromCorrections(
    const std::vector<StampedPose>& corrections, const std::vector<SubmapInfo>& submaps) {
  std::vector<std::pair<int, Eigen::Isometry3d>> placements;
  if (corrections.empty()) return placements;
  for (const SubmapInfo& submap : submaps) {
    if (submap.fixed || submap.start_stamp == 0.0) continue;
    std::vector<Eigen::Isometry3d> within;
    const auto first = std::lower_bound(corrections.begin(), corrections.end(),
                                        StampedPose{submap.start_stamp, {}}, earlier);
    for (auto it = first; it != corrections.end() && it->stamp <= submap.end_stamp; ++it) {
      within.push_back(it->pose);
    }
    if (!within.empty()) {
      placements.emplace_back(submap.id, meanPose(within));
      continue;
    }
    // Between keyframes (or beyond the path's ends): the nearest corrections.
    const double middle = 0.5 * (submap.start_stamp + submap.end_stamp);
    const double clamped =
        std::min(std::max(middle, corrections.front().stamp), corrections.back().stamp);
    placements.emplace_back(submap.id, *interpolateAt(corrections, clamped, INFINITY));
  }
  return placements;
}

}  // namespace occupancy_fusion
