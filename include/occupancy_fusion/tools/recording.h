// Recorded sensor data as the offline tools see it: an InputReader delivers time-ordered frames
// of any sensor kind to a FrameConsumer and provides the poses that place them in the map.
// A new input kind (depth images, disparity, laser scans, CARMEN logs, image folders) is a new
// frame type with its FrameConsumer callback plus a reader; the mapping side stays the same.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace occupancy_fusion {

// What every frame carries: where it came from, its sensor frame and its time.
struct FrameHeader {
  std::string source;    // topic or file it was read from
  std::string frame_id;  // the sensor's frame
  double stamp = 0.0;    // s; 0 means "latest available pose" (tf's convention)
};

// 3D points in the sensor frame; non-finite points already removed.
struct PointCloudFrame {
  FrameHeader header;
  std::vector<Eigen::Vector3f> points;
};

// Receives the frames of a recording, one callback per sensor kind.
class FrameConsumer {
 public:
  virtual ~FrameConsumer() = default;
  virtual void onPointCloud(const PointCloudFrame& frame) = 0;
  // A message that could not be decoded (e.g. a cloud without x/y/z): counted, not fatal.
  virtual void onUnreadable(const FrameHeader& header, const std::string& why) = 0;
};

// Where sensor poses come from (tf in a bag, odometry in a log, a poses file beside images).
class PoseSource {
 public:
  virtual ~PoseSource() = default;
  // The transform taking points from sensor_frame to target_frame at stamp; nullopt when it is
  // not available, with the reason in *why (one short line, e.g. the tf2 error).
  virtual std::optional<Eigen::Isometry3d> lookup(const std::string& target_frame,
                                                  const std::string& sensor_frame, double stamp,
                                                  std::string* why) const = 0;
};

class InputReader {
 public:
  virtual ~InputReader() = default;
  // One line for logs, e.g. "rosbag in.bag: 120 PointCloud2 on /cloud_in".
  virtual std::string description() const = 0;
  // How many frames read() delivers, for progress output.
  virtual std::size_t frameCount() const = 0;
  virtual const PoseSource& poses() const = 0;
  // Delivers every frame in time order; after_frame(frames delivered so far) follows each one.
  virtual void read(FrameConsumer* consumer,
                    const std::function<void(std::size_t)>& after_frame) = 0;
};

}  // namespace occupancy_fusion
