// FrameStatistics: the input counts every mapper reports, against counts made by hand.
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "occupancy_fusion/mapping/frame_statistics.h"

namespace occupancy_fusion {
namespace {

using Clock = FrameStatistics::Clock;

std::string valueOf(const FrameStatistics::Report& report, const std::string& key) {
  for (const auto& [name, value] : report) {
    if (name == key) return value;
  }
  ADD_FAILURE() << "no key '" << key << "'";
  return "";
}

TEST(FrameStatistics, ReportsCountsRateWaitingFramesAndIntegrationTimes) {
  const Clock::time_point start = Clock::now();
  FrameStatistics frames({"bad encoding"}, start);
  for (int i = 0; i < 5; ++i) frames.countReceived();
  frames.countIntegrated(2.0);
  frames.countIntegrated(4.0);
  frames.countDropped(FrameStatistics::kTfLookup);
  frames.countDropped("bad encoding");

  const FrameStatistics::Report first = frames.report(start + std::chrono::seconds(2));
  EXPECT_EQ(valueOf(first, "frames received"), "5");
  EXPECT_EQ(valueOf(first, "input rate (Hz)"), "2.5");  // 5 frames in 2 s
  EXPECT_EQ(valueOf(first, "frames integrated"), "2");
  EXPECT_EQ(valueOf(first, "frames waiting"), "1");  // 5 - 2 integrated - 2 dropped
  EXPECT_EQ(valueOf(first, "frames dropped"), "2");
  EXPECT_EQ(valueOf(first, "frames dropped (bad encoding)"), "1");
  EXPECT_EQ(valueOf(first, "frames dropped (tf: lookup failed)"), "1");
  EXPECT_EQ(valueOf(first, "frames dropped (tf: no transform while queued)"), "0");
  EXPECT_EQ(valueOf(first, "tf failures"), "1");  // the tf reasons only
  EXPECT_EQ(valueOf(first, "integration ms (last)"), "4");
  EXPECT_EQ(valueOf(first, "integration ms (mean)"), "3");
  EXPECT_EQ(valueOf(first, "integration ms (max)"), "4");

  // The rate counts the frames since the previous report only.
  frames.countReceived();
  frames.countDropped("not declared");  // added on its first drop
  const FrameStatistics::Report second = frames.report(start + std::chrono::seconds(4));
  EXPECT_EQ(valueOf(second, "input rate (Hz)"), "0.5");  // 1 frame in 2 s
  EXPECT_EQ(valueOf(second, "frames dropped (not declared)"), "1");
  EXPECT_EQ(valueOf(second, "frames waiting"), "1");  // 6 - 2 integrated - 3 dropped
  EXPECT_EQ(frames.droppedTotal(), 3u);
}

}  // namespace
}  // namespace occupancy_fusion
