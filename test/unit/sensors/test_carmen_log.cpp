#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "occupancy_fusion/sensors/carmen_log.h"

namespace occupancy_fusion {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string flaser(int beams, double first_range, double x) {
  std::string line = "FLASER " + std::to_string(beams);
  for (int i = 0; i < beams; ++i)
    line += " " + std::to_string(first_range + 0.01 * i);
  line += " " + std::to_string(x) + " -2.5 0.75 " + std::to_string(x) +
          " -2.5 0.75 1234.5 nohost 1234.6";
  return line;
}

TEST(CarmenLog, ParsesFlaserLine) {
  const auto scan =
      parseCarmenFlaserLine(flaser(361, 1.0, 3.25), CarmenReadConfig());
  ASSERT_TRUE(scan.has_value());
  EXPECT_EQ(scan->scan.beamCount(), 361);
  EXPECT_NEAR(scan->scan.angle_min, -kPi / 2, 1e-12);
  EXPECT_NEAR(scan->scan.angle_increment, kPi / 360, 1e-12);
  EXPECT_NEAR(scan->scan.angle(360), kPi / 2, 1e-12);
  EXPECT_FLOAT_EQ(scan->scan.ranges[10], 1.1f);
  EXPECT_DOUBLE_EQ(scan->x, 3.25);
  EXPECT_DOUBLE_EQ(scan->y, -2.5);
  EXPECT_DOUBLE_EQ(scan->theta, 0.75);
  EXPECT_DOUBLE_EQ(scan->ipc_timestamp, 1234.5);
  EXPECT_EQ(scan->hostname, "nohost");
  EXPECT_DOUBLE_EQ(scan->scan.range_max, 49.9);
  const auto intel =
      parseCarmenFlaserLine(flaser(180, 1.0, 0.0), CarmenReadConfig());
  EXPECT_NEAR(intel->scan.angle_increment, kPi / 180, 1e-12);
  const auto fr079 =
      parseCarmenFlaserLine(flaser(360, 1.0, 0.0), CarmenReadConfig());
  EXPECT_NEAR(fr079->scan.angle_increment, kPi / 360, 1e-12);
}

TEST(CarmenLog, IgnoresOtherLinesRejectsBrokenFlaser) {
  EXPECT_FALSE(
      parseCarmenFlaserLine("ODOM 0 0 0 0 0 0 1 host 1", CarmenReadConfig()));
  EXPECT_FALSE(parseCarmenFlaserLine("PARAM robot_frontlaser_offset 0",
                                     CarmenReadConfig()));
  EXPECT_FALSE(parseCarmenFlaserLine("", CarmenReadConfig()));
  EXPECT_THROW(parseCarmenFlaserLine("FLASER 3 1.0 2.0", CarmenReadConfig()),
               std::runtime_error);
  EXPECT_THROW(parseCarmenFlaserLine("FLASER 3 1 2 3 0 0", CarmenReadConfig()),
               std::runtime_error);
}

TEST(CarmenLog, ReadsPlainAndGzippedFiles) {
  const std::string path = testing::TempDir() + "carmen_log_test.log";
  {
    std::ofstream out(path);
    out << "# CARMEN log\nPARAM robot_frontlaser_offset 0.0\n"
        << flaser(180, 1.0, 0.5) << "\nNEFF 1 2 3\n"
        << flaser(180, 2.0, 1.5) << "\n"
        << flaser(180, 3.0, 2.5) << "\n";
  }
  auto scans = readCarmenLog(path);
  ASSERT_EQ(scans.size(), 3u);
  EXPECT_EQ(scans[0].line_number, 3u);
  EXPECT_DOUBLE_EQ(scans[2].x, 2.5);
  EXPECT_FLOAT_EQ(scans[1].scan.ranges[0], 2.0f);
  ASSERT_EQ(std::system(("gzip -kf " + path).c_str()), 0);
  CarmenReadConfig first_two;
  first_two.max_scans = 2;
  scans = readCarmenLog(path + ".gz", first_two);
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_DOUBLE_EQ(scans[1].x, 1.5);
  EXPECT_THROW(readCarmenLog(path + ".missing"), std::runtime_error);
  std::remove(path.c_str());
  std::remove((path + ".gz").c_str());
}

TEST(CarmenLog, SkipsMalformedLinesNamingThem) {
  const std::string path = testing::TempDir() + "carmen_log_malformed.log";
  {
    std::ofstream out(path);
    out << flaser(180, 1.0, 0.5) << "\n"
        << "FLASER 180 1.0 2.0\n" // truncated: line 2
        << flaser(180, 2.0, 1.5) << "\n"
        << "FLASER x\n" // no beam count: line 4
        << flaser(180, 3.0, 2.5) << "\n";
  }
  std::vector<CarmenSkippedLine> skipped;
  const auto scans = readCarmenLog(path, CarmenReadConfig(), &skipped);
  // The valid lines are read as if the bad ones were not there.
  ASSERT_EQ(scans.size(), 3u);
  EXPECT_EQ(scans[1].line_number, 3u);
  EXPECT_DOUBLE_EQ(scans[2].x, 2.5);
  ASSERT_EQ(skipped.size(), 2u);
  EXPECT_EQ(skipped[0].line_number, 2u);
  EXPECT_NE(skipped[0].reason.find("fewer ranges"), std::string::npos);
  EXPECT_EQ(skipped[1].line_number, 4u);
  EXPECT_NE(skipped[1].reason.find("beam count"), std::string::npos);

  // Nothing valid left: an error naming the first bad line.
  {
    std::ofstream out(path);
    out << "PARAM x 0\nFLASER 180 1.0\n";
  }
  try {
    readCarmenLog(path);
    FAIL() << "a log of malformed lines only must not read as empty";
  } catch (const std::runtime_error &error) {
    EXPECT_NE(std::string(error.what()).find(path + ":2:"), std::string::npos)
        << error.what();
  }
  std::remove(path.c_str());
}

} // namespace
} // namespace occupancy_fusion
