// The tests' one temporary folder: a fresh folder of its own under the system's temporary folder,
// removed afterwards. The name holds the process id and the test's name, so tests running in
// parallel never share a folder. Shared by the unit tests, the integration tests and the rostests'
// test nodes.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>

namespace occupancy_fusion {

// The folder for the current test, made empty; removed when it goes out of scope. `tag` tells
// two folders of one test apart.
class TemporaryFolder {
 public:
  explicit TemporaryFolder(const std::string& tag = "") {
    const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            (std::string("occupancy_fusion_") + test->test_suite_name() + "_" +
             std::to_string(::getpid()) + "_" + test->name() + tag);
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TemporaryFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string path(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// A fixture with a TemporaryFolder per test. Every file writer of the project writes a temporary
// file and renames it: the fixture fails a test that leaves one behind.
class TestFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    temporary_ = std::make_unique<TemporaryFolder>();
    folder_ = temporary_->path();
  }
  void TearDown() override {
    for (const auto& entry : std::filesystem::directory_iterator(folder_)) {
      EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos)
          << "temporary file left behind: " << entry.path();
    }
    temporary_.reset();
  }
  std::string path(const std::string& name) const { return (folder_ / name).string(); }

  std::filesystem::path folder_;

 private:
  std::unique_ptr<TemporaryFolder> temporary_;
};

}  // namespace occupancy_fusion
