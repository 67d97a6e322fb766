// Runs the occupancy_fusion/Simulator nodelet in its own process, under this node's name.
#include <exception>

#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "simulator");
  nodelet::Loader loader;
  try {
    if (!loader.load(ros::this_node::getName(), "occupancy_fusion/Simulator",
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
