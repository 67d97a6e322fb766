// What every mapper reports about its input, counted in one place (the nodelets' MapperNodeletBase
// puts it into their diagnostics) so that the four mappers report it alike: frames received and
// their rate, frames integrated and the time each took, frames dropped by reason, and how many of
// those drops were tf failures. Thread-safe: the tf2 filters, the nodelet's callbacks and the
// diagnostics timer may run on different threads.
#pragma once

#include <chrono>
#include <cstddef>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace occupancy_fusion {

class FrameStatistics {
 public:
  using Clock = std::chrono::steady_clock;

  // The drop reasons that are tf failures ("tf failures" sums them). The tf2 message filter gives
  // up on a frame whose transform did not arrive while it was queued (pushed out by newer frames
  // or timed out), whose stamp is older than the tf buffer, or that has no frame_id; a lookup can
  // still fail after the filter let the frame through.
  static constexpr const char* kTfQueue = "tf: no transform while queued";
  static constexpr const char* kTfTooOld = "tf: older than the tf buffer";
  static constexpr const char* kTfNoFrameId = "tf: empty frame_id";
  static constexpr const char* kTfLookup = "tf: lookup failed";

  // `drop_reasons`: the mapper's own reasons, reported (at 0) from the start with the tf ones.
  explicit FrameStatistics(const std::vector<std::string>& drop_reasons = {},
                           Clock::time_point start = Clock::now());

  void addDropReasons(const std::vector<std::string>& drop_reasons);
  void countReceived();
  void countIntegrated(double milliseconds);
  // A reason not declared yet is added (declare them, so their keys show from the start at 0).
  void countDropped(const std::string& reason);

  std::size_t received() const;
  std::size_t integrated() const;
  std::size_t dropped(const std::string& reason) const;
  std::size_t droppedTotal() const;

  // Adds the keys "frames received", "input rate (Hz)" (frames received per second of wall time
  // since the previous call), "frames integrated", "frames waiting" (received, neither integrated
  // nor dropped yet: held in the tf2 filter), "frames dropped", one "frames dropped (<reason>)"
  // per reason, "tf failures", "integration ms (last)", "integration ms (mean)" and
  // "integration ms (max)" (per integrated frame: conversion and core call).
  // Each value as diagnostic_updater writes it (operator<< of the count or double).
  using Report = std::vector<std::pair<std::string, std::string>>;
  Report report(Clock::time_point now = Clock::now());

 private:
  static bool isTfReason(const std::string& reason);

  mutable std::mutex mutex_;
  std::size_t received_ = 0;
  std::size_t integrated_ = 0;
  double last_milliseconds_ = 0.0;
  double total_milliseconds_ = 0.0;
  double max_milliseconds_ = 0.0;
  std::map<std::string, std::size_t> dropped_;  // ordered, so the keys keep their order
  std::size_t received_at_last_fill_ = 0;
  Clock::time_point last_fill_;
};

}  // namespace occupancy_fusion
