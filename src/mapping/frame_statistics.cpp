#include "occupancy_fusion/mapping/frame_statistics.h"

#include <algorithm>
#include <sstream>

namespace occupancy_fusion {

FrameStatistics::FrameStatistics(const std::vector<std::string>& drop_reasons,
                                 Clock::time_point start)
    : last_fill_(start) {
  addDropReasons({kTfQueue, kTfTooOld, kTfNoFrameId, kTfLookup});
  addDropReasons(drop_reasons);
}

void FrameStatistics::addDropReasons(const std::vector<std::string>& drop_reasons) {
  const std::lock_guard<std::mutex> lock(mutex_);
  for (const std::string& reason : drop_reasons) dropped_.emplace(reason, 0);
}

void FrameStatistics::countReceived() {
  const std::lock_guard<std::mutex> lock(mutex_);
  ++received_;
}

void FrameStatistics::countIntegrated(double milliseconds) {
  const std::lock_guard<std::mutex> lock(mutex_);
  ++integrated_;
  last_milliseconds_ = milliseconds;
  total_milliseconds_ += milliseconds;
  max_milliseconds_ = std::max(max_milliseconds_, milliseconds);
}

void FrameStatistics::countDropped(const std::string& reason) {
  const std::lock_guard<std::mutex> lock(mutex_);
  ++dropped_[reason];
}

std::size_t FrameStatistics::received() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return received_;
}

std::size_t FrameStatistics::integrated() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return integrated_;
}

std::size_t FrameStatistics::dropped(const std::string& reason) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto counter = dropped_.find(reason);
  return counter == dropped_.end() ? 0 : counter->second;
}

std::size_t FrameStatistics::droppedTotal() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::size_t total = 0;
  for (const auto& entry : dropped_) total += entry.second;
  return total;
}

bool FrameStatistics::isTfReason(const std::string& reason) { return reason.rfind("tf: ", 0) == 0; }

namespace {

template <typename Value>
void add(FrameStatistics::Report* report, const std::string& key, const Value& value) {
  std::ostringstream text;
  text << value;
  report->emplace_back(key, text.str());
}

}  // namespace

FrameStatistics::Report FrameStatistics::report(Clock::time_point now) {
  const std::lock_guard<std::mutex> lock(mutex_);
  const double seconds = std::chrono::duration<double>(now - last_fill_).count();
  const double rate =
      seconds > 0.0 ? static_cast<double>(received_ - received_at_last_fill_) / seconds : 0.0;
  received_at_last_fill_ = received_;
  last_fill_ = now;

  std::size_t dropped = 0, tf_failures = 0;
  for (const auto& [reason, count] : dropped_) {
    dropped += count;
    if (isTfReason(reason)) tf_failures += count;
  }
  // A frame is counted as received before the filter decides on it, so this cannot underflow.
  const std::size_t waiting = received_ - std::min(received_, integrated_ + dropped);
  Report report;
  add(&report, "frames received", received_);
  add(&report, "input rate (Hz)", rate);
  add(&report, "frames integrated", integrated_);
  add(&report, "frames waiting", waiting);
  add(&report, "frames dropped", dropped);
  for (const auto& [reason, count] : dropped_)
    add(&report, "frames dropped (" + reason + ")", count);
  add(&report, "tf failures", tf_failures);
  add(&report, "integration ms (last)", last_milliseconds_);
  add(&report, "integration ms (mean)",
      integrated_ > 0 ? total_milliseconds_ / static_cast<double>(integrated_) : 0.0);
  add(&report, "integration ms (max)", max_milliseconds_);
  return report;
}

}  // namespace occupancy_fusion
