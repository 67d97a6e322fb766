// Poses from a live tf2 buffer, for the mapping session's lookups of its own (reanchoring: the
// odometry's pose of a sensor, of the robot's body, and map -> odom, each at a frame's stamp).
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>

#include <tf2/buffer_core.h>

#include "occupancy_fusion/mapping/frames.h"

namespace occupancy_fusion {

class TfBufferPoseSource : public PoseSource {
 public:
  explicit TfBufferPoseSource(const tf2::BufferCore& buffer) : buffer_(buffer) {}
  std::optional<Eigen::Isometry3d> lookup(const std::string& target_frame,
                                          const std::string& sensor_frame, double stamp,
                                          std::string* why) const override;

 private:
  const tf2::BufferCore& buffer_;
};

}  // namespace occupancy_fusion
