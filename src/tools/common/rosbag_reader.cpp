#include "occupancy_fusion/tools/rosbag_reader.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <stereo_msgs/DisparityImage.h>
#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include "occupancy_fusion/ros/conversions.h"
#include "occupancy_fusion/ros/depth_messages.h"
#include "occupancy_fusion/ros/disparity_messages.h"
#include "occupancy_fusion/ros/keyframe_path.h"
#include "occupancy_fusion/tools/ros_conversions.h"

namespace occupancy_fusion {
namespace {

constexpr const char* kPointCloud2Type = "sensor_msgs/PointCloud2";
constexpr const char* kImageType = "sensor_msgs/Image";
constexpr const char* kDisparityType = "stereo_msgs/DisparityImage";
constexpr const char* kLaserScanType = "sensor_msgs/LaserScan";
constexpr const char* kPathType = "nav_msgs/Path";

// Topic name -> message type, for every connection in the bags.
std::map<std::string, std::string> topicTypes(const std::vector<const rosbag::Bag*>& bags) {
  std::map<std::string, std::string> types;
  for (const rosbag::Bag* bag : bags) {
    rosbag::View view(*bag);
    for (const rosbag::ConnectionInfo* connection : view.getConnections()) {
      types[connection->topic] = connection->datatype;
    }
  }
  return types;
}

std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text.empty() ? "none" : text;
}

// The cache must reach from the first to the last transform, or tf2 would forget the start.
ros::Duration recordingSpan(const std::vector<const rosbag::Bag*>& bags) {
  rosbag::View view;
  for (const rosbag::Bag* bag : bags) view.addQuery(*bag);
  if (view.size() == 0) return ros::Duration(1.0);
  return (view.getEndTime() - view.getBeginTime()) + ros::Duration(10.0);
}

// ".../NAME" -> ".../sibling".
std::string siblingTopic(const std::string& topic, const std::string& sibling) {
  const std::size_t slash = topic.rfind('/');
  return (slash == std::string::npos ? std::string() : topic.substr(0, slash + 1)) + sibling;
}

std::vector<std::string> depthInfoTopics(const std::string& image_topic) {
  return {siblingTopic(image_topic, "camera_info")};
}

std::vector<std::string> disparityInfoTopics(const std::string& disparity_topic) {
  return {siblingTopic(disparity_topic, "camera_info"),
          siblingTopic(disparity_topic, "left/camera_info")};
}

bool contains(const std::vector<std::string>& list, const std::string& value) {
  return std::find(list.begin(), list.end(), value) != list.end();
}

// Whether the first message on an Image topic has a depth encoding.
bool carriesDepth(const std::vector<const rosbag::Bag*>& bags, const std::string& topic) {
  rosbag::View view;
  for (const rosbag::Bag* bag : bags) view.addQuery(*bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& message : view) {
    const sensor_msgs::Image::ConstPtr image = message.instantiate<sensor_msgs::Image>();
    return image && isDepthEncoding(image->encoding);
  }
  return false;
}

FrameHeader headerOf(const rosbag::MessageInstance& message, const std::string& kind,
                     const std_msgs::Header& header) {
  return frameHeaderOf(header, kind, message.getTopic());
}

}  // namespace

TfPoseSource::TfPoseSource(const rosbag::Bag& bag, const std::string& tf_topic,
                           const std::string& static_tf_topic)
    : TfPoseSource(std::vector<const rosbag::Bag*>{&bag}, tf_topic, static_tf_topic) {}

TfPoseSource::TfPoseSource(const std::vector<const rosbag::Bag*>& bags, const std::string& tf_topic,
                           const std::string& static_tf_topic)
    : buffer_(std::make_unique<tf2::BufferCore>(recordingSpan(bags))) {
  for (const rosbag::Bag* bag : bags) load(*bag, tf_topic, static_tf_topic);
}

void TfPoseSource::load(const rosbag::Bag& bag, const std::string& tf_topic,
                        const std::string& static_tf_topic) {
  rosbag::View view(bag, rosbag::TopicQuery({tf_topic, static_tf_topic}));
  std::map<std::pair<std::string, std::string>, ros::Time> latest;  // by parent and child
  for (const rosbag::MessageInstance& message : view) {
    if (time_jump_at_ && message.getTime() >= *time_jump_at_) return;
    const tf2_msgs::TFMessage::ConstPtr transforms = message.instantiate<tf2_msgs::TFMessage>();
    if (!transforms) continue;  // another type on a tf topic: nothing to learn from it
    const bool is_static = message.getTopic() == static_tf_topic;
    for (const geometry_msgs::TransformStamped& transform : transforms->transforms) {
      if (!is_static) {
        ros::Time& last = latest[{transform.header.frame_id, transform.child_frame_id}];
        const double back = (last - transform.header.stamp).toSec();
        if (!last.isZero() && back > kTimeJump) {
          if (!time_jump_at_ || message.getTime() < *time_jump_at_) {
            time_jump_at_ = message.getTime();
            time_jump_seconds_ = back;
          }
          return;
        }
        last = std::max(last, transform.header.stamp);
      }
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

RosbagReader::RosbagReader(const std::vector<std::string>& paths, const RosbagTopics& topics) {
  open(paths, topics, false);
}

RosbagReader::RosbagReader(const std::string& path, const std::vector<std::string>& cloud_topics) {
  RosbagTopics topics;
  topics.clouds = cloud_topics;
  open({path}, topics, true);
}

RosbagReader::~RosbagReader() {
  for (const std::unique_ptr<rosbag::Bag>& bag : bags_) bag->close();
}

void RosbagReader::open(const std::vector<std::string>& paths, const RosbagTopics& topics,
                        bool clouds_only) {
  paths_ = paths;
  std::vector<const rosbag::Bag*> bags;
  for (const std::string& path : paths) {
    bags_.push_back(std::make_unique<rosbag::Bag>());
    try {
      bags_.back()->open(path, rosbag::bagmode::Read);
    } catch (const rosbag::BagException& error) {
      throw std::invalid_argument("cannot open bag '" + path + "': " + error.what());
    }
    bags.push_back(bags_.back().get());
  }
  const std::string where =
      "bag" + std::string(paths.size() > 1 ? "s '" : " '") + joined(paths) + "'";
  const std::map<std::string, std::string> types = topicTypes(bags);
  RosbagTopics available;
  for (const auto& [topic, type] : types) {
    if (type == kPointCloud2Type) available.clouds.push_back(topic);
    if (type == kImageType && carriesDepth(bags, topic)) available.depth_images.push_back(topic);
    if (type == kDisparityType) available.disparity_images.push_back(topic);
    if (type == kLaserScanType) available.scans.push_back(topic);
  }
  const auto check = [&](const std::vector<std::string>& requested, const char* type,
                         const std::vector<std::string>& of_type) {
    for (const std::string& topic : requested) {
      const auto entry = types.find(topic);
      if (entry == types.end() || entry->second != type) {
        throw std::invalid_argument(where + " has no " + type + " topic '" + topic +
                                    "' (its topics of that type: " + joined(of_type) + ")");
      }
    }
  };
  check(topics.clouds, kPointCloud2Type, available.clouds);
  check(topics.depth_images, kImageType, available.depth_images);
  check(topics.disparity_images, kDisparityType, available.disparity_images);
  check(topics.scans, kLaserScanType, available.scans);
  std::vector<std::string> path_topics;
  for (const auto& [topic, type] : types) {
    if (type == kPathType) path_topics.push_back(topic);
  }
  check(topics.paths, kPathType, path_topics);
  if (!topics.empty()) {
    topics_ = topics;
  } else if (clouds_only) {
    topics_.clouds = available.clouds;
  } else {
    topics_ = available;
  }
  topics_.paths = topics.paths;
  if (topics_.empty()) {
    throw std::invalid_argument(where + " holds no " +
                                (clouds_only ? std::string("sensor_msgs/PointCloud2")
                                             : std::string("PointCloud2, depth Image, "
                                                           "DisparityImage or LaserScan")));
  }
  std::vector<std::string> sensor_topics = topics_.clouds;
  for (const auto* list : {&topics_.depth_images, &topics_.disparity_images, &topics_.scans}) {
    sensor_topics.insert(sensor_topics.end(), list->begin(), list->end());
  }
  rosbag::View view;
  for (const rosbag::Bag* bag : bags) view.addQuery(*bag, rosbag::TopicQuery(sensor_topics));
  frame_count_ = view.size();
  poses_ = std::make_unique<TfPoseSource>(bags);
  loadCameraInfos();
}

void RosbagReader::loadCameraInfos() {
  std::vector<std::string> info_topics;
  for (const std::string& topic : topics_.depth_images) {
    for (const std::string& info : depthInfoTopics(topic)) info_topics.push_back(info);
  }
  for (const std::string& topic : topics_.disparity_images) {
    for (const std::string& info : disparityInfoTopics(topic)) info_topics.push_back(info);
  }
  if (info_topics.empty()) return;
  rosbag::View view;
  for (const std::unique_ptr<rosbag::Bag>& bag : bags_) {
    view.addQuery(*bag, rosbag::TopicQuery(info_topics));
  }
  for (const rosbag::MessageInstance& message : view) {
    const sensor_msgs::CameraInfo::ConstPtr info = message.instantiate<sensor_msgs::CameraInfo>();
    if (info) camera_infos_[message.getTopic()].emplace_back(info->header.stamp.toSec(), *info);
  }
  for (auto& entry : camera_infos_) {
    std::stable_sort(entry.second.begin(), entry.second.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
  }
}

const sensor_msgs::CameraInfo* RosbagReader::nearestCameraInfo(
    const std::vector<std::string>& candidates, double stamp, std::string* why) const {
  for (const std::string& topic : candidates) {
    const auto entry = camera_infos_.find(topic);
    if (entry == camera_infos_.end() || entry->second.empty()) continue;
    const auto& infos = entry->second;
    auto after = std::lower_bound(infos.begin(), infos.end(), stamp,
                                  [](const auto& info, double t) { return info.first < t; });
    if (after == infos.end()) return &infos.back().second;
    if (after == infos.begin()) return &after->second;
    const auto before = std::prev(after);
    return std::abs(after->first - stamp) < std::abs(stamp - before->first) ? &after->second
                                                                            : &before->second;
  }
  *why = "no sensor_msgs/CameraInfo on " + joined(candidates);
  return nullptr;
}

std::vector<std::string> RosbagReader::disparityTopicsWithoutCameraInfo() const {
  std::vector<std::string> topics;
  for (const std::string& topic : topics_.disparity_images) {
    bool has_info = false;
    for (const std::string& info : disparityInfoTopics(topic)) {
      has_info = has_info || camera_infos_.count(info) > 0;
    }
    if (!has_info) topics.push_back(topic);
  }
  return topics;
}

std::string RosbagReader::description() const {
  std::ostringstream text;
  text << "rosbag " << joined(paths_) << ": " << frame_count_ << " frames";
  const auto kind = [&](const char* name, const std::vector<std::string>& topics) {
    if (!topics.empty()) text << ", " << name << " on " << joined(topics);
  };
  kind("PointCloud2", topics_.clouds);
  kind("depth Image", topics_.depth_images);
  kind("DisparityImage", topics_.disparity_images);
  kind("LaserScan", topics_.scans);
  text << ", " << poses_->transformCount() << " tf transforms";
  const std::vector<std::string> without_info = disparityTopicsWithoutCameraInfo();
  if (!without_info.empty()) {
    text << " (no camera_info for " << joined(without_info)
         << ": principal point at the image centre)";
  }
  return text.str();
}

void RosbagReader::deliver(const rosbag::MessageInstance& message, FrameConsumer* consumer) const {
  const std::string& topic = message.getTopic();
  if (contains(topics_.clouds, topic)) {
    const sensor_msgs::PointCloud2::ConstPtr cloud =
        message.instantiate<sensor_msgs::PointCloud2>();
    if (!cloud) return;
    PointCloudFrame frame;
    frame.header = headerOf(message, "point_cloud", cloud->header);
    try {
      // The nodelets' conversion, in the sensor frame: the mapping session places the points.
      frame.points = transformedPoints(*cloud, Eigen::Isometry3d::Identity());
    } catch (const std::invalid_argument& error) {
      consumer->onUnreadable(frame.header, error.what());
      return;
    }
    consumer->onPointCloud(frame);
  } else if (contains(topics_.depth_images, topic)) {
    const sensor_msgs::Image::ConstPtr image = message.instantiate<sensor_msgs::Image>();
    if (!image) return;
    DepthImageFrame frame;
    frame.header = headerOf(message, "depth", image->header);
    std::string why;
    const sensor_msgs::CameraInfo* info =
        nearestCameraInfo(depthInfoTopics(topic), frame.header.stamp, &why);
    try {
      if (info == nullptr) throw std::invalid_argument(why);
      std::vector<float> storage;
      const DepthImageView view = depthInMetres(*image, &storage);
      frame.camera = depthCameraIntrinsics(*info, *image);
      // The frame owns its pixels (a consumer may keep it): a dense copy where the view points
      // into the message.
      if (view.depth == storage.data()) {
        frame.depth = std::move(storage);
      } else {
        frame.depth.resize(static_cast<std::size_t>(view.width) * view.height);
        for (int v = 0; v < view.height; ++v) {
          for (int u = 0; u < view.width; ++u) {
            frame.depth[static_cast<std::size_t>(v) * view.width + u] = view.at(u, v);
          }
        }
      }
    } catch (const std::invalid_argument& error) {
      consumer->onUnreadable(frame.header, error.what());
      return;
    }
    consumer->onDepthImage(frame);
  } else if (contains(topics_.disparity_images, topic)) {
    const stereo_msgs::DisparityImage::ConstPtr disparity =
        message.instantiate<stereo_msgs::DisparityImage>();
    if (!disparity) return;
    DisparityFrame frame;
    frame.header = headerOf(message, "disparity", disparity->header);
    std::string why;
    const sensor_msgs::CameraInfo* info =
        nearestCameraInfo(disparityInfoTopics(topic), frame.header.stamp, &why);
    try {
      frame.disparity = validDisparities(*disparity);
      frame.width = static_cast<int>(disparity->image.width);
      frame.height = static_cast<int>(disparity->image.height);
      frame.camera = info != nullptr ? stereoCameraOf(*disparity, *info)
                                     : stereoCameraAtImageCentre(*disparity);
    } catch (const std::invalid_argument& error) {
      consumer->onUnreadable(frame.header, error.what());
      return;
    }
    consumer->onDisparityImage(frame);
  } else if (contains(topics_.scans, topic)) {
    const sensor_msgs::LaserScan::ConstPtr scan = message.instantiate<sensor_msgs::LaserScan>();
    if (!scan) return;
    LaserScanFrame frame;
    frame.header = headerOf(message, "laser", scan->header);
    try {
      frame.scan = checkedLaserScan(*scan);
    } catch (const std::invalid_argument& error) {
      consumer->onUnreadable(frame.header, error.what());
      return;
    }
    consumer->onLaserScan(frame);
  } else if (contains(topics_.paths, topic)) {
    const nav_msgs::Path::ConstPtr path = message.instantiate<nav_msgs::Path>();
    if (path) consumer->onTrajectory(keyframesOf(*path), path->header.stamp.toSec());
  }
}

void RosbagReader::read(FrameConsumer* consumer,
                        const std::function<void(std::size_t)>& after_frame) {
  std::vector<std::string> sensor_topics = topics_.clouds;
  for (const auto* list :
       {&topics_.depth_images, &topics_.disparity_images, &topics_.scans, &topics_.paths}) {
    sensor_topics.insert(sensor_topics.end(), list->begin(), list->end());
  }
  // A View over several bags and topics yields their messages merged in bag time order.
  rosbag::View view;
  for (const std::unique_ptr<rosbag::Bag>& bag : bags_) {
    view.addQuery(*bag, rosbag::TopicQuery(sensor_topics));
  }
  std::size_t delivered = 0;
  const std::optional<ros::Time> jump = poses_->timeJumpAt();
  for (const rosbag::MessageInstance& message : view) {
    if (jump && message.getTime() >= *jump) {
      // See TfPoseSource::timeJumpAt: the poses after the jump were not loaded.
      FrameHeader header;
      header.source = message.getTopic();
      consumer->onUnreadable(header, "tf stamps jump back by " +
                                         std::to_string(poses_->timeJumpSeconds()) +
                                         " s at bag time " + std::to_string(jump->toSec()) +
                                         " (a looped recording?): the rest is not mapped; split "
                                         "the bag there (rosbag filter) to map each pass");
    } else {
      deliver(message, consumer);
    }
    if (contains(topics_.paths, message.getTopic())) continue;  // not a frame
    if (after_frame) after_frame(++delivered);
  }
}

}  // namespace occupancy_fusion
