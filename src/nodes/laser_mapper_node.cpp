// Runs the occupancy_fusion/LaserMapper nodelet in its own process. Alone in a process the mapper
// owns its map, so it publishes the map itself unless ~publish_map is set to false (in a nodelet
// manager, a MapServer nodelet does that instead).
#include "occupancy_fusion/ros/nodelet_main.h"

int main(int argc, char** argv) {
  return occupancy_fusion::runNodeletInOwnProcess(
      argc, argv, "laser_mapper", "occupancy_fusion/LaserMapper",
      [](ros::NodeHandle& private_node_handle) {
        if (!private_node_handle.hasParam("publish_map")) {
          private_node_handle.setParam("publish_map", true);
        }
      });
}
