// Runs the occupancy_fusion/MapServer nodelet in its own process, under this node's name, so its
// private parameters are this node's ~ parameters.
#include "occupancy_fusion/ros/nodelet_main.h"

int main(int argc, char** argv) {
  return occupancy_fusion::runNodeletInOwnProcess(argc, argv, "map_server",
                                                  "occupancy_fusion/MapServer");
}
