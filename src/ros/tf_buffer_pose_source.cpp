#include "occupancy_fusion/ros/tf_buffer_pose_source.h"

#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>

namespace occupancy_fusion {

std::optional<Eigen::Isometry3d> TfBufferPoseSource::lookup(const std::string& target_frame,
                                                            const std::string& sensor_frame,
                                                            double stamp, std::string* why) const {
  const ros::Time time(stamp);
  try {
    return tf2::transformToEigen(buffer_.lookupTransform(target_frame, sensor_frame, time));
  } catch (const tf2::ExtrapolationException& error) {
    // A frame's stamp reaches here as double seconds, which keep a stamp of today only to about
    // 0.1 us: back as a ros::Time it may lie just after the newest transform, sent at the
    // frame's exact stamp. A microsecond earlier is the same pose.
    try {
      return tf2::transformToEigen(
          buffer_.lookupTransform(target_frame, sensor_frame, time - ros::Duration(1e-6)));
    } catch (const tf2::TransformException&) {
      if (why != nullptr) *why = error.what();
      return std::nullopt;
    }
  } catch (const tf2::TransformException& error) {
    if (why != nullptr) *why = error.what();
    return std::nullopt;
  }
}

}  // namespace occupancy_fusion
