// PointCloudMapper nodelet: cloud_in (sensor_msgs/PointCloud2) -> tf2 message filter into the map
// frame -> PointCloudIntegrator -> shared map. With ~publish_map it also publishes the map, for a
// mapper that runs alone in its own process.
#include <atomic>
#include <chrono>
#include <memory>
#include <stdexcept>

#include <diagnostic_updater/diagnostic_updater.h>
#include <message_filters/subscriber.h>
#include <nodelet/nodelet.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>
#include <pluginlib/class_list_macros.hpp>

#include "occupancy_fusion/integrators/point_cloud_integrator.h"
#include "occupancy_fusion/params/config_readers.h"
#include "occupancy_fusion/ros/conversions.h"
#include "occupancy_fusion/ros/map_publisher.h"
#include "occupancy_fusion/ros/ros_parameter_source.h"
#include "occupancy_fusion/ros/shared_map_access.h"

namespace occupancy_fusion {

class PointCloudMapper : public nodelet::Nodelet {
 private:
  using Cloud = sensor_msgs::PointCloud2;

  void onInit() override {
    const RosParameterSource parameters(getPrivateNodeHandle());
    int queue_size = 5;
    bool publish_map = false;
    try {
      map_ = acquireSharedMap(parameters, getName());
      integrator_ =
          std::make_unique<PointCloudIntegrator>(readPointCloudIntegratorConfig(parameters));
      parameters.get("queue_size", &queue_size);
      if (queue_size < 1) throw std::invalid_argument("queue_size must be >= 1");
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
    subscribe(queue_size);
    diagnostics_ = std::make_unique<diagnostic_updater::Updater>(getNodeHandle(),
                                                                 getPrivateNodeHandle(), getName());
    diagnostics_->setHardwareID("map '" + map_->name() + "'");
    diagnostics_->add("point cloud mapping", this, &PointCloudMapper::fillDiagnostics);
    diagnostics_timer_ = getNodeHandle().createTimer(
        ros::Duration(1.0), [this](const ros::TimerEvent&) { diagnostics_->update(); });
  }

  void subscribe(int queue_size) {
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, getNodeHandle());
    cloud_subscriber_.subscribe(getNodeHandle(), "cloud_in", queue_size);
    // Callbacks run on this nodelet's queue (the node handle's), not on the tf thread.
    tf_filter_ = std::make_unique<tf2_ros::MessageFilter<Cloud>>(
        cloud_subscriber_, *tf_buffer_, map_->frameId(), queue_size, getNodeHandle());
    tf_filter_->registerCallback([this](const Cloud::ConstPtr& cloud) { onCloud(*cloud); });
    tf_filter_->registerFailureCallback(
        [this](const Cloud::ConstPtr& cloud, tf2_ros::filter_failure_reasons::FilterFailureReason) {
          ++dropped_clouds_;
          NODELET_WARN_THROTTLE(5.0, "no transform from '%s' to '%s' at %.3f: cloud dropped",
                                cloud->header.frame_id.c_str(), map_->frameId().c_str(),
                                cloud->header.stamp.toSec());
        });
  }

  void onCloud(const Cloud& cloud) {
    Eigen::Isometry3d map_T_cloud;
    try {
      map_T_cloud = tf2::transformToEigen(
          tf_buffer_->lookupTransform(map_->frameId(), cloud.header.frame_id, cloud.header.stamp));
    } catch (const tf2::TransformException& error) {
      ++dropped_clouds_;
      NODELET_WARN_THROTTLE(5.0, "cloud dropped: %s", error.what());
      return;
    }
    std::vector<Eigen::Vector3f> points;
    try {
      points = transformedPoints(cloud, map_T_cloud);
    } catch (const std::invalid_argument& error) {
      ++dropped_clouds_;
      NODELET_WARN_THROTTLE(5.0, "cloud dropped: %s", error.what());
      return;
    }
    // The sensor sits at the origin of the cloud's frame.
    last_stats_ = integrator_->integrate(points, map_T_cloud.translation(), &map_->voxels());
    ++integrated_clouds_;
    skipped_points_ += last_stats_.skipped_points;
    NODELET_DEBUG("integrated %zu points (%zu skipped) in %.1f ms", last_stats_.points,
                  last_stats_.skipped_points, last_stats_.seconds * 1e3);
  }

  void fillDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "mapping");
    status.add("clouds integrated", integrated_clouds_.load());
    status.add("clouds dropped", dropped_clouds_.load());
    status.add("points skipped", skipped_points_.load());
    status.add("last cloud points", last_stats_.points);
    status.add("last cloud ms", last_stats_.seconds * 1e3);
  }

  std::shared_ptr<SharedMap> map_;
  std::unique_ptr<PointCloudIntegrator> integrator_;
  std::unique_ptr<MapPublisher> map_publisher_;

  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  message_filters::Subscriber<Cloud> cloud_subscriber_;
  std::unique_ptr<tf2_ros::MessageFilter<Cloud>> tf_filter_;

  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;
  std::atomic<std::size_t> integrated_clouds_{0};
  std::atomic<std::size_t> dropped_clouds_{0};
  std::atomic<std::size_t> skipped_points_{0};
  IntegrationStats last_stats_;
};

}  // namespace occupancy_fusion

PLUGINLIB_EXPORT_CLASS(occupancy_fusion::PointCloudMapper, nodelet::Nodelet)
