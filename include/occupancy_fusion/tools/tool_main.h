// The shared main() of the command-line tools (offline_mapper, simulate_recording,
// make_demo_recording): --help, ros::Time and how errors reach the user and the exit code.
#pragma once

#include <functional>
#include <string>

namespace occupancy_fusion {

// Prints `usage` and returns 0 when any argument is --help or -h. Otherwise initialises ros::Time
// (rosbag and tf2 stamp with it; no master is contacted) and returns run(argc, argv), except that
// a UsageError is printed as "<tool>: error: ..." with a pointer to --help and gives
// kUsageExitCode, and any other std::exception is printed as "<tool>: failed: ..." and gives 1.
int runTool(const std::string& tool, const char* usage, int argc, char** argv,
            const std::function<int(int, char**)>& run);

}  // namespace occupancy_fusion
