// PointCloudMapper nodelet: cloud_in (sensor_msgs/PointCloud2) -> tf2 message filter into the map
// frame -> the mapping session (PointCloudIntegrator) -> shared map. With ~publish_map it also
// publishes the map, for a mapper that runs alone in its own process.
#include <atomic>
#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

#include <message_filters/subscriber.h>
#include <sensor_msgs/PointCloud2.h>
#include <pluginlib/class_list_macros.hpp>

#include "occupancy_fusion/integrators/point_cloud_integrator.h"
#include "occupancy_fusion/params/config_readers.h"
#include "occupancy_fusion/ros/conversions.h"
#include "occupancy_fusion/ros/mapper_nodelet_base.h"

namespace occupancy_fusion {

class PointCloudMapper : public MapperNodeletBase {
 private:
  using Cloud = sensor_msgs::PointCloud2;
  static constexpr const char* kInvalidCloud = "invalid cloud";

  void onInit() override {
    setUpMapper([this](const ParameterSource& parameters) {
      MappingSessionConfig session;
      session.point_cloud = readPointCloudIntegratorConfig(parameters);
      startSession(session);
    });
    cloud_subscriber_.subscribe(getNodeHandle(), "cloud_in", queueSize());
    tf_filter_ = makeMapFrameFilter<Cloud>(cloud_subscriber_, "cloud",
                                           [this](const Cloud& cloud) { return onCloud(cloud); });
    startDiagnostics(
        "point cloud mapping", {kInvalidCloud},
        [this](diagnostic_updater::DiagnosticStatusWrapper& status) { fillDiagnostics(status); });
  }

  // Whether the cloud was integrated.
  bool onCloud(const Cloud& cloud) {
    const std::optional<Eigen::Isometry3d> map_T_cloud = poseInMap(cloud, "cloud");
    if (!map_T_cloud) return false;
    PointCloudFrame frame;
    frame.header = frameHeaderOf(cloud.header, "point_cloud", cloud_subscriber_.getTopic());
    frame.header.T_map_sensor = *map_T_cloud;
    try {
      frame.points = transformedPoints(cloud, Eigen::Isometry3d::Identity());
    } catch (const std::invalid_argument& error) {
      countDropped(kInvalidCloud);
      NODELET_WARN_THROTTLE(5.0, "cloud dropped: %s", error.what());
      return false;
    }
    if (!integrateFrame(frame, "cloud")) return false;
    last_stats_ = session().lastPointCloudStats();
    skipped_points_ += last_stats_.skipped_points;
    NODELET_DEBUG("integrated %zu points (%zu skipped) in %.1f ms", last_stats_.points,
                  last_stats_.skipped_points, last_stats_.seconds * 1e3);
    return true;
  }

  void fillDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "mapping");
    const FrameStatistics& frames = frameStatistics();
    status.add("clouds integrated", frames.integrated());
    status.add("clouds dropped", frames.droppedTotal());
    status.add("points skipped", skipped_points_.load());
    status.add("last cloud points", last_stats_.points);
    status.add("last cloud ms", last_stats_.seconds * 1e3);
  }

  message_filters::Subscriber<Cloud> cloud_subscriber_;
  std::unique_ptr<tf2_ros::MessageFilter<Cloud>> tf_filter_;

  std::atomic<std::size_t> skipped_points_{0};
  IntegrationStats last_stats_;
};

}  // namespace occupancy_fusion

PLUGINLIB_EXPORT_CLASS(occupancy_fusion::PointCloudMapper, nodelet::Nodelet)
