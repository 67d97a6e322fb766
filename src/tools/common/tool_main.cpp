#include "occupancy_fusion/tools/tool_main.h"

#include <exception>
#include <iostream>

#include <ros/time.h>

#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

bool wantsHelp(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") return true;
  }
  return false;
}

}  // namespace

int runTool(const std::string& tool, const char* usage, int argc, char** argv,
            const std::function<int(int, char**)>& run) {
  if (wantsHelp(argc, argv)) {
    std::cout << usage;
    return 0;
  }
  ros::Time::init();
  try {
    return run(argc, argv);
  } catch (const UsageError& error) {
    std::cerr << tool << ": error: " << error.what() << "\n(" << tool << " --help for usage)\n";
    return kUsageExitCode;
  } catch (const std::exception& error) {
    std::cerr << tool << ": failed: " << error.what() << "\n";
    return 1;
  }
}

}  // namespace occupancy_fusion
