// CartographerPathRelay nodelet: polls cartographer's trajectory_query service (the optimised
// poses of its trajectory nodes, with their stamps) and republishes them as a latched
// nav_msgs/Path on `path` whenever the pose graph moved them, for reanchoring:=path.
// cartographer publishes its graph otherwise only as markers (trajectory_node_list), which carry
// neither the nodes' orientations nor their stamps.
#include <cmath>
#include <optional>

#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <pluginlib/class_list_macros.hpp>

#include "occupancy_fusion/CartographerTrajectoryQuery.h"
#include "occupancy_fusion/ros/cartographer_trajectory.h"

namespace occupancy_fusion {

class CartographerPathRelay : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& node_handle = getNodeHandle();
    ros::NodeHandle& parameters = getPrivateNodeHandle();
    trajectory_id_ = parameters.param("trajectory_id", 0);
    min_translation_ =
        positiveOr(parameters.param("min_translation", 0.001), 0.001, "min_translation");
    min_rotation_ = positiveOr(parameters.param("min_rotation", 0.001), 0.001, "min_rotation");
    const double period = positiveOr(parameters.param("period", 1.0), 1.0, "period");
    client_ = node_handle.serviceClient<CartographerTrajectoryQuery>("trajectory_query");
    publisher_ = node_handle.advertise<nav_msgs::Path>("path", 1, /*latch=*/true);
    timer_ =
        node_handle.createWallTimer(ros::WallDuration(period), &CartographerPathRelay::query, this);
    NODELET_INFO("relaying trajectory %d of %s to %s every %.2f s", trajectory_id_,
                 client_.getService().c_str(), publisher_.getTopic().c_str(), period);
  }

  double positiveOr(double value, double fallback, const char* name) const {
    if (std::isfinite(value) && value > 0.0) return value;
    NODELET_ERROR("~%s must be a positive number, not %g: using %g", name, value, fallback);
    return fallback;
  }

  void query(const ros::WallTimerEvent& /*event*/) {
    CartographerTrajectoryQuery call;
    call.request.trajectory_id = trajectory_id_;
    if (!client_.call(call)) {
      NODELET_WARN_THROTTLE(10.0, "no answer from %s: is cartographer_node running (1.0 or later)?",
                            client_.getService().c_str());
      return;
    }
    if (call.response.status.code != 0) {
      NODELET_WARN_THROTTLE(10.0, "%s answered code %d: %s", client_.getService().c_str(),
                            call.response.status.code, call.response.status.message.c_str());
      return;
    }
    std::size_t left_out = 0;
    nav_msgs::Path path = trajectoryPath(call.response.trajectory, &left_out);
    if (left_out > 0) {
      NODELET_WARN_THROTTLE(10.0,
                            "%zu of trajectory %d's %zu nodes left out (another frame, no "
                            "stamp or not a rigid pose)",
                            left_out, trajectory_id_, call.response.trajectory.size());
    }
    if (path.poses.empty()) return;
    if (last_ && !pathMoved(*last_, path, min_translation_, min_rotation_)) return;
    publisher_.publish(path);
    if (!last_)
      NODELET_INFO("first path: %zu nodes in %s", path.poses.size(), path.header.frame_id.c_str());
    last_ = std::move(path);
  }

  int trajectory_id_ = 0;
  double min_translation_ = 0.001;
  double min_rotation_ = 0.001;
  ros::ServiceClient client_;
  ros::Publisher publisher_;
  ros::WallTimer timer_;
  std::optional<nav_msgs::Path> last_;
};

}  // namespace occupancy_fusion

PLUGINLIB_EXPORT_CLASS(occupancy_fusion::CartographerPathRelay, nodelet::Nodelet)
