#include "occupancy_fusion/ros/frame_statistics.h"

#include <algorithm>

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

void FrameStatistics::fill(diagnostic_updater::DiagnosticStatusWrapper* status,
                           Clock::time_point now) {
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
  status->add("frames received", received_);
  status->add("input rate (Hz)", rate);
  status->add("frames integrated", integrated_);
  status->add("frames waiting", waiting);
  status->add("frames dropped", dropped);
  for (const auto& [reason, count] : dropped_)
    status->add("frames dropped (" + reason + ")", count);
  status->add("tf failures", tf_failures);
  status->add("integration ms (last)", last_milliseconds_);
  status->add("integration ms (mean)",
              integrated_ > 0 ? total_milliseconds_ / static_cast<double>(integrated_) : 0.0);
  status->add("integration ms (max)", max_milliseconds_);
}

}  // namespace occupancy_fusion
