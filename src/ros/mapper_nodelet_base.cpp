#include "occupancy_fusion/ros/mapper_nodelet_base.h"

#include <algorithm>
#include <stdexcept>

#include "occupancy_fusion/params/config_readers.h"
#include "occupancy_fusion/ros/ros_parameter_source.h"
#include "occupancy_fusion/ros/shared_map_access.h"

namespace occupancy_fusion {

void MapperNodeletBase::setUpMapper(
    const std::function<void(const ParameterSource&)>& read_mapper_config) {
  const RosParameterSource parameters(getPrivateNodeHandle());
  bool publish_map = false;
  try {
    map_ = acquireSharedMap(parameters, getName());
    read_mapper_config(parameters);
    const MapperNodeletConfig nodelet_config = readMapperNodeletConfig(parameters);
    queue_size_ = nodelet_config.queue_size;
    threads_ = nodelet_config.threads;
    parameters.get("publish_map", &publish_map);
    if (publish_map) {
      map_publisher_ =
          std::make_unique<MapPublisher>(getNodeHandle(), getPrivateNodeHandle(), getName(), map_,
                                         readMapPublisherConfig(parameters));
    }
  } catch (const std::invalid_argument& error) {
    NODELET_FATAL("invalid parameter: %s", error.what());
    throw;
  }
  tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, getNodeHandle());
  if (session_ && map_->reanchoring() != nullptr) {
    pose_source_ = std::make_unique<TfBufferPoseSource>(*tf_buffer_);
    session_->setPoseSource(pose_source_.get());
    session_->setReanchoring(map_->reanchoring());
  }
}

std::string MapperNodeletBase::placementFrame() const {
  const ReanchoringConfig& reanchoring = map_->config().reanchoring;
  const bool by_path =
      map_->reanchoring() != nullptr && reanchoring.source == ReanchoringConfig::Source::kPath;
  return by_path ? reanchoring.odom_frame : map_->frameId();
}

void MapperNodeletBase::startSession(MappingSessionConfig config) {
  config.frame_id = map_->frameId();
  config.map = map_->config().voxels;
  config.reanchoring = map_->config().reanchoring;
  session_ =
      std::make_unique<MappingSession>(config, &map_->voxels(), &map_->layer(), nullptr, nullptr);
}

void MapperNodeletBase::startDiagnostics(const std::string& task_name,
                                         const std::vector<std::string>& drop_reasons,
                                         DiagnosticsTask fill) {
  frames_.addDropReasons({MappingSession::kDropDuplicateStamp, MappingSession::kDropPoseNotFinite});
  frames_.addDropReasons(drop_reasons);
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(getNodeHandle(),
                                                               getPrivateNodeHandle(), getName());
  diagnostics_->setHardwareID("map '" + map_->name() + "'");
  diagnostics_->add(task_name, [this, fill = std::move(fill)](
                                   diagnostic_updater::DiagnosticStatusWrapper& status) {
    for (const auto& [key, value] : frames_.report()) status.add(key, value);
    {
      const std::lock_guard<std::mutex> lock(stamps_mutex_);
      status.add("time jumps back (tf buffer cleared)", backwards_jumps_);
    }
    fill(status);
  });
  diagnostics_timer_ = getNodeHandle().createTimer(
      // force_update: Updater::update() waits until ROS time passes its next due time, which a
      // looped bag's clock, jumping back, never reaches again (roscpp resets this timer itself).
      ros::Duration(1.0), [this](const ros::TimerEvent&) { diagnostics_->force_update(); });
}

void MapperNodeletBase::noteReceivedStamp(const std_msgs::Header& header) {
  const std::lock_guard<std::mutex> lock(stamps_mutex_);
  const auto newest = newest_received_.find(header.frame_id);
  if (newest == newest_received_.end()) {
    newest_received_.emplace(header.frame_id, header.stamp);
    return;
  }
  const double back = (newest->second - header.stamp).toSec();
  if (back <= kBackwardsJumpSeconds) {
    newest->second = std::max(newest->second, header.stamp);
    return;
  }
  ++backwards_jumps_;
  tf_buffer_->clear();
  // Every sensor starts over: their next (earlier) stamps are no second jump.
  newest_received_ = {{header.frame_id, header.stamp}};
  if (session_) {
    const std::lock_guard<std::mutex> session_lock(session_mutex_);
    session_->forgetStamps();
  }
  NODELET_WARN_THROTTLE(5.0,
                        "time jumped back by %.3f s in the stamps of '%s' (a looped bag?): tf "
                        "buffer cleared, mapping goes on",
                        back, header.frame_id.c_str());
}

const char* MapperNodeletBase::tfDropReason(
    tf2_ros::filter_failure_reasons::FilterFailureReason reason) {
  switch (reason) {
    case tf2_ros::filter_failure_reasons::OutTheBack:
      return FrameStatistics::kTfTooOld;
    case tf2_ros::filter_failure_reasons::EmptyFrameID:
      return FrameStatistics::kTfNoFrameId;
    default:  // Unknown: pushed out of the queue or timed out while waiting for the transform
      return FrameStatistics::kTfQueue;
  }
}

}  // namespace occupancy_fusion
