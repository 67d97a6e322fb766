// DepthMapper nodelet: depth images (image, through image_transport, with camera_info) -> tf2
// message filter (pose of the optical frame in the map frame at the image stamp) ->
// PyramidDepthIntegrator (Pirker et al.'s per-voxel inverse sensor model) -> shared map. With
// ~publish_map it also publishes the map, for a mapper that runs alone in its own process.
//
// Why not image_transport::CameraSubscriber itself: it hands out (image, camera_info) pairs,
// and tf2_ros::MessageFilter holds back messages of one type only. So the image goes through
// image_transport's SubscriberFilter (same transports and ~image_transport parameter as a
// CameraSubscriber) into the tf2 filter, and camera_info, subscribed where a CameraSubscriber
// looks for it (the sibling of the image topic), fills a short cache. An image is paired with
// the camera_info of the same stamp, as CameraSubscriber's exact synchroniser pairs them; if
// that one was lost, with the latest, since a depth camera's intrinsics do not change while it
// runs. An image never waits for camera_info (one waiting stage, the tf2 filter, is enough).
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

#include "occupancy_fusion/integrators/pyramid_depth_integrator.h"
#include "occupancy_fusion/params/depth_config_reader.h"
#include "occupancy_fusion/ros/mapper_nodelet_base.h"

namespace occupancy_fusion {
namespace {

// Why an image was not integrated; each reason has its own counter in the diagnostics.
class DroppedImage : public std::runtime_error {
 public:
  enum class Reason { kEncoding, kCameraInfo };
  DroppedImage(Reason reason, const std::string& message)
      : std::runtime_error(message), reason_(reason) {}
  Reason reason() const { return reason_; }

 private:
  Reason reason_;
};

bool hostIsBigEndian() {
  const std::uint16_t probe = 1;
  std::uint8_t first_byte = 0;
  std::memcpy(&first_byte, &probe, 1);
  return first_byte == 0;
}

// The image's pixels as z-depth in metres, in `storage` when they need converting or copying.
DepthImageView depthInMetres(const sensor_msgs::Image& image, std::vector<float>* storage) {
  namespace enc = sensor_msgs::image_encodings;
  const bool millimetres = image.encoding == enc::TYPE_16UC1 || image.encoding == enc::MONO16;
  const bool metres = image.encoding == enc::TYPE_32FC1;
  if (!millimetres && !metres) {
    throw DroppedImage(
        DroppedImage::Reason::kEncoding,
        "encoding '" + image.encoding + "' is not a depth encoding (16UC1 in mm or 32FC1 in m)");
  }
  if (static_cast<bool>(image.is_bigendian) != hostIsBigEndian()) {
    throw DroppedImage(DroppedImage::Reason::kEncoding,
                       "encoding '" + image.encoding + "' with foreign byte order");
  }
  const std::size_t pixel_bytes = millimetres ? 2 : 4;
  if (image.step < image.width * pixel_bytes ||
      image.data.size() < static_cast<std::size_t>(image.step) * image.height) {
    throw DroppedImage(DroppedImage::Reason::kEncoding,
                       "encoding '" + image.encoding + "': step or data size too small");
  }
  const int width = static_cast<int>(image.width);
  const int height = static_cast<int>(image.height);
  if (metres && image.step % sizeof(float) == 0) {
    // Zero copy: the message's buffer is suitably aligned (std::allocator) and rows are whole
    // floats apart.
    return {width, height, reinterpret_cast<const float*>(image.data.data()),
            static_cast<int>(image.step / sizeof(float))};
  }
  const std::size_t row_bytes = static_cast<std::size_t>(width) * pixel_bytes;
  if (metres) {  // rows padded to a step that is no whole number of floats
    storage->resize(static_cast<std::size_t>(width) * height);
    for (int v = 0; v < height; ++v) {
      std::memcpy(storage->data() + static_cast<std::size_t>(v) * width,
                  image.data.data() + static_cast<std::size_t>(v) * image.step, row_bytes);
    }
  } else {
    std::vector<std::uint16_t> millimetres_dense(static_cast<std::size_t>(width) * height);
    for (int v = 0; v < height; ++v) {
      std::memcpy(millimetres_dense.data() + static_cast<std::size_t>(v) * width,
                  image.data.data() + static_cast<std::size_t>(v) * image.step, row_bytes);
    }
    *storage = depthFromMillimetres(millimetres_dense.data(), millimetres_dense.size());
  }
  return {width, height, storage->data(), width};
}

// Intrinsics from K of a camera_info that must describe this very image.
CameraIntrinsics intrinsicsFor(const sensor_msgs::CameraInfo& info,
                               const sensor_msgs::Image& image) {
  using Reason = DroppedImage::Reason;
  if (info.width != image.width || info.height != image.height) {
    throw DroppedImage(Reason::kCameraInfo, "camera_info is " + std::to_string(info.width) + "x" +
                                                std::to_string(info.height) + " but the image " +
                                                std::to_string(image.width) + "x" +
                                                std::to_string(image.height));
  }
  if (info.binning_x > 1 || info.binning_y > 1 || info.roi.width != 0 || info.roi.height != 0) {
    throw DroppedImage(Reason::kCameraInfo, "camera_info with binning or ROI is not supported");
  }
  CameraIntrinsics camera;
  camera.width = static_cast<int>(info.width);
  camera.height = static_cast<int>(info.height);
  camera.fx = info.K[0];
  camera.fy = info.K[4];
  camera.cx = info.K[2];
  camera.cy = info.K[5];
  if (!(camera.fx > 0.0) || !(camera.fy > 0.0)) {
    throw DroppedImage(Reason::kCameraInfo,
                       "camera_info has focal length fx = " + std::to_string(camera.fx) +
                           ", fy = " + std::to_string(camera.fy));
  }
  try {
    camera.validate();
  } catch (const std::invalid_argument& error) {
    throw DroppedImage(Reason::kCameraInfo, std::string("camera_info: ") + error.what());
  }
  return camera;
}

}  // namespace

class DepthMapper : public MapperNodeletBase {
 private:
  using Image = sensor_msgs::Image;
  using CameraInfo = sensor_msgs::CameraInfo;
  static constexpr const char* kNoCameraInfo = "no camera_info";
  static constexpr const char* kEncoding = "encoding";
  static constexpr const char* kBadCameraInfo = "camera_info";

  void onInit() override {
    setUpMapper([this](const ParameterSource& parameters) {
      integrator_ = std::make_unique<PyramidDepthIntegrator>(readPyramidDepthConfig(parameters));
    });
    subscribe(queueSize());
    startDiagnostics(
        "depth mapping", {kNoCameraInfo, kEncoding, kBadCameraInfo},
        [this](diagnostic_updater::DiagnosticStatusWrapper& status) { fillDiagnostics(status); });
    NODELET_INFO("mapping depth images from '%s' with camera_info from '%s' (%s method)",
                 image_subscriber_.getTopic().c_str(), camera_info_subscriber_.getTopic().c_str(),
                 toString(integrator_->config().method).c_str());
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
    try {
      integrate(image, *info, *T_map_camera);
      return true;
    } catch (const DroppedImage& error) {
      countDropped(error.reason() == DroppedImage::Reason::kEncoding ? kEncoding : kBadCameraInfo);
      NODELET_ERROR_THROTTLE(5.0, "depth image on '%s' dropped: %s",
                             image_subscriber_.getTopic().c_str(), error.what());
      return false;
    }
  }

  void integrate(const Image& image, const CameraInfo& info,
                 const Eigen::Isometry3d& T_map_camera) {
    const CameraIntrinsics camera = intrinsicsFor(info, image);
    std::vector<float> storage;
    const DepthImageView depth = depthInMetres(image, &storage);
    last_stats_ = integrator_->integrate(depth, camera, T_map_camera, &map().voxels());
    NODELET_DEBUG("integrated a %dx%d depth image: %zu voxels in %.1f ms", camera.width,
                  camera.height, last_stats_.voxels_updated, last_stats_.milliseconds);
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
    status.add("images dropped (encoding)", frames.dropped(kEncoding));
    status.add("images dropped (camera_info)", frames.dropped(kBadCameraInfo));
    status.add("last image voxels updated", last_stats_.voxels_updated);
    status.add("last image blocks updated", last_stats_.blocks_updated);
    status.add("last image ms", last_stats_.milliseconds);
  }

  std::unique_ptr<PyramidDepthIntegrator> integrator_;
  std::unique_ptr<image_transport::ImageTransport> image_transport_;
  image_transport::SubscriberFilter image_subscriber_;
  message_filters::Subscriber<CameraInfo> camera_info_subscriber_;
  message_filters::Cache<CameraInfo> camera_infos_;
  std::unique_ptr<tf2_ros::MessageFilter<Image>> tf_filter_;

  DepthIntegrationStats last_stats_;
};

}  // namespace occupancy_fusion

PLUGINLIB_EXPORT_CLASS(occupancy_fusion::DepthMapper, nodelet::Nodelet)
