// DepthMapper nodelet: depth images (image, through image_transport, with camera_info) -> tf2
// message filter (pose of the optical frame in the map frame at the image stamp) -> the mapping
// session (PyramidDepthIntegrator, Pirker et al.'s per-voxel inverse sensor model) -> shared map.
// With ~publish_map it also publishes the map, for a mapper that runs alone in its own process.
//
// Why not image_transport::CameraSubscriber itself: it hands out (image, camera_info) pairs,
// and tf2_ros::MessageFilter holds back messages of one type only. So the image goes through
// image_transport's SubscriberFilter (same transports and ~image_transport parameter as a
// CameraSubscriber) into the tf2 filter, and camera_info, subscribed where a CameraSubscriber
// looks for it (the sibling of the image topic), fills a short cache. An image is paired with
// the camera_info of the same stamp, as CameraSubscriber's exact synchroniser pairs them; if
// that one was lost, with the latest, since a depth camera's intrinsics do not change while it
// runs. An image never waits for camera_info (one waiting stage, the tf2 filter, is enough).
#include <atomic>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <image_transport/camera_common.h>
#include <image_transport/image_transport.h>
#include <image_transport/subscriber_filter.h>
#include <message_filters/cache.h>
#include <message_filters/subscriber.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <pluginlib/class_list_macros.hpp>

#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"
#include "occupancy_fusion/params/depth_config_reader.h"
#include "occupancy_fusion/ros/conversions.h"
#include "occupancy_fusion/ros/depth_messages.h"
#include "occupancy_fusion/ros/mapper_nodelet_base.h"

namespace occupancy_fusion {

class DepthMapper : public MapperNodeletBase {
 private:
  using Image = sensor_msgs::Image;
  using CameraInfo = sensor_msgs::CameraInfo;
  static constexpr const char* kNoCameraInfo = "no camera_info";
  static constexpr const char* kEncoding = "encoding";
  static constexpr const char* kBadCameraInfo = "camera_info";

  void onInit() override {
    setUpMapper([this](const ParameterSource& parameters) {
      MappingSessionConfig session;
      session.depth = readPyramidDepthConfig(parameters);
      startSession(session);
    });
    subscribe(queueSize());
    startDiagnostics(
        "depth mapping", {kNoCameraInfo, kEncoding, kBadCameraInfo},
        [this](diagnostic_updater::DiagnosticStatusWrapper& status) { fillDiagnostics(status); });
    NODELET_INFO("mapping depth images from '%s' with camera_info from '%s' (%s method)",
                 image_subscriber_.getTopic().c_str(), camera_info_subscriber_.getTopic().c_str(),
                 toString(session().config().depth.method).c_str());
  }

  void subscribe(int queue_size) {
    image_transport_ = std::make_unique<image_transport::ImageTransport>(getNodeHandle());
    // ~image_transport picks the transport, as for a CameraSubscriber.
    image_subscriber_.subscribe(
        *image_transport_, "image", queue_size,
        image_transport::TransportHints("raw", ros::TransportHints(), getPrivateNodeHandle()));
    const std::string camera_info_topic =
        image_transport::getCameraInfoTopic(getNodeHandle().resolveName("image"));
    camera_info_subscriber_.subscribe(getNodeHandle(), camera_info_topic, queue_size);
    // Long enough to hold the camera_info of every image the tf2 filter may still hold back.
    camera_infos_.setCacheSize(static_cast<unsigned int>(2 * queue_size + 2));
    camera_infos_.connectInput(camera_info_subscriber_);
    // After the cache's own callback: once counted, a camera_info is in the cache.
    camera_info_subscriber_.registerCallback(
        [this](const CameraInfo::ConstPtr&) { ++camera_infos_received_; });
    tf_filter_ = makeMapFrameFilter<Image>(image_subscriber_, "depth image",
                                           [this](const Image& image) { return onImage(image); });
  }

  // The camera_info stamped like the image, else the latest one; null when none arrived yet.
  CameraInfo::ConstPtr cameraInfoFor(const Image& image) const {
    const std::vector<CameraInfo::ConstPtr> same_stamp =
        camera_infos_.getInterval(image.header.stamp, image.header.stamp);
    if (!same_stamp.empty()) return same_stamp.back();
    return camera_infos_.getElemBeforeTime(ros::TIME_MAX);
  }

  // Whether the image was integrated.
  bool onImage(const Image& image) {
    const CameraInfo::ConstPtr info = cameraInfoFor(image);
    if (!info) {
      countDropped(kNoCameraInfo);
      NODELET_WARN_THROTTLE(5.0, "no camera_info received yet on '%s': depth image dropped",
                            camera_info_subscriber_.getTopic().c_str());
      return false;
    }
    const std::optional<Eigen::Isometry3d> T_map_camera = poseInMap(image, "depth image");
    if (!T_map_camera) return false;
    DepthImageFrame frame;
    frame.header = frameHeaderOf(image.header, "depth", image_subscriber_.getTopic());
    frame.header.T_map_sensor = *T_map_camera;
    try {
      frame.camera = depthCameraIntrinsics(*info, image);
      // Into the message's buffer where it is metres already, else into frame.depth.
      frame.pixels = depthInMetres(image, &frame.depth);
    } catch (const DepthImageRejected& error) {
      countDropped(error.reason() == DepthImageRejected::Reason::kEncoding ? kEncoding
                                                                           : kBadCameraInfo);
      NODELET_ERROR_THROTTLE(5.0, "depth image on '%s' dropped: %s",
                             image_subscriber_.getTopic().c_str(), error.what());
      return false;
    }
    if (!integrateFrame(frame, "depth image")) return false;
    last_stats_ = session().lastDepthStats();
    NODELET_DEBUG("integrated a %dx%d depth image: %zu voxels in %.1f ms", frame.camera.width,
                  frame.camera.height, last_stats_.voxels_updated, last_stats_.milliseconds);
    return true;
  }

  void fillDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) {
    const FrameStatistics& frames = frameStatistics();
    if (frames.dropped(kEncoding) > 0 || frames.dropped(kBadCameraInfo) > 0) {
      status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "mapping; bad images dropped");
    } else if (frames.integrated() == 0 && frames.dropped(kNoCameraInfo) > 0) {
      status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "waiting for camera_info");
    } else {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, "mapping");
    }
    status.add("images integrated", frames.integrated());
    status.add("camera_info received", camera_infos_received_.load());
    status.add("images dropped (encoding)", frames.dropped(kEncoding));
    status.add("images dropped (camera_info)", frames.dropped(kBadCameraInfo));
    status.add("last image voxels updated", last_stats_.voxels_updated);
    status.add("last image blocks updated", last_stats_.blocks_updated);
    status.add("last image ms", last_stats_.milliseconds);
  }

  std::unique_ptr<image_transport::ImageTransport> image_transport_;
  image_transport::SubscriberFilter image_subscriber_;
  message_filters::Subscriber<CameraInfo> camera_info_subscriber_;
  message_filters::Cache<CameraInfo> camera_infos_;
  std::atomic<std::size_t> camera_infos_received_{0};
  std::unique_ptr<tf2_ros::MessageFilter<Image>> tf_filter_;

  DepthIntegrationStats last_stats_;
};

}  // namespace occupancy_fusion

PLUGINLIB_EXPORT_CLASS(occupancy_fusion::DepthMapper, nodelet::Nodelet)
