#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "occupancy_fusion/tools/command_line.h"
#include "occupancy_fusion/tools/yaml_parameter_source.h"

#include "../../common/test_folder.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

// The layout rosparam load puts under a nodelet's private namespace.
const char* const kConfig = R"(
resolution: 0.1
frame_id: odom
latch: true
max_iterations: 7
sensor_model:
  hit: 0.75
  max_range: 5
topics: [cloud_a, cloud_b]
weights: [1, 2.5, -3]
)";

std::string messageOf(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const std::exception& error) {
    return error.what();
  }
  return "(no exception)";
}

TEST(YamlParameterSource, ReadsEveryTypeAndNestedKeys) {
  const YamlParameterSource source = YamlParameterSource::fromString(kConfig);
  double resolution = 0.0, hit = 0.0, max_range = 0.0;
  int iterations = 0;
  bool latch = false;
  std::string frame;
  std::vector<std::string> topics;
  std::vector<double> weights;
  EXPECT_TRUE(source.get("resolution", &resolution));
  EXPECT_TRUE(source.get("sensor_model/hit", &hit));
  EXPECT_TRUE(source.get("/sensor_model//max_range", &max_range));  // an integer read as double
  EXPECT_TRUE(source.get("max_iterations", &iterations));
  EXPECT_TRUE(source.get("latch", &latch));
  EXPECT_TRUE(source.get("frame_id", &frame));
  EXPECT_TRUE(source.get("topics", &topics));
  EXPECT_TRUE(source.get("weights", &weights));
  EXPECT_DOUBLE_EQ(resolution, 0.1);
  EXPECT_DOUBLE_EQ(hit, 0.75);
  EXPECT_DOUBLE_EQ(max_range, 5.0);
  EXPECT_EQ(iterations, 7);
  EXPECT_TRUE(latch);
  EXPECT_EQ(frame, "odom");
  EXPECT_EQ(topics, (std::vector<std::string>{"cloud_a", "cloud_b"}));
  EXPECT_EQ(weights, (std::vector<double>{1.0, 2.5, -3.0}));
}

TEST(YamlParameterSource, AbsentKeysLeaveTheValueAlone) {
  const YamlParameterSource source = YamlParameterSource::fromString(kConfig);
  double value = 42.0;
  EXPECT_FALSE(source.get("sensor_model/miss", &value));
  EXPECT_FALSE(source.get("resolution/deeper", &value));  // through a scalar
  EXPECT_FALSE(source.get("nothing", &value));
  EXPECT_DOUBLE_EQ(value, 42.0);
}

TEST(YamlParameterSource, WrongTypesNameTheKey) {
  const YamlParameterSource source = YamlParameterSource::fromString(kConfig);
  int integer = 0;
  double number = 0.0;
  bool flag = false;
  std::vector<double> numbers;
  EXPECT_NE(messageOf([&] { source.get("resolution", &integer); }).find("'resolution'"),
            std::string::npos);
  EXPECT_NE(messageOf([&] { source.get("frame_id", &number); }).find("'frame_id'"),
            std::string::npos);
  EXPECT_NE(messageOf([&] { source.get("sensor_model", &number); }).find("'sensor_model'"),
            std::string::npos);
  EXPECT_NE(messageOf([&] { source.get("frame_id", &flag); }).find("'frame_id'"),
            std::string::npos);
  EXPECT_NE(messageOf([&] { source.get("topics", &numbers); }).find("'topics'"), std::string::npos);
}

TEST(YamlParameterSource, OverridesWinAndParseAsTheRequestedType) {
  YamlParameterSource source = YamlParameterSource::fromString(kConfig);
  source.addOverride("sensor_model/hit=0.9");
  source.addOverride("frame_id=true");  // a string stays a string
  source.addOverride("max_iterations", "12");
  source.addOverride("weights=[4, 5]");
  source.addOverride("sensor_model/miss=0.3");  // not in the file
  double hit = 0.0, miss = 0.0;
  int iterations = 0;
  std::string frame;
  std::vector<double> weights;
  ASSERT_TRUE(source.get("sensor_model/hit", &hit));
  ASSERT_TRUE(source.get("sensor_model/miss", &miss));
  ASSERT_TRUE(source.get("max_iterations", &iterations));
  ASSERT_TRUE(source.get("frame_id", &frame));
  ASSERT_TRUE(source.get("weights", &weights));
  EXPECT_DOUBLE_EQ(hit, 0.9);
  EXPECT_DOUBLE_EQ(miss, 0.3);
  EXPECT_EQ(iterations, 12);
  EXPECT_EQ(frame, "true");
  EXPECT_EQ(weights, (std::vector<double>{4.0, 5.0}));
}

TEST(YamlParameterSource, BadOverrideValueNamesTheKey) {
  YamlParameterSource source = YamlParameterSource::fromString(kConfig);
  source.addOverride("sensor_model/hit=abc");
  source.addOverride("max_iterations=1.5");
  source.addOverride("weights=[1,");
  double hit = 0.0;
  int iterations = 0;
  std::vector<double> weights;
  const std::string hit_message = messageOf([&] { source.get("sensor_model/hit", &hit); });
  EXPECT_NE(hit_message.find("sensor_model/hit"), std::string::npos) << hit_message;
  EXPECT_NE(hit_message.find("abc"), std::string::npos) << hit_message;
  EXPECT_NE(messageOf([&] { source.get("max_iterations", &iterations); }).find("max_iterations"),
            std::string::npos);
  EXPECT_NE(messageOf([&] { source.get("weights", &weights); }).find("weights"), std::string::npos);
  EXPECT_THROW(source.addOverride("no_equals_sign"), std::invalid_argument);
  EXPECT_THROW(source.addOverride("=3"), std::invalid_argument);
}

TEST(YamlParameterSource, ReportsOverridesNothingRead) {
  YamlParameterSource source = YamlParameterSource::fromString(kConfig);
  source.addOverride("resolution=0.2");
  source.addOverride("sensor_model/hitt=0.8");  // misspelt
  double resolution = 0.0;
  source.get("resolution", &resolution);
  EXPECT_EQ(source.unreadOverrides(), std::vector<std::string>{"sensor_model/hitt"});
}

TEST(YamlParameterSource, ListsLeafKeysAndOverrides) {
  YamlParameterSource source = YamlParameterSource::fromString(kConfig);
  source.addOverride("extra/key=1");
  const std::vector<std::string> expected = {"extra/key",
                                             "frame_id",
                                             "latch",
                                             "max_iterations",
                                             "resolution",
                                             "sensor_model/hit",
                                             "sensor_model/max_range",
                                             "topics",
                                             "weights"};
  EXPECT_EQ(source.keys(), expected);
}

TEST(YamlParameterSource, PicksASection) {
  const std::string text = "mapper:\n  inner:\n    resolution: 0.2\nresolution: 0.5\n";
  double resolution = 0.0;
  ASSERT_TRUE(YamlParameterSource::fromString(text, "mapper/inner").get("resolution", &resolution));
  EXPECT_DOUBLE_EQ(resolution, 0.2);
  EXPECT_NE(messageOf([&] { YamlParameterSource::fromString(text, "other"); }).find("other"),
            std::string::npos);
  EXPECT_THROW(YamlParameterSource::fromString(text, "resolution"), std::invalid_argument);
}

TEST(YamlParameterSource, RejectsBadFilesWithTheirName) {
  EXPECT_NE(messageOf([] {
              YamlParameterSource::fromFile("/nonexistent/params.yaml");
            }).find("/nonexistent/params.yaml"),
            std::string::npos);
  EXPECT_THROW(YamlParameterSource::fromString("a: [1, 2"), std::invalid_argument);
  EXPECT_THROW(YamlParameterSource::fromString("- 1\n- 2\n"), std::invalid_argument);
  double value = 3.0;
  EXPECT_FALSE(YamlParameterSource::fromString("").get("resolution", &value));  // empty file
}

TEST(YamlParameterSource, MergesFilesLikeSuccessiveRosparamLoads) {
  const TemporaryFolder temporary;
  const fs::path& dir = temporary.path();
  std::ofstream(dir / "first.yaml") << "resolution: 0.1\nsensor_model: {hit: 0.7, miss: 0.4}\n";
  std::ofstream(dir / "second.yaml") << "sensor_model: {miss: 0.3}\noccupancy_max_z: 2.0\n";
  const YamlParameterSource source = YamlParameterSource::fromFiles(
      {(dir / "first.yaml").string(), (dir / "second.yaml").string()});
  double resolution = 0.0, hit = 0.0, miss = 0.0, max_z = 0.0;
  EXPECT_TRUE(source.get("resolution", &resolution));
  EXPECT_TRUE(source.get("sensor_model/hit", &hit));
  EXPECT_TRUE(source.get("sensor_model/miss", &miss));
  EXPECT_TRUE(source.get("occupancy_max_z", &max_z));
  EXPECT_DOUBLE_EQ(resolution, 0.1);
  EXPECT_DOUBLE_EQ(hit, 0.7);   // kept from the first file
  EXPECT_DOUBLE_EQ(miss, 0.3);  // replaced by the second
  EXPECT_DOUBLE_EQ(max_z, 2.0);
  EXPECT_THROW(YamlParameterSource::fromFiles({}), std::invalid_argument);
}

TEST(CommandLine, ParsesValuesFlagsAndRepeats) {
  const char* argv[] = {"tool", "--bag",     "a.bag",    "--set=x=1", "--set",
                        "y=2",  "--verbose", "--frames", "12",        "--rate=2.5"};
  const CommandLine line(10, argv, {"bag", "set", "frames", "rate"}, {"verbose"});
  EXPECT_EQ(line.required("bag"), "a.bag");
  EXPECT_EQ(line.values("set"), (std::vector<std::string>{"x=1", "y=2"}));
  EXPECT_TRUE(line.has("verbose"));
  EXPECT_EQ(line.intValue("frames", 0), 12);
  EXPECT_DOUBLE_EQ(line.doubleValue("rate", 0.0), 2.5);
  EXPECT_EQ(line.value("output", "fallback"), "fallback");
  EXPECT_THROW(line.required("output"), UsageError);
}

TEST(CommandLine, RejectsWhatItDoesNotKnow) {
  const char* unknown[] = {"tool", "--bogus", "1"};
  EXPECT_THROW(CommandLine(3, unknown, {"bag"}, {}), UsageError);
  const char* positional[] = {"tool", "file.bag"};
  EXPECT_THROW(CommandLine(2, positional, {"bag"}, {}), UsageError);
  const char* missing_value[] = {"tool", "--bag"};
  EXPECT_THROW(CommandLine(2, missing_value, {"bag"}, {}), UsageError);
  const char* not_a_number[] = {"tool", "--frames", "12x"};
  const CommandLine line(3, not_a_number, {"frames"}, {});
  EXPECT_THROW(line.intValue("frames", 0), UsageError);
}

}  // namespace
}  // namespace occupancy_fusion
