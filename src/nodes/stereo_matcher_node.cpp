// Runs the occupancy_fusion/StereoMatcher nodelet in its own process (stereo_image_proc's
// disparity node, for systems where that cannot be loaded).
#include "occupancy_fusion/ros/nodelet_main.h"

int main(int argc, char** argv) {
  return occupancy_fusion::runNodeletInOwnProcess(argc, argv, "stereo_matcher",
                                                  "occupancy_fusion/StereoMatcher");
}
