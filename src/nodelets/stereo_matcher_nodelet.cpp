// StereoMatcher nodelet: left and right camera images with their camera_infos (exact-time
// synchronised) -> rectification from the camera_infos (unless ~rectify is false) -> the core's
// StereoMatcher (OpenCV StereoSGBM or StereoBM) -> stereo_msgs/DisparityImage on `disparity`,
// with its fields filled as stereo_image_proc fills them. It stands in for stereo_image_proc's
// disparity nodelet where that cannot be loaded (Debian ships it without its plugin description)
// and runs in the mapping manager in front of the DisparityMapper, which receives the message
// without a copy.
//
// Inputs are exact-time synchronised, as stereo_image_proc does by default: a stereo camera
// triggers both sensors together and stamps the four messages alike; pairing by approximate time
// would match images of different instants, whose disparities are wrong wherever anything moved.
// Pairs that never complete are reported (throttled) naming the inputs that are missing.
#include <atomic>
#include <memory>
#include <stdexcept>
#include <string>

#include <image_transport/image_transport.h>
#include <image_transport/subscriber_filter.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <stereo_msgs/DisparityImage.h>
#include <boost/bind/bind.hpp>
#include <boost/make_shared.hpp>
#include <pluginlib/class_list_macros.hpp>

#include "occupancy_fusion/params/stereo_matcher_config_reader.h"
#include "occupancy_fusion/ros/ros_parameter_source.h"
#include "occupancy_fusion/ros/stereo_images.h"
#include "occupancy_fusion/sensors/stereo_matcher.h"
#include "occupancy_fusion/sensors/stereo_rectification.h"

namespace occupancy_fusion {

class StereoMatcherNodelet : public nodelet::Nodelet {
 private:
  using Image = sensor_msgs::Image;
  using CameraInfo = sensor_msgs::CameraInfo;
  using ExactPolicy =
      message_filters::sync_policies::ExactTime<Image, CameraInfo, Image, CameraInfo>;
  // How often unpaired inputs are reported, s (wall time).
  static constexpr double kReportPeriod = 5.0;

  void onInit() override {
    ros::NodeHandle& node_handle = getNodeHandle();
    ros::NodeHandle& private_node_handle = getPrivateNodeHandle();
    int queue_size = 5;
    try {
      const RosParameterSource parameters(private_node_handle);
      matcher_ = std::make_unique<StereoMatcher>(readStereoMatcherConfig(parameters));
      parameters.get("rectify", &rectify_);
      parameters.get("queue_size", &queue_size);
      if (queue_size < 1) {
        throw std::invalid_argument("queue_size must be at least 1, not " +
                                    std::to_string(queue_size));
      }
    } catch (const std::invalid_argument& error) {
      NODELET_FATAL("%s", error.what());
      throw;
    }
    const StereoMatcherConfig& config = matcher_->config();
    const std::string mode = config.algorithm == StereoAlgorithm::kSemiGlobal
                                 ? " (" + toString(config.sgbm_mode) + ")"
                                 : std::string();
    NODELET_INFO("%s%s, window %d px, disparities %d..%d, %s images",
                 toString(config.algorithm).c_str(), mode.c_str(), config.correlation_window_size,
                 config.min_disparity, config.min_disparity + config.disparity_range - 1,
                 rectify_ ? "raw (rectified here)" : "rectified");

    publisher_ = node_handle.advertise<stereo_msgs::DisparityImage>("disparity", 1);
    image_transport_ = std::make_unique<image_transport::ImageTransport>(node_handle);
    // ~image_transport picks the transport, as for stereo_image_proc.
    const image_transport::TransportHints hints("raw", ros::TransportHints(),
                                                getPrivateNodeHandle());
    left_image_.subscribe(*image_transport_, "left/image", queue_size, hints);
    right_image_.subscribe(*image_transport_, "right/image", queue_size, hints);
    left_info_.subscribe(node_handle, "left/camera_info", queue_size);
    right_info_.subscribe(node_handle, "right/camera_info", queue_size);
    left_image_.registerCallback([this](const Image::ConstPtr&) { ++received_[0]; });
    left_info_.registerCallback([this](const CameraInfo::ConstPtr&) { ++received_[1]; });
    right_image_.registerCallback([this](const Image::ConstPtr&) { ++received_[2]; });
    right_info_.registerCallback([this](const CameraInfo::ConstPtr&) { ++received_[3]; });
    synchronizer_ = std::make_unique<message_filters::Synchronizer<ExactPolicy>>(
        ExactPolicy(queue_size), left_image_, left_info_, right_image_, right_info_);
    synchronizer_->registerCallback(&StereoMatcherNodelet::onStereo, this);
    report_timer_ = node_handle.createWallTimer(ros::WallDuration(kReportPeriod),
                                                &StereoMatcherNodelet::reportUnpaired, this);
  }

  // Names the inputs that sent nothing over the last period while others did, or says that all
  // arrive but never with the same stamps.
  void reportUnpaired(const ros::WallTimerEvent& /*event*/) {
    const std::size_t paired = paired_.load();
    std::size_t counts[4];
    bool any_new = false;
    for (int i = 0; i < 4; ++i) {
      counts[i] = received_[i].load();
      any_new = any_new || counts[i] != reported_[i];
    }
    if (paired == reported_paired_ && any_new) {
      const std::string names[4] = {left_image_.getTopic(), left_info_.getTopic(),
                                    right_image_.getTopic(), right_info_.getTopic()};
      std::string missing;
      for (int i = 0; i < 4; ++i) {
        if (counts[i] == reported_[i]) missing += (missing.empty() ? "" : ", ") + names[i];
      }
      if (missing.empty()) {
        NODELET_WARN(
            "no synchronised stereo set in %.0f s: all four inputs arrive (%s, %s, %s, "
            "%s) but never with equal stamps; disparity needs exact-time inputs",
            kReportPeriod, names[0].c_str(), names[1].c_str(), names[2].c_str(), names[3].c_str());
      } else {
        NODELET_WARN("no synchronised stereo set in %.0f s: nothing received on %s", kReportPeriod,
                     missing.c_str());
      }
    }
    for (int i = 0; i < 4; ++i) reported_[i] = counts[i];
    reported_paired_ = paired;
  }

  void onStereo(const Image::ConstPtr& left_image, const CameraInfo::ConstPtr& left_info,
                const Image::ConstPtr& right_image, const CameraInfo::ConstPtr& right_info) {
    ++paired_;
    try {
      const CameraCalibration left_calibration = calibrationOf(*left_info, "left camera_info");
      const CameraCalibration right_calibration = calibrationOf(*right_info, "right camera_info");
      const StereoGeometry geometry = stereoGeometryOf(left_calibration, right_calibration);
      cv::Mat left = greyImageOf(*left_image, "left image");
      cv::Mat right = greyImageOf(*right_image, "right image");
      if (left.size() != right.size()) {
        throw std::invalid_argument("left image is " + std::to_string(left.cols) + "x" +
                                    std::to_string(left.rows) + " px, right image " +
                                    std::to_string(right.cols) + "x" + std::to_string(right.rows));
      }
      if (left.cols != left_calibration.width || left.rows != left_calibration.height) {
        throw std::invalid_argument("images are " + std::to_string(left.cols) + "x" +
                                    std::to_string(left.rows) + " px, their camera_infos " +
                                    std::to_string(left_calibration.width) + "x" +
                                    std::to_string(left_calibration.height));
      }
      const DisparityImageFields fields =
          disparityImageFields(matcher_->config(), geometry, left.cols, left.rows);
      if (rectify_) {
        cv::Mat left_rectified, right_rectified;
        left_rectification_.rectify(left_calibration, left, &left_rectified);
        right_rectification_.rectify(right_calibration, right, &right_rectified);
        left = left_rectified;
        right = right_rectified;
      }
      cv::Mat disparity;
      matcher_->match(left, right, geometry.principal_point_offset, &disparity);
      // Published as a shared pointer and never touched again: nodelets in the same manager
      // (the DisparityMapper) receive it without a copy.
      publisher_.publish(boost::make_shared<stereo_msgs::DisparityImage>(
          disparityImageOf(disparity, fields, left_image->header)));
    } catch (const std::invalid_argument& error) {
      ++dropped_;
      NODELET_ERROR_THROTTLE(5.0, "stereo pair dropped (%zu so far): %s", dropped_.load(),
                             error.what());
    }
  }

  std::unique_ptr<StereoMatcher> matcher_;
  bool rectify_ = true;
  CachedRectification left_rectification_, right_rectification_;
  ros::Publisher publisher_;
  std::unique_ptr<image_transport::ImageTransport> image_transport_;
  image_transport::SubscriberFilter left_image_, right_image_;
  message_filters::Subscriber<CameraInfo> left_info_, right_info_;
  std::unique_ptr<message_filters::Synchronizer<ExactPolicy>> synchronizer_;
  ros::WallTimer report_timer_;
  // Messages received per input (left image, left info, right image, right info), sets paired,
  // and their values at the last report.
  std::atomic<std::size_t> received_[4] = {};
  std::atomic<std::size_t> paired_{0};
  std::atomic<std::size_t> dropped_{0};
  std::size_t reported_[4] = {};
  std::size_t reported_paired_ = 0;
};

}  // namespace occupancy_fusion

PLUGINLIB_EXPORT_CLASS(occupancy_fusion::StereoMatcherNodelet, nodelet::Nodelet)
