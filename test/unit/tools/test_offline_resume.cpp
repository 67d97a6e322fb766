// offline_mapper --load-map: mapping a recording in two parts, the second resumed from the files
// the first wrote (voxels in the .ot, laser cells in the .laser.* files), gives exactly the map of
// the whole recording mapped at once: nothing of the first part is lost or counted twice. A file
// that cannot be resumed is refused as a bad input (exit 2), naming it.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "occupancy_fusion/tools/simulated_recording.h"
#include "tool_test_support.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

constexpr int kFrames = 8;

std::string quoted(const fs::path& path) { return "'" + path.string() + "'"; }

std::string configText() {
  return "resolution: 0.05\nframe_id: map\n"
         "sensor_model:\n  max_range: 8.0\n"
         "depth:\n  k: 0.05\n  sigma: 0.05\n  max_range: 8.0\n"
         "stereo:\n  disparity_sigma_px: 0.1\n  max_range: 8.0\n"
         "  unknown_neighbour_occupancy: 0.2\n";
}

// Every message of `whole` stamped before `split` into `first`, the others into `second`; the
// static transforms (sensor mounts) into both.
void splitBag(const fs::path& whole, const ros::Time& split, const fs::path& first,
              const fs::path& second) {
  rosbag::Bag in(whole.string(), rosbag::bagmode::Read);
  rosbag::Bag out_first(first.string(), rosbag::bagmode::Write);
  rosbag::Bag out_second(second.string(), rosbag::bagmode::Write);
  for (const rosbag::MessageInstance& message : rosbag::View(in)) {
    const bool is_static = message.getTopic() == "/tf_static";
    if (is_static || message.getTime() < split)
      out_first.write(message.getTopic(), message.getTime(), message);
    if (is_static || message.getTime() >= split) {
      out_second.write(message.getTopic(), message.getTime(), message);
    }
  }
}

class OfflineResume : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = makeRoomRecordingDir(configText(), kFrames,
                                makeSimulatedSensors({"cloud", "depth", "disparity", "scan"}));
    rosbag::Bag whole((dir_ / "room.bag").string(), rosbag::bagmode::Read);
    rosbag::View view(whole);
    const ros::Time split = view.getBeginTime() + (view.getEndTime() - view.getBeginTime()) * 0.5;
    whole.close();
    splitBag(dir_ / "room.bag", split, dir_ / "first.bag", dir_ / "second.bag");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static RunResult map(const std::string& inputs, const std::string& name) {
    return runTool(OFFLINE_MAPPER_PATH,
                   "--config " + quoted(dir_ / "mapper.yaml") + " " + inputs + " --output-dir " +
                       quoted(dir_ / name) + " --name " + name + " --quiet",
                   dir_);
  }
  static std::string bytes(const std::string& name, const std::string& extension) {
    return readText(dir_ / name / (name + extension));
  }

  static fs::path dir_;
};
fs::path OfflineResume::dir_;

TEST_F(OfflineResume, SecondPartResumedFromTheFirstEqualsTheWholeRecording) {
  const RunResult first = map("--bag " + quoted(dir_ / "first.bag"), "first");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const RunResult resumed = map(
      "--bag " + quoted(dir_ / "second.bag") + " --load-map " + quoted(dir_ / "first" / "first.ot"),
      "resumed");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("offline_mapper: resumed "), std::string::npos) << resumed.out;
  EXPECT_EQ(resumed.out.find("no laser layer files"), std::string::npos) << resumed.out;
  const RunResult whole =
      map("--bag " + quoted(dir_ / "first.bag") + " --bag " + quoted(dir_ / "second.bag"), "whole");
  ASSERT_EQ(whole.exit_code, 0) << whole.err;

  // Both parts integrated something of every kind, and the resumed map is the whole one.
  for (const std::string& run : {first.out, resumed.out}) {
    for (const char* kind : {"point_cloud", "depth", "disparity", "laser"}) {
      EXPECT_NE(run.find(std::string(kind) + ": "), std::string::npos) << kind << "\n" << run;
    }
  }
  EXPECT_NE(bytes("first", ".ot"), bytes("whole", ".ot"));
  EXPECT_NE(bytes("first", ".laser.npy"), bytes("whole", ".laser.npy"));
  EXPECT_TRUE(bytes("resumed", ".ot") == bytes("whole", ".ot"));
  EXPECT_TRUE(bytes("resumed", ".laser.npy") == bytes("whole", ".laser.npy"));
  EXPECT_TRUE(bytes("resumed", ".pgm") == bytes("whole", ".pgm"));
}

// The same through the checkpoint store (spill_folder, checkpoint_period): the first run's final
// checkpoint (voxels and laser layer) is what the second run starts from, with a memory bound
// that keeps most of the map in the store.
TEST_F(OfflineResume, SecondPartResumedFromTheCheckpointStoreEqualsTheWholeRecording) {
  const std::string store = " --set spill_folder=" + quoted(dir_ / "store") +
                            " --set checkpoint_period=3600 --set max_memory_mb=0.05" +
                            " --set layer_max_memory_mb=0.01";
  const RunResult first = map("--bag " + quoted(dir_ / "first.bag") + store, "first_store");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const RunResult second = map("--bag " + quoted(dir_ / "second.bag") + store, "second_store");
  ASSERT_EQ(second.exit_code, 0) << second.err;
  const RunResult whole = map(
      "--bag " + quoted(dir_ / "first.bag") + " --bag " + quoted(dir_ / "second.bag"), "whole_all");
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  EXPECT_EQ(second.err.find("warning"), std::string::npos) << second.err;
  // Both bounds were exceeded: blocks and laser tiles went to the store and came back.
  for (const RunResult* run : {&first, &second}) {
    const std::size_t line = run->out.find("spill store: ");
    ASSERT_NE(line, std::string::npos) << run->out;
    unsigned long blocks = 0, tiles = 0;
    ASSERT_EQ(std::sscanf(run->out.c_str() + line, "spill store: %lu blocks and %lu laser tiles",
                          &blocks, &tiles),
              2);
    EXPECT_GT(blocks, 0u);
    EXPECT_GT(tiles, 0u);
  }
  EXPECT_NE(bytes("first_store", ".ot"), bytes("whole_all", ".ot"));
  EXPECT_TRUE(bytes("second_store", ".ot") == bytes("whole_all", ".ot"));
  EXPECT_NE(bytes("first_store", ".laser.npy"), bytes("whole_all", ".laser.npy"));
  EXPECT_TRUE(bytes("second_store", ".laser.npy") == bytes("whole_all", ".laser.npy"));
  EXPECT_TRUE(bytes("second_store", ".pgm") == bytes("whole_all", ".pgm"));
}

TEST_F(OfflineResume, FilesThatCannotBeResumedAreBadInput) {
  const RunResult absent =
      map("--bag " + quoted(dir_ / "second.bag") + " --load-map " + quoted(dir_ / "absent.ot"),
          "absent");
  EXPECT_EQ(absent.exit_code, 2);
  EXPECT_NE(absent.err.find((dir_ / "absent.ot").string()), std::string::npos) << absent.err;

  std::ofstream(dir_ / "not_a_map.ot") << "# Octomap OcTree file\nid OcTree\nsize 9\nres 0.05\n";
  const RunResult damaged =
      map("--bag " + quoted(dir_ / "second.bag") + " --load-map " + quoted(dir_ / "not_a_map.ot"),
          "damaged");
  EXPECT_EQ(damaged.exit_code, 2);
  EXPECT_NE(damaged.err.find("--load-map: cannot resume"), std::string::npos) << damaged.err;
  EXPECT_FALSE(fs::exists(dir_ / "damaged" / "damaged.ot"));
}

}  // namespace
}  // namespace occupancy_fusion
