// What the mapper nodelets (point cloud, depth, disparity, laser) share, so that each keeps only
// its input, its conversion and its core call: the shared map and the parameters every mapper
// reads (the map's, ~queue_size, ~publish_map), the MapPublisher of a mapper that runs alone, the
// tf2 buffer with the message filters that hold inputs back until their pose is known, and the
// 1 Hz diagnostics task.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <nodelet/nodelet.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>
#include <Eigen/Geometry>

#include "occupancy_fusion/params/parameter_source.h"
#include "occupancy_fusion/ros/map_publisher.h"
#include "occupancy_fusion/ros/map_registry.h"

namespace occupancy_fusion {

class MapperNodeletBase : public nodelet::Nodelet {
 protected:
  using DiagnosticsTask = std::function<void(diagnostic_updater::DiagnosticStatusWrapper&)>;

  // Acquires the shared map, lets `read_mapper_config` read the mapper's own configuration, then
  // reads ~queue_size and ~publish_map (creating the MapPublisher when set) and starts the tf2
  // listener. A std::invalid_argument from any of them is logged as fatal and rethrown.
  void setUpMapper(const std::function<void(const ParameterSource&)>& read_mapper_config);

  // Publishes `fill`'s status as diagnostics task `task_name` once a second, under the hardware
  // ID "map '<map name>'".
  void startDiagnostics(const std::string& task_name, DiagnosticsTask fill);

  // A tf2 filter between `input` and `on_message` that holds each message back until its frame
  // can be transformed into every one of `target_frames` at its stamp (at most ~queue_size
  // messages). Both callbacks run on this nodelet's queue, not on the tf thread; `on_dropped`
  // gets each message the filter gives up on.
  template <class Message, class Input>
  std::unique_ptr<tf2_ros::MessageFilter<Message>> makeTransformFilter(
      Input& input, const std::vector<std::string>& target_frames,
      std::function<void(const Message&)> on_message,
      std::function<void(const Message&)> on_dropped) {
    auto filter = std::make_unique<tf2_ros::MessageFilter<Message>>(
        input, *tf_buffer_, target_frames.front(), queue_size_, getNodeHandle());
    filter->setTargetFrames(target_frames);
    filter->registerCallback(
        [on_message = std::move(on_message)](const typename Message::ConstPtr& message) {
          on_message(*message);
        });
    filter->registerFailureCallback(
        [on_dropped = std::move(on_dropped)](const typename Message::ConstPtr& message,
                                             tf2_ros::filter_failure_reasons::FilterFailureReason) {
          on_dropped(*message);
        });
    return filter;
  }

  // The usual filter: into the map frame. A message without a transform in time is counted in
  // `dropped` and warned about (throttled), naming it `what` ("cloud", "depth image").
  template <class Message, class Input>
  std::unique_ptr<tf2_ros::MessageFilter<Message>> makeMapFrameFilter(
      Input& input, const std::string& what, std::atomic<std::size_t>* dropped,
      std::function<void(const Message&)> on_message) {
    return makeTransformFilter<Message>(
        input, {map_->frameId()}, std::move(on_message), [this, what, dropped](const Message& m) {
          ++*dropped;
          NODELET_WARN_THROTTLE(5.0, "no transform from '%s' to '%s' at %.3f: %s dropped",
                                m.header.frame_id.c_str(), map_->frameId().c_str(),
                                m.header.stamp.toSec(), what.c_str());
        });
  }

  // The pose of the message's frame in the map frame at its stamp. Without one, the message is
  // counted in `dropped`, warned about (throttled) and nullopt returned. A template so that each
  // mapper keeps its own throttled warning.
  template <class Message>
  std::optional<Eigen::Isometry3d> poseInMap(const Message& message, const std::string& what,
                                             std::atomic<std::size_t>* dropped) const {
    try {
      return tf2::transformToEigen(tf_buffer_->lookupTransform(
          map_->frameId(), message.header.frame_id, message.header.stamp));
    } catch (const tf2::TransformException& error) {
      ++*dropped;
      NODELET_WARN_THROTTLE(5.0, "%s dropped: %s", what.c_str(), error.what());
      return std::nullopt;
    }
  }

  SharedMap& map() const { return *map_; }
  int queueSize() const { return queue_size_; }
  const tf2_ros::Buffer& tfBuffer() const { return *tf_buffer_; }

 private:
  std::shared_ptr<SharedMap> map_;
  int queue_size_ = 5;
  std::unique_ptr<MapPublisher> map_publisher_;
  // Outlives the derived mappers' message filters, which unregister from it when they go.
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;
};

}  // namespace occupancy_fusion
