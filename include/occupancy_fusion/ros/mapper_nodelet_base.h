// What the mapper nodelets (point cloud, depth, disparity, laser) share, so that each keeps only
// its input, its conversion and its frame: the shared map and the parameters every mapper reads
// (the map's, ~queue_size, ~threads, ~publish_map), the mapping session over the shared map that
// applies the rules offline_mapper applies too (mapping/mapping_session.h: duplicate stamps, poses,
// laser sources, drops), the MapPublisher of a mapper that runs alone, the tf2 buffer with the
// message filters that hold inputs back until their pose is known, and the 1 Hz diagnostics task
// with the input statistics every mapper reports alike (FrameStatistics: frames received and
// their rate, integrated and the time each took, dropped by reason, tf failures), counted here:
// every frame that enters a transform filter is received, a message callback that returns true
// has integrated it, every other outcome is a drop with a reason.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <nodelet/nodelet.h>
#include <std_msgs/Header.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>
#include <Eigen/Geometry>

#include "occupancy_fusion/mapping/frame_statistics.h"
#include "occupancy_fusion/mapping/mapping_session.h"
#include "occupancy_fusion/mapping/scoped_openmp_threads.h"
#include "occupancy_fusion/params/parameter_source.h"
#include "occupancy_fusion/ros/map_publisher.h"
#include "occupancy_fusion/ros/map_registry.h"
#include "occupancy_fusion/ros/tf_buffer_pose_source.h"

namespace occupancy_fusion {

class MapperNodeletBase : public nodelet::Nodelet {
 protected:
  using DiagnosticsTask = std::function<void(diagnostic_updater::DiagnosticStatusWrapper&)>;

  // Acquires the shared map, lets `read_mapper_config` read the mapper's own configuration, then
  // reads ~queue_size, ~threads and ~publish_map (creating the MapPublisher when set) and starts
  // the tf2 listener. A std::invalid_argument from any of them is logged as fatal and rethrown.
  void setUpMapper(const std::function<void(const ParameterSource&)>& read_mapper_config);

  // Publishes the input statistics and `fill`'s status as diagnostics task `task_name` once a
  // second, under the hardware ID "map '<map name>'". `drop_reasons`: the mapper's own reasons to
  // drop a frame (besides the tf ones), reported from the start.
  void startDiagnostics(const std::string& task_name, const std::vector<std::string>& drop_reasons,
                        DiagnosticsTask fill);

  // The mapping session over the shared map, for `config`'s integrator settings (its frame_id and
  // map are the shared map's). Call it from setUpMapper's read_mapper_config.
  void startSession(MappingSessionConfig config);
  const MappingSession& session() const { return *session_; }

  // Integrates a frame (its pose looked up with poseInMap) through the session; a drop is counted
  // by the session's reason and warned about (throttled), naming `what`. Whether it integrated.
  template <class Frame>
  bool integrateFrame(const Frame& frame, const std::string& what) {
    FrameOutcome outcome;
    {
      const std::lock_guard<std::mutex> lock(session_mutex_);
      // ~threads: the manager's worker threads run every nodelet's callbacks, so this mapper's
      // OpenMP thread count is set for each frame on the thread that integrates it.
      const ScopedOpenMpThreads threads(threads_);
      outcome = session_->integrate(frame);
    }
    if (outcome.integrated) {
      // The stamp as the frame carries it (s, a double: within a microsecond of the message's).
      map_->noteIntegrated(frame.header.source, ros::Time(frame.header.stamp));
      return true;
    }
    frames_.countDropped(outcome.drop);
    NODELET_WARN_THROTTLE(5.0, "%s dropped: %s", what.c_str(), outcome.detail.c_str());
    return false;
  }

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
    // Registered before the filter connects to `input`, so a backwards jump clears the tf buffer
    // before the filter asks it about the frame.
    input.registerCallback([this](const typename Message::ConstPtr& message) {
      frames_.countReceived();
      noteReceivedStamp(message->header);
    });
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

  // The frame a sensor's pose is needed in: the map's; with reanchoring from a SLAM path, the
  // odometry's (the session places each frame by odom -> sensor and the path's corrections, and
  // a system that publishes a path need not publish map -> odom).
  std::string placementFrame() const;

  // The usual filter: into placementFrame(). A message without a transform in time is warned
  // about (throttled), naming it `what` ("cloud", "depth image").
  template <class Message, class Input>
  std::unique_ptr<tf2_ros::MessageFilter<Message>> makeMapFrameFilter(
      Input& input, const std::string& what, std::function<bool(const Message&)> on_message) {
    const std::string target = placementFrame();
    return makeTransformFilter<Message>(
        input, {target}, std::move(on_message), [this, what, target](const Message& m) {
          NODELET_WARN_THROTTLE(5.0, "no transform from '%s' to '%s' at %.3f: %s dropped",
                                m.header.frame_id.c_str(), target.c_str(), m.header.stamp.toSec(),
                                what.c_str());
        });
  }

  // The pose of `sensor_frame` (by default the message's frame) in `frame` (by default
  // placementFrame()) at the message's exact stamp, for the frame's T_map_sensor: the session then
  // checks it (a pose that is not finite is dropped there; with reanchoring it places the frame
  // by odometry itself). Without one, the message is counted as dropped
  // (a tf failure), warned about (throttled) and nullopt returned. A template so that each mapper
  // keeps its own throttled warning.
  template <class Message>
  std::optional<Eigen::Isometry3d> poseInMap(const Message& message, const std::string& what,
                                             const std::string& sensor_frame = "",
                                             const std::string& frame = "") {
    try {
      return tf2::transformToEigen(tf_buffer_->lookupTransform(
          frame.empty() ? placementFrame() : frame,
          sensor_frame.empty() ? message.header.frame_id : sensor_frame, message.header.stamp));
    } catch (const tf2::TransformException& error) {
      frames_.countDropped(FrameStatistics::kTfLookup);
      NODELET_WARN_THROTTLE(5.0, "%s dropped: %s", what.c_str(), error.what());
      return std::nullopt;
    }
  }

  // A sensor's stamp going back by more than this is a jump back in time (a looped bag), not
  // reordering.
  static constexpr double kBackwardsJumpSeconds = 1.0;

  SharedMap& map() const { return *map_; }
  int queueSize() const { return queue_size_; }
  const tf2_ros::Buffer& tfBuffer() const { return *tf_buffer_; }

 private:
  // Detects time jumping backwards in a sensor's own stamps (a bag played in a loop without
  // /clock; with /clock, tf2's TransformListener clears its buffer itself when ros::Time jumps
  // back): the tf buffer, which would refuse the older transforms, is cleared and mapping goes
  // on.
  void noteReceivedStamp(const std_msgs::Header& header);
  static const char* tfDropReason(tf2_ros::filter_failure_reasons::FilterFailureReason reason);

  std::shared_ptr<SharedMap> map_;
  int queue_size_ = 5;
  int threads_ = 0;
  std::unique_ptr<MapPublisher> map_publisher_;
  // Outlives the derived mappers' message filters, which unregister from it when they go.
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  // With reanchoring: the session looks up the odometry and map -> odom itself, here.
  std::unique_ptr<TfBufferPoseSource> pose_source_;
  FrameStatistics frames_;
  // The nodelet's callbacks run on its one-threaded queue; the lock keeps the session safe should
  // a mapper ever take a multi-threaded one.
  std::mutex session_mutex_;
  std::unique_ptr<MappingSession> session_;
  std::mutex stamps_mutex_;
  std::map<std::string, ros::Time> newest_received_;  // per frame_id
  std::size_t backwards_jumps_ = 0;                   // guarded by stamps_mutex_
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;
};

}  // namespace occupancy_fusion
