#include "occupancy_fusion/ros/tf_buffer_pose_source.h"

#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>

namespace occupancy_fusion {

std::optional<Eigen::Isometry3d> TfBufferPoseSource::lookup(const std::string& target_frame,
                                                            const std::string& sensor_frame,
                                                            double stamp, std::string* why) const {
  try {
    return tf2::transformToEigen(
        buffer_.lookupTransform(target_frame, sensor_frame, ros::Time(stamp)));
  } catch (const tf2::TransformException& error) {
    if (why != nullptr) *why = error.what();
    return std::nullopt;
  }
}

}  // namespace occupancy_fusion
