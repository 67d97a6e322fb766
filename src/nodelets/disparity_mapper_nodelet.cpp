// DisparityMapper nodelet: disparity (stereo_msgs/DisparityImage) -> tf2 message filter into the
// map frame -> the mapping session (VisibilityStereoIntegrator, Schauwecker & Zell 2014) -> shared
// map. The principal
// point comes from the left camera's camera_info. With ~publish_map it also publishes the map, for
// a mapper that runs alone in its own process.
//
// camera_info is cached (the last few messages), not time-synchronised with the disparity
// images: a rectified pair's intrinsics do not change while it runs, drivers publish camera_info
// at their own rate (or latched, once), and an exact-time synchroniser would drop every disparity
// image whose camera_info was lost or stamped differently. A disparity image takes the cached
// camera_info of its own stamp and frame if there is one (cameras of different sizes sharing a
// topic, or a message on the other topic arriving late), else the latest. Only the principal point
// and fy are taken from it; f and T come with each disparity image. A camera_info that does not fit
// the image (another size) is detected per frame, and the frame dropped.
#include <atomic>
#include <deque>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <message_filters/subscriber.h>
#include <sensor_msgs/CameraInfo.h>
#include <stereo_msgs/DisparityImage.h>
#include <pluginlib/class_list_macros.hpp>

#include "occupancy_fusion/integrators/stereo/visibility_stereo_integrator.h"
#include "occupancy_fusion/params/stereo_config_reader.h"
#include "occupancy_fusion/ros/conversions.h"
#include "occupancy_fusion/ros/disparity_messages.h"
#include "occupancy_fusion/ros/mapper_nodelet_base.h"

namespace occupancy_fusion {

class DisparityMapper : public MapperNodeletBase {
 private:
  using Disparity = stereo_msgs::DisparityImage;
  static constexpr const char* kInvalid = "invalid";
  static constexpr const char* kNoCameraInfo = "no camera_info";

  void onInit() override {
    setUpMapper([this](const ParameterSource& parameters) {
      MappingSessionConfig session;
      session.stereo = readVisibilityStereoConfig(parameters);
      startSession(session);
    });
    NODELET_INFO("stereo method '%s', input resolution %s",
                 toString(session().config().stereo.method).c_str(),
                 toString(session().config().stereo.disparity.input_resolution).c_str());
    subscribe();
    startDiagnostics(
        "disparity mapping", {kInvalid, kNoCameraInfo},
        [this](diagnostic_updater::DiagnosticStatusWrapper& status) { fillDiagnostics(status); });
  }

  // All callbacks run on this nodelet's single-threaded queue (getNodeHandle()), so the cached
  // camera_info needs no lock.
  void subscribe() {
    // As deep as the cache: with a queue of 1, camera_infos arriving while an image is integrated
    // were dropped, and images still waiting for tf lost the camera_info of their own stamp.
    camera_info_subscriber_ = getNodeHandle().subscribe<sensor_msgs::CameraInfo>(
        "camera_info", kCameraInfosKept, [this](const sensor_msgs::CameraInfo::ConstPtr& info) {
          camera_infos_.push_back(info);
          if (camera_infos_.size() > kCameraInfosKept) camera_infos_.pop_front();
          ++camera_infos_received_;
        });
    disparity_subscriber_.subscribe(getNodeHandle(), "disparity", queueSize());
    tf_filter_ = makeMapFrameFilter<Disparity>(
        disparity_subscriber_, "disparity image",
        [this](const Disparity& disparity) { return onDisparity(disparity); });
  }

  // The header of a DisparityImage is the left optical frame's (stereo_image_proc copies the left
  // image's header into both the message and its image). Whether the image was integrated.
  // See the file comment: same stamp and frame, else the latest (nullptr: none received yet).
  const sensor_msgs::CameraInfo* cameraInfoFor(const stereo_msgs::DisparityImage& message) const {
    for (auto it = camera_infos_.rbegin(); it != camera_infos_.rend(); ++it) {
      const std_msgs::Header& header = (*it)->header;
      if (header.stamp == message.header.stamp && header.frame_id == message.header.frame_id) {
        return it->get();
      }
    }
    return camera_infos_.empty() ? nullptr : camera_infos_.back().get();
  }

  bool onDisparity(const Disparity& message) {
    const sensor_msgs::CameraInfo* camera_info = cameraInfoFor(message);
    if (camera_info == nullptr) {
      countDropped(kNoCameraInfo);
      NODELET_WARN_THROTTLE(5.0, "no camera_info received yet on '%s': disparity images dropped",
                            camera_info_subscriber_.getTopic().c_str());
      return false;
    }
    DisparityFrame frame;
    frame.header = frameHeaderOf(message.header, "disparity", disparity_subscriber_.getTopic());
    frame.width = static_cast<int>(message.image.width);
    frame.height = static_cast<int>(message.image.height);
    try {
      frame.disparity = validDisparities(message);
      frame.camera = stereoCameraOf(message, *camera_info);
    } catch (const std::invalid_argument& error) {
      countDropped(kInvalid);
      NODELET_ERROR_THROTTLE(5.0, "disparity image dropped: %s", error.what());
      return false;
    }
    const std::optional<Eigen::Isometry3d> T_map_camera = poseInMap(message, "disparity image");
    if (!T_map_camera) return false;
    frame.header.T_map_sensor = *T_map_camera;
    if (!integrateFrame(frame, "disparity image")) return false;
    last_stats_ = session().lastStereoStats();
    skipped_points_ += last_stats_.skipped_points;
    dropped_uncertain_points_ += last_stats_.dropped_uncertain;
    NODELET_DEBUG("integrated %zu points (%zu skipped) in %.1f ms, cache hit rate %.2f",
                  last_stats_.points, last_stats_.skipped_points, last_stats_.milliseconds(),
                  last_stats_.cacheHitRate());
    return true;
  }

  void fillDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) {
    const FrameStatistics& frames = frameStatistics();
    const bool starved = camera_infos_.empty() && frames.dropped(kNoCameraInfo) > 0;
    if (starved) {
      status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "waiting for camera_info");
    } else {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, "mapping");
    }
    status.add("images integrated", frames.integrated());
    status.add("camera_info received", camera_infos_received_.load());
    status.add("images dropped (invalid)", frames.dropped(kInvalid));
    status.add("points skipped", skipped_points_.load());
    status.add("points dropped (sigma_z / z over max_depth_sigma_ratio)",
               dropped_uncertain_points_.load());
    status.add("last image points", last_stats_.points);
    status.add("last image rays stopped invisible", last_stats_.rays_invisible);
    status.add("last image voxels updated", last_stats_.updated_voxels);
    status.add("last image cache hit rate", last_stats_.cacheHitRate());
    status.add("last image ms", last_stats_.milliseconds());
    // Where the time went: which setting would shorten it (input_resolution for the conversion,
    // resolution for the walks).
    status.add("last image conversion ms", 1e3 * last_stats_.conversion_seconds);
    status.add("last image bundling ms", 1e3 * last_stats_.bundling_seconds);
    status.add("last image walks ms", 1e3 * last_stats_.walk_seconds);
    status.add("last image writing ms", 1e3 * last_stats_.write_seconds);
    status.add("map version", map().voxels().version());
  }

  ros::Subscriber camera_info_subscriber_;
  static constexpr std::size_t kCameraInfosKept = 8;
  std::deque<sensor_msgs::CameraInfo::ConstPtr> camera_infos_;  // oldest first
  std::atomic<std::size_t> camera_infos_received_{0};
  message_filters::Subscriber<Disparity> disparity_subscriber_;
  std::unique_ptr<tf2_ros::MessageFilter<Disparity>> tf_filter_;

  std::atomic<std::size_t> skipped_points_{0};
  std::atomic<std::size_t> dropped_uncertain_points_{0};
  StereoIntegrationStats last_stats_;
};

}  // namespace occupancy_fusion

PLUGINLIB_EXPORT_CLASS(occupancy_fusion::DisparityMapper, nodelet::Nodelet)
