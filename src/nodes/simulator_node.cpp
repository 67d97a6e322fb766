// Runs the occupancy_fusion/Simulator nodelet in its own process, under this node's name.
#include "occupancy_fusion/ros/nodelet_main.h"

int main(int argc, char** argv) {
  return occupancy_fusion::runNodeletInOwnProcess(argc, argv, "simulator",
                                                  "occupancy_fusion/Simulator");
}
