// Reads a rosbag without a ROS master: sensor messages in time order, poses from its tf.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/message_instance.h>
#include <sensor_msgs/CameraInfo.h>
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
  // The same for several bags recorded together: one buffer holds all their transforms.
  explicit TfPoseSource(const std::vector<const rosbag::Bag*>& bags,
                        const std::string& tf_topic = "/tf",
                        const std::string& static_tf_topic = "/tf_static");

  std::optional<Eigen::Isometry3d> lookup(const std::string& target_frame,
                                          const std::string& sensor_frame, double stamp,
                                          std::string* why) const override;

  std::size_t transformCount() const { return transform_count_; }

  // A recording whose tf stamps go back by more than kTimeJump (a bag recorded from a looped
  // playback, or bags of two runs read together) would mix both passes' poses in one buffer:
  // tf is read only up to the first such jump, and this is the bag time where it happened.
  static constexpr double kTimeJump = 1.0;  // s
  std::optional<ros::Time> timeJumpAt() const { return time_jump_at_; }
  double timeJumpSeconds() const { return time_jump_seconds_; }

 private:
  void load(const rosbag::Bag& bag, const std::string& tf_topic,
            const std::string& static_tf_topic);

  std::unique_ptr<tf2::BufferCore> buffer_;
  std::size_t transform_count_ = 0;
  std::optional<ros::Time> time_jump_at_;
  double time_jump_seconds_ = 0.0;
};

// The sensor topics of a bag to map, per kind.
struct RosbagTopics {
  std::vector<std::string> clouds;            // sensor_msgs/PointCloud2
  std::vector<std::string> depth_images;      // sensor_msgs/Image, 16UC1 / mono16 mm or 32FC1 m
  std::vector<std::string> disparity_images;  // stereo_msgs/DisparityImage
  std::vector<std::string> scans;             // sensor_msgs/LaserScan
  // nav_msgs/Path: a SLAM system's keyframes, for the map's reanchoring (never chosen by default)
  std::vector<std::string> paths;

  bool empty() const {
    return clouds.empty() && depth_images.empty() && disparity_images.empty() && scans.empty();
  }
};

// Sensor frames from one or more bags, merged in time order: PointCloud2, depth images with their
// camera_info, DisparityImages with the left camera's camera_info, and LaserScans. Poses come from
// the bags' tf. A message that cannot be decoded (wrong encoding, no camera_info) reaches the
// consumer's onUnreadable and reading goes on.
//
// Camera infos: a depth image on .../NAME uses .../camera_info (image_transport's convention); a
// disparity image on .../NAME uses .../camera_info, else .../left/camera_info (stereo_image_proc's
// layout). The camera_info nearest in time to the image is used. A depth image without one is
// skipped; a disparity topic without any (a DisparityImage carries f and the baseline itself)
// takes its principal point at the image centre, and description() says so.
class RosbagReader : public InputReader {
 public:
  // Opens the bags. With `topics` empty every topic of a supported type is mapped: every
  // PointCloud2, DisparityImage and LaserScan topic, and every Image topic whose first message
  // has a depth encoding. Otherwise exactly the topics given. Throws std::invalid_argument when
  // a file cannot be opened as a bag, a requested topic is in none of them or has another type,
  // or there is nothing to map.
  RosbagReader(const std::vector<std::string>& paths, const RosbagTopics& topics);
  // One bag, PointCloud2 topics only (every one when cloud_topics is empty).
  RosbagReader(const std::string& path, const std::vector<std::string>& cloud_topics);
  ~RosbagReader() override;

  std::string description() const override;
  std::size_t frameCount() const override { return frame_count_; }
  const PoseSource& poses() const override { return *poses_; }
  void read(FrameConsumer* consumer, const std::function<void(std::size_t)>& after_frame) override;

  const RosbagTopics& topics() const { return topics_; }
  // Disparity topics that have no camera_info in the bags.
  std::vector<std::string> disparityTopicsWithoutCameraInfo() const;
  const std::vector<std::string>& cloudTopics() const { return topics_.clouds; }

 private:
  void open(const std::vector<std::string>& paths, const RosbagTopics& topics, bool clouds_only);
  // Camera infos of every topic some image may use, by topic, in time order.
  void loadCameraInfos();
  const sensor_msgs::CameraInfo* nearestCameraInfo(const std::vector<std::string>& candidates,
                                                   double stamp, std::string* why) const;
  void deliver(const rosbag::MessageInstance& message, FrameConsumer* consumer) const;

  std::vector<std::string> paths_;
  std::vector<std::unique_ptr<rosbag::Bag>> bags_;
  RosbagTopics topics_;
  std::size_t frame_count_ = 0;
  std::unique_ptr<TfPoseSource> poses_;
  std::map<std::string, std::vector<std::pair<double, sensor_msgs::CameraInfo>>> camera_infos_;
};

}  // namespace occupancy_fusion
