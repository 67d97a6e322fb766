#include "occupancy_fusion/tools/rosbag_reader.h"

#include <algorithm>
#include <map>
#include <sstream>
#include <stdexcept>

#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include "occupancy_fusion/tools/ros_conversions.h"

namespace occupancy_fusion {
namespace {

constexpr const char* kPointCloud2Type = "sensor_msgs/PointCloud2";

// Topic name -> message type, for every connection in the bag.
std::map<std::string, std::string> topicTypes(const rosbag::Bag& bag) {
  std::map<std::string, std::string> types;
  rosbag::View view(bag);
  for (const rosbag::ConnectionInfo* connection : view.getConnections()) {
    types[connection->topic] = connection->datatype;
  }
  return types;
}

std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text.empty() ? "none" : text;
}

// The cache must reach from the first to the last transform, or tf2 would forget the start.
ros::Duration recordingSpan(const rosbag::Bag& bag) {
  rosbag::View view(bag);
  if (view.size() == 0) return ros::Duration(1.0);
  return (view.getEndTime() - view.getBeginTime()) + ros::Duration(10.0);
}

}  // namespace

TfPoseSource::TfPoseSource(const rosbag::Bag& bag, const std::string& tf_topic,
                           const std::string& static_tf_topic)
    : buffer_(std::make_unique<tf2::BufferCore>(recordingSpan(bag))) {
  rosbag::View view(bag, rosbag::TopicQuery({tf_topic, static_tf_topic}));
  for (const rosbag::MessageInstance& message : view) {
    const tf2_msgs::TFMessage::ConstPtr transforms = message.instantiate<tf2_msgs::TFMessage>();
    if (!transforms) continue;  // another type on a tf topic: nothing to learn from it
    const bool is_static = message.getTopic() == static_tf_topic;
    for (const geometry_msgs::TransformStamped& transform : transforms->transforms) {
      // setTransform rejects malformed transforms (NaN, empty frame) with a ROS_ERROR; skip them
      // rather than stop.
      if (buffer_->setTransform(transform, "bag", is_static)) ++transform_count_;
    }
  }
}

std::optional<Eigen::Isometry3d> TfPoseSource::lookup(const std::string& target_frame,
                                                      const std::string& sensor_frame, double stamp,
                                                      std::string* why) const {
  // tf2 rejects the leading '/' that tf1-era bags put on frame names.
  const auto strip = [](const std::string& frame) {
    return frame.rfind('/', 0) == 0 ? frame.substr(1) : frame;
  };
  try {
    const geometry_msgs::TransformStamped transform =
        buffer_->lookupTransform(strip(target_frame), strip(sensor_frame), ros::Time(stamp));
    return tf2::transformToEigen(transform);
  } catch (const tf2::TransformException& error) {
    if (why != nullptr) *why = error.what();
    return std::nullopt;
  }
}

RosbagReader::RosbagReader(const std::string& path, const std::vector<std::string>& cloud_topics)
    : path_(path) {
  try {
    bag_.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& error) {
    throw std::invalid_argument("cannot open bag '" + path + "': " + error.what());
  }
  const std::map<std::string, std::string> types = topicTypes(bag_);
  std::vector<std::string> all_clouds;
  for (const auto& [topic, type] : types) {
    if (type == kPointCloud2Type) all_clouds.push_back(topic);
  }
  for (const std::string& topic : cloud_topics) {
    const auto entry = types.find(topic);
    if (entry == types.end() || entry->second != kPointCloud2Type) {
      throw std::invalid_argument("bag '" + path + "' has no PointCloud2 topic '" + topic +
                                  "' (its PointCloud2 topics: " + joined(all_clouds) + ")");
    }
  }
  cloud_topics_ = cloud_topics.empty() ? all_clouds : cloud_topics;
  if (cloud_topics_.empty()) {
    throw std::invalid_argument("bag '" + path + "' holds no sensor_msgs/PointCloud2");
  }
  frame_count_ = rosbag::View(bag_, rosbag::TopicQuery(cloud_topics_)).size();
  poses_ = std::make_unique<TfPoseSource>(bag_);
}

RosbagReader::~RosbagReader() { bag_.close(); }

std::string RosbagReader::description() const {
  std::ostringstream text;
  text << "rosbag " << path_ << ": " << frame_count_ << " PointCloud2 on " << joined(cloud_topics_)
       << ", " << poses_->transformCount() << " tf transforms";
  return text.str();
}

void RosbagReader::read(FrameConsumer* consumer,
                        const std::function<void(std::size_t)>& after_frame) {
  // A View over several topics yields their messages merged in bag time order.
  rosbag::View view(bag_, rosbag::TopicQuery(cloud_topics_));
  std::size_t delivered = 0;
  for (const rosbag::MessageInstance& message : view) {
    const sensor_msgs::PointCloud2::ConstPtr cloud =
        message.instantiate<sensor_msgs::PointCloud2>();
    if (!cloud) continue;
    PointCloudFrame frame;
    frame.header.source = message.getTopic();
    frame.header.frame_id = cloud->header.frame_id;
    frame.header.stamp = cloud->header.stamp.toSec();
    try {
      frame.points = pointsFromCloud(*cloud);
      consumer->onPointCloud(frame);
    } catch (const std::invalid_argument& error) {
      consumer->onUnreadable(frame.header, error.what());
    }
    if (after_frame) after_frame(++delivered);
  }
}

}  // namespace occupancy_fusion
