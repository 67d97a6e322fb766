// The frames every input delivers to the mapping (mapping_session.h), whether a nodelet converted
// them from live messages (ros/*_messages.h) or a reader from a recording (tools/recording.h):
// one type per sensor kind, each with the header that says where it came from, its sensor frame
// and its time; the consumer interface with one callback per kind; and where poses come from. A
// new sensor kind is a new frame type here, its callback and its rules in the session.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "occupancy_fusion/sensors/camera_intrinsics.h"
#include "occupancy_fusion/sensors/depth_image.h"
#include "occupancy_fusion/sensors/disparity_image.h"
#include "occupancy_fusion/sensors/laser_scan.h"

namespace occupancy_fusion {

// What every frame carries: where it came from, its sensor frame and its time.
struct FrameHeader {
  std::string kind;      // sensor kind for the statistics: "point_cloud", "depth", "disparity",
                         // "laser"
  std::string source;    // topic or file it was read from
  std::string frame_id;  // the sensor's frame
  double stamp = 0.0;    // s; 0 means "latest available pose" (tf's convention)
  // The sensor's pose in the map frame when the input gives it: a recording's own poses (pose
  // files beside images, a log's corrected poses; the recording's world frame is taken as the
  // map frame), or what a nodelet looked up in tf at the message's exact stamp. Without it the
  // session asks its PoseSource for the sensor frame at stamp.
  std::optional<Eigen::Isometry3d> T_map_sensor;
};

// 3D points in the sensor frame. Non-finite points may be present: the integrator skips and
// counts them.
struct PointCloudFrame {
  FrameHeader header;
  std::vector<Eigen::Vector3f> points;
};

// A depth image (sensor_msgs/Image 16UC1 or 32FC1, a 7-Scenes PNG) already in metres.
struct DepthImageFrame {
  FrameHeader header;
  CameraIntrinsics camera;   // its size is the image's
  std::vector<float> depth;  // z-depth in m, row-major, 0 or NaN = no measurement
  // Pixels held elsewhere instead (a message's buffer, read without a copy): used when set, and
  // only while the call that is given the frame lasts.
  DepthImageView pixels;

  DepthImageView view() const {
    return pixels.depth != nullptr ? pixels
                                   : DepthImageView{camera.width, camera.height, depth.data(), 0};
  }
};

// A disparity image of the left camera of a rectified pair (stereo_msgs/DisparityImage, a PFM
// file with a Middlebury calib.txt).
struct DisparityFrame {
  FrameHeader header;
  StereoCamera camera;
  int width = 0;
  int height = 0;
  std::vector<float> disparity;  // px, row-major, NaN = no match

  DisparityImageView view() const { return {width, height, disparity.data(), 0}; }
};

// A 2D laser scan in the sensor's x-y plane (sensor_msgs/LaserScan, a CARMEN FLASER line).
struct LaserScanFrame {
  FrameHeader header;
  LaserScan scan;
};

// A pose at a time: a SLAM system's keyframe (T_map_base at its stamp), an odometry pose.
struct StampedPose {
  double stamp = 0.0;  // s
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

// Receives the frames of a recording, one callback per sensor kind.
class FrameConsumer {
 public:
  virtual ~FrameConsumer() = default;
  virtual void onPointCloud(const PointCloudFrame& frame) = 0;
  virtual void onDepthImage(const DepthImageFrame& frame) = 0;
  virtual void onDisparityImage(const DisparityFrame& frame) = 0;
  virtual void onLaserScan(const LaserScanFrame& frame) = 0;
  // A message that could not be decoded (e.g. a cloud without x/y/z): counted, not fatal.
  virtual void onUnreadable(const FrameHeader& header, const std::string& why) = 0;
  // A SLAM system's optimised keyframes, published at `stamp` (a nav_msgs/Path): the map's
  // reanchoring reads them; other consumers need not.
  virtual void onTrajectory(const std::vector<StampedPose>& /*keyframes*/, double /*stamp*/) {}
};

// Where sensor poses come from (tf in a bag, odometry in a log, a poses file beside images).
class PoseSource {
 public:
  virtual ~PoseSource() = default;
  // The transform taking points from sensor_frame to target_frame at stamp; nullopt when it is
  // not available, with the reason in *why (one short line, e.g. the tf2 error).
  virtual std::optional<Eigen::Isometry3d> lookup(const std::string& target_frame,
                                                  const std::string& sensor_frame, double stamp,
                                                  std::string* why) const = 0;
};

// The PoseSource of recordings whose frames all carry their pose (T_map_sensor): it has none.
class NoPoseSource : public PoseSource {
 public:
  std::optional<Eigen::Isometry3d> lookup(const std::string&, const std::string&, double,
                                          std::string* why) const override {
    if (why != nullptr) *why = "the recording has no poses apart from those in its frames";
    return std::nullopt;
  }
};

}  // namespace occupancy_fusion
