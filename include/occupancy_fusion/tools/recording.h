// Recorded sensor data as the offline tools see it: an InputReader delivers time-ordered frames
// of any sensor kind (mapping/frames.h) to a FrameConsumer, usually the MappingSession, and
// provides the poses that place them in the map. A new recording format (CARMEN logs, image
// folders) is a new reader; the frames and the mapping side stay the same.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "occupancy_fusion/mapping/frames.h"

namespace occupancy_fusion {

class InputReader {
 public:
  virtual ~InputReader() = default;
  // One line for logs, e.g. "rosbag in.bag: 120 PointCloud2 on /cloud_in".
  virtual std::string description() const = 0;
  // How many frames read() delivers, for progress output.
  virtual std::size_t frameCount() const = 0;
  // Poses of frames whose header has no T_map_sensor.
  virtual const PoseSource& poses() const = 0;
  // Delivers every frame in time order; after_frame(frames delivered so far) follows each one.
  virtual void read(FrameConsumer* consumer,
                    const std::function<void(std::size_t)>& after_frame) = 0;
};

}  // namespace occupancy_fusion
