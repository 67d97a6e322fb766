// `benchmark robot-budget`: runs the robot budget's script with this build, its arguments passed
// on; a stand-in script records what it was given (the real one needs a ROS graph and minutes).
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tool_test_support.h"

namespace occupancy_fusion {
namespace {

using test_support::makeTempDir;
using test_support::readText;
using test_support::RunResult;
using test_support::runTool;
namespace fs = std::filesystem;

// <build>/devel/lib/occupancy_fusion/benchmark -> <build>, links resolved as the running
// executable's own path has them.
fs::path buildFolderOfBenchmark() {
  return fs::canonical(BENCHMARK_PATH).parent_path().parent_path().parent_path().parent_path();
}

class RobotBudgetWorkload : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = makeTempDir();
    unsetenv("BUDGET_BUILD_DIR");
  }
  void TearDown() override {
    unsetenv("BUDGET_BUILD_DIR");
    fs::remove_all(dir_);
  }
  // A script that writes its arguments, one per line, and BUDGET_BUILD_DIR to args.txt, then
  // exits with `exit_code`.
  fs::path standInScript(int exit_code) const {
    const fs::path script = dir_ / "budget.sh";
    std::ofstream(script) << "printf '%s\\n' \"$@\" > '" << (dir_ / "args.txt").string() << "'\n"
                          << "echo \"build=$BUDGET_BUILD_DIR\" >> '" << (dir_ / "args.txt").string()
                          << "'\n"
                          << "exit " << exit_code << "\n";
    return script;
  }
  RunResult run(const std::string& arguments) const {
    return runTool(BENCHMARK_PATH, "robot-budget " + arguments, dir_);
  }
  fs::path dir_;
};

TEST_F(RobotBudgetWorkload, RunsTheScriptWithThisBuildAndPassesItsArgumentsOn) {
  const fs::path script = standInScript(3);
  const RunResult result =
      run("--seconds 30 --output out --launch_arg stereo_input:=half "
          "--launch_arg disparity:=false --script '" +
          script.string() + "'");
  EXPECT_EQ(result.exit_code, 3) << result.err;  // the script's own exit code
  EXPECT_EQ(readText(dir_ / "args.txt"), "30\nout\nstereo_input:=half\ndisparity:=false\nbuild=" +
                                             buildFolderOfBenchmark().string() + "\n");
}

TEST_F(RobotBudgetWorkload, KeepsAGivenBuildFolderAndDefaults) {
  const fs::path script = standInScript(0);
  setenv("BUDGET_BUILD_DIR", "/some/build", 1);
  const RunResult result = run("--script '" + script.string() + "'");
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(readText(dir_ / "args.txt"), "60\noutput/robot_budget\nbuild=/some/build\n");
}

TEST_F(RobotBudgetWorkload, FindsThePackagesScriptAndPrintsTheCommand) {
  const RunResult result = run("--seconds 5 --dry_run 1");
  EXPECT_EQ(result.exit_code, 0) << result.err;
  const fs::path script = fs::path(OCCUPANCY_FUSION_SOURCE_DIR) / "scripts/robot_budget.sh";
  ASSERT_TRUE(fs::is_regular_file(script));
  EXPECT_NE(result.err.find("BUDGET_BUILD_DIR=" + buildFolderOfBenchmark().string() +
                            " /bin/bash " + script.string() + " 5 output/robot_budget"),
            std::string::npos)
      << result.err;
  EXPECT_FALSE(fs::exists(dir_ / "output"));  // nothing run
}

TEST_F(RobotBudgetWorkload, RejectsBadArgumentsWithAUsageError) {
  const fs::path script = standInScript(0);
  const std::string with_script = " --script '" + script.string() + "'";
  for (const std::string& arguments :
       {"--seconds 0" + with_script, "--seconds x" + with_script,
        "--launch_arg stereo_input" + with_script, "--launch_arg :=half" + with_script,
        std::string("--script '") + (dir_ / "missing.sh").string() + "'"}) {
    const RunResult result = run(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments;
    EXPECT_NE(result.err.find("benchmark robot-budget: "), std::string::npos) << result.err;
    EXPECT_FALSE(fs::exists(dir_ / "args.txt")) << arguments;
  }
}

}  // namespace
}  // namespace occupancy_fusion
