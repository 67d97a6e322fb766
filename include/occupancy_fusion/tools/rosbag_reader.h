// Reads a rosbag without a ROS master: sensor messages in time order, poses from its tf.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <rosbag/bag.h>
#include <tf2/buffer_core.h>

#include "occupancy_fusion/tools/recording.h"

namespace occupancy_fusion {

// Poses from /tf and /tf_static messages, all loaded into a tf2::BufferCore up front (its cache
// spans the whole recording, so any stamp in it can be looked up, like a listener that had
// heard the whole bag).
class TfPoseSource : public PoseSource {
 public:
  // Loads every tf2_msgs/TFMessage on tf_topic and static_tf_topic of an open bag.
  TfPoseSource(const rosbag::Bag& bag, const std::string& tf_topic = "/tf",
               const std::string& static_tf_topic = "/tf_static");

  std::optional<Eigen::Isometry3d> lookup(const std::string& target_frame,
                                          const std::string& sensor_frame, double stamp,
                                          std::string* why) const override;

  std::size_t transformCount() const { return transform_count_; }

 private:
  std::unique_ptr<tf2::BufferCore> buffer_;
  std::size_t transform_count_ = 0;
};

// sensor_msgs/PointCloud2 frames from a bag (later issues add images and scans).
class RosbagReader : public InputReader {
 public:
  // Opens the bag; cloud_topics empty means every PointCloud2 topic in it. Throws
  // std::invalid_argument when the file cannot be opened as a bag, a requested topic is not in
  // it or is not a PointCloud2, or it holds no PointCloud2 at all.
  RosbagReader(const std::string& path, const std::vector<std::string>& cloud_topics);
  ~RosbagReader() override;

  std::string description() const override;
  std::size_t frameCount() const override { return frame_count_; }
  const PoseSource& poses() const override { return *poses_; }
  void read(FrameConsumer* consumer, const std::function<void(std::size_t)>& after_frame) override;

  const std::vector<std::string>& cloudTopics() const { return cloud_topics_; }

 private:
  std::string path_;
  rosbag::Bag bag_;
  std::vector<std::string> cloud_topics_;
  std::size_t frame_count_ = 0;
  std::unique_ptr<TfPoseSource> poses_;
};

}  // namespace occupancy_fusion
