// main() of a node executable that runs one of the package's nodelets in its own process, as
// image_pipeline's nodes do: one implementation, run either in a nodelet manager or alone.
#pragma once

#include <exception>
#include <functional>

#include <nodelet/loader.h>
#include <ros/ros.h>

namespace occupancy_fusion {

// Sets the node's private parameters that differ from the nodelet's defaults when it runs alone;
// called after ros::init with the node's private handle, before the nodelet reads them.
using StandaloneDefaults = std::function<void(ros::NodeHandle& private_node_handle)>;

// Loads nodelet_type under this node's name (so the nodelet's private parameters are the node's
// ~ parameters, and command-line remappings apply) and spins. Returns main's exit status: 1 when
// the nodelet cannot be loaded or its onInit throws.
inline int runNodeletInOwnProcess(int argc, char** argv, const char* default_node_name,
                                  const char* nodelet_type,
                                  const StandaloneDefaults& set_defaults = nullptr) {
  ros::init(argc, argv, default_node_name);
  // Lives until spin returns: the last NodeHandle to go out of scope would shut the node down.
  ros::NodeHandle private_node_handle("~");
  if (set_defaults) set_defaults(private_node_handle);
  nodelet::Loader loader;
  try {
    if (!loader.load(ros::this_node::getName(), nodelet_type, ros::names::getRemappings(),
                     nodelet::V_string())) {
      return 1;
    }
  } catch (const std::exception& error) {
    ROS_FATAL("%s", error.what());
    return 1;
  }
  ros::spin();
  return 0;
}

}  // namespace occupancy_fusion
