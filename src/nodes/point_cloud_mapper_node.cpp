// Runs the occupancy_fusion/PointCloudMapper nodelet in its own process. Alone in a process the
// mapper owns its map, so it publishes the map itself unless ~publish_map is set to false
// (in a nodelet manager, a MapServer nodelet does that instead).
#include <exception>

#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "point_cloud_mapper");
  ros::NodeHandle private_node_handle("~");
  if (!private_node_handle.hasParam("publish_map")) {
    private_node_handle.setParam("publish_map", true);
  }
  nodelet::Loader loader;
  try {
    if (!loader.load(ros::this_node::getName(), "occupancy_fusion/PointCloudMapper",
                     ros::names::getRemappings(), nodelet::V_string())) {
      return 1;
    }
  } catch (const std::exception& error) {
    ROS_FATAL("%s", error.what());
    return 1;
  }
  ros::spin();
  return 0;
}
