// benchmark robot-budget: the whole robot's budget in the ROS graph. Unlike the other workloads
// it needs a ROS master and several processes (mapping.launch's manager, rosbag play, the
// monitor), so its work is done by scripts/robot_budget.sh; this workload runs that script with
// this executable's own build, so that every benchmark of the package starts from one command.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

// The catkin build folder of this executable (<build>/devel/lib/occupancy_fusion/benchmark), or
// empty where it does not lie in one (an install space).
fs::path ownBuildFolder() {
  std::error_code error;
  const fs::path executable = fs::read_symlink("/proc/self/exe", error);
  if (error) return {};
  const fs::path package = executable.parent_path();
  const fs::path devel = package.parent_path().parent_path();
  if (package.filename() != "occupancy_fusion" || devel.filename() != "devel") return {};
  return devel.parent_path();
}

fs::path budgetScript(const CommandLine& args) {
  const fs::path script = args.has("script")
                              ? fs::path(args.value("script"))
                              : fs::path(OCCUPANCY_FUSION_SOURCE_DIR) / "scripts/robot_budget.sh";
  if (!fs::is_regular_file(script)) {
    throw UsageError("no robot budget script at " + script.string() +
                     " (it is part of the package's sources; give its path with --script)");
  }
  return script;
}

// The generated launch file's arguments, name:=value each.
std::vector<std::string> launchArguments(const CommandLine& args) {
  std::vector<std::string> arguments = args.values("launch_arg");
  for (const std::string& argument : arguments) {
    const std::size_t separator = argument.find(":=");
    if (separator == std::string::npos || separator == 0) {
      throw UsageError("--launch_arg takes name:=value, got '" + argument + "'");
    }
  }
  return arguments;
}

}  // namespace

int runRobotBudget(const CommandLine& args) {
  const int seconds = args.intValue("seconds", 60);
  if (seconds < 1 || seconds > 24 * 3600) {
    throw UsageError("--seconds must be between 1 and 86400, got " + std::to_string(seconds));
  }
  const std::string output = args.value("output", "output/robot_budget");
  const fs::path script = budgetScript(args);
  std::vector<std::string> command = {"/bin/bash", script.string(), std::to_string(seconds),
                                      output};
  for (const std::string& argument : launchArguments(args)) command.push_back(argument);
  // The script builds and installs unless told which build to use: this one.
  const char* given_build = std::getenv("BUDGET_BUILD_DIR");
  const fs::path build = given_build != nullptr ? fs::path(given_build) : ownBuildFolder();
  if (!build.empty()) setenv("BUDGET_BUILD_DIR", build.c_str(), 1);

  std::cerr << "robot budget: "
            << (build.empty() ? "" : "BUDGET_BUILD_DIR=" + build.string() + " ");
  for (const std::string& part : command) std::cerr << part << " ";
  std::cerr << "\n";
  if (args.intValue("dry_run", 0) != 0) return 0;
  std::vector<char*> argv;
  for (std::string& part : command) argv.push_back(part.data());
  argv.push_back(nullptr);
  execv(argv[0], argv.data());
  std::cerr << "robot budget: could not run " << argv[0] << "\n";
  return 1;
}

}  // namespace occupancy_fusion
