// Runs the occupancy_fusion/CartographerPathRelay nodelet in its own process: cartographer's
// optimised trajectory (trajectory_query) republished as a nav_msgs/Path for reanchoring:=path.
#include "occupancy_fusion/ros/nodelet_main.h"

int main(int argc, char** argv) {
  return occupancy_fusion::runNodeletInOwnProcess(argc, argv, "cartographer_path_relay",
                                                  "occupancy_fusion/CartographerPathRelay");
}
