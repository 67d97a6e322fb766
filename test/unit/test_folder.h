// A test fixture with a fresh folder of its own under the system's temporary folder, removed
// after the test. The name holds the process id and the test's name, so tests running in parallel
// never share a folder. Every file writer of the project writes a temporary file and renames it:
// the fixture fails a test that leaves one behind.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <string>

namespace occupancy_fusion {

class TestFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
    folder_ = std::filesystem::temp_directory_path() /
              (std::string("occupancy_fusion_") + test->test_suite_name() + "_" +
               std::to_string(::getpid()) + "_" + test->name());
    std::filesystem::remove_all(folder_);
    std::filesystem::create_directories(folder_);
  }
  void TearDown() override {
    for (const auto& entry : std::filesystem::directory_iterator(folder_)) {
      EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos)
          << "temporary file left behind: " << entry.path();
    }
    std::filesystem::remove_all(folder_);
  }
  std::string path(const std::string& name) const { return (folder_ / name).string(); }

  std::filesystem::path folder_;
};

}  // namespace occupancy_fusion
