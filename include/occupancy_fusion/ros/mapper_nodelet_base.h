// What the mapper nodelets (point cloud, depth, disparity, laser) share, so that each keeps only
// its input, its conversion and its core call: the shared map and the parameters every mapper
// reads (the map's, ~queue_size, ~publish_map), the MapPublisher of a mapper that runs alone, the
// tf2 buffer with the message filters that hold inputs back until their pose is known, and the
// 1 Hz diagnostics task with the input statistics every mapper reports alike (FrameStatistics:
// frames received and their rate, integrated and the time each took, dropped by reason, tf
// failures), counted here: every frame that enters a transform filter is received, a message
// callback that returns true has integrated it, every other outcome is a drop with a reason.
#pragma once

#include <chrono>
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
#include "occupancy_fusion/ros/frame_statistics.h"
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

  // Publishes the input statistics and `fill`'s status as diagnostics task `task_name` once a
  // second, under the hardware ID "map '<map name>'". `drop_reasons`: the mapper's own reasons to
  // drop a frame (besides the tf ones), reported from the start.
  void startDiagnostics(const std::string& task_name, const std::vector<std::string>& drop_reasons,
                        DiagnosticsTask fill);

  // A frame that passed the transform filter and was not integrated, for `reason`.
  void countDropped(const std::string& reason) { frames_.countDropped(reason); }
  const FrameStatistics& frameStatistics() const { return frames_; }

  // A tf2 filter between `input` and `on_message` that holds each message back until its frame
  // can be transformed into every one of `target_frames` at its stamp (at most ~queue_size
  // messages). Both callbacks run on this nodelet's queue, not on the tf thread. Every message
  // of `input` is counted as received; `on_message` returns whether it integrated the message
  // (timed and counted here; when it returns false it has counted the drop with its reason);
  // `on_dropped` gets each message the filter gives up on, counted here as a tf failure.
  template <class Message, class Input>
  std::unique_ptr<tf2_ros::MessageFilter<Message>> makeTransformFilter(
      Input& input, const std::vector<std::string>& target_frames,
      std::function<bool(const Message&)> on_message,
      std::function<void(const Message&)> on_dropped) {
    input.registerCallback([this](const typename Message::ConstPtr&) { frames_.countReceived(); });
    auto filter = std::make_unique<tf2_ros::MessageFilter<Message>>(
        input, *tf_buffer_, target_frames.front(), queue_size_, getNodeHandle());
    filter->setTargetFrames(target_frames);
    filter->registerCallback(
        [this, on_message = std::move(on_message)](const typename Message::ConstPtr& message) {
          const auto start = std::chrono::steady_clock::now();
          if (!on_message(*message)) return;
          frames_.countIntegrated(
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                  .count());
        });
    filter->registerFailureCallback(
        [this, on_dropped = std::move(on_dropped)](
            const typename Message::ConstPtr& message,
            tf2_ros::filter_failure_reasons::FilterFailureReason reason) {
          frames_.countDropped(tfDropReason(reason));
          on_dropped(*message);
        });
    return filter;
  }

  // The usual filter: into the map frame. A message without a transform in time is warned about
  // (throttled), naming it `what` ("cloud", "depth image").
  template <class Message, class Input>
  std::unique_ptr<tf2_ros::MessageFilter<Message>> makeMapFrameFilter(
      Input& input, const std::string& what, std::function<bool(const Message&)> on_message) {
    return makeTransformFilter<Message>(
        input, {map_->frameId()}, std::move(on_message), [this, what](const Message& m) {
          NODELET_WARN_THROTTLE(5.0, "no transform from '%s' to '%s' at %.3f: %s dropped",
                                m.header.frame_id.c_str(), map_->frameId().c_str(),
                                m.header.stamp.toSec(), what.c_str());
        });
  }

  // The pose of the message's frame in the map frame at its stamp. Without one, the message is
  // counted as dropped (a tf failure), warned about (throttled) and nullopt returned. A template
  // so that each mapper keeps its own throttled warning.
  template <class Message>
  std::optional<Eigen::Isometry3d> poseInMap(const Message& message, const std::string& what) {
    try {
      return tf2::transformToEigen(tf_buffer_->lookupTransform(
          map_->frameId(), message.header.frame_id, message.header.stamp));
    } catch (const tf2::TransformException& error) {
      frames_.countDropped(FrameStatistics::kTfLookup);
      NODELET_WARN_THROTTLE(5.0, "%s dropped: %s", what.c_str(), error.what());
      return std::nullopt;
    }
  }

  SharedMap& map() const { return *map_; }
  int queueSize() const { return queue_size_; }
  const tf2_ros::Buffer& tfBuffer() const { return *tf_buffer_; }

 private:
  static const char* tfDropReason(tf2_ros::filter_failure_reasons::FilterFailureReason reason);

  std::shared_ptr<SharedMap> map_;
  int queue_size_ = 5;
  std::unique_ptr<MapPublisher> map_publisher_;
  // Outlives the derived mappers' message filters, which unregister from it when they go.
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  FrameStatistics frames_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;
};

}  // namespace occupancy_fusion
