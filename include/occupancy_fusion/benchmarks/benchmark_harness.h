// What the benchmark subcommands share: wall and CPU time, medians of repetitions, comma-separated
// list options, and the OctoMap baseline set up with our maps' sensor model.
#pragma once

#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <sstream>
#include <string>
#include <vector>

#include "occupancy_fusion/map/occupancy_model.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {
namespace bench {

using Clock = std::chrono::steady_clock;

inline double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// CPU time of all the process's threads, ms: on a shared machine wall time includes waiting for a
// core, CPU time does not (with one thread it is the cost of the work itself).
inline double processCpuMilliseconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return 1e3 * static_cast<double>(now.tv_sec) + 1e-6 * static_cast<double>(now.tv_nsec);
}

// CPU time of the calling thread, ms: a peer that inserts on one thread, measured apart from the
// other threads' work (an OpenMP team of ours, timed just before, spins a while after its region).
inline double threadCpuMilliseconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return 1e3 * static_cast<double>(now.tv_sec) + 1e-6 * static_cast<double>(now.tv_nsec);
}

// The middle value (the mean of the middle two for an even count); 0 for no values.
inline double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// "full,half" -> {"full", "half"}. UsageError for an empty item and for an empty list.
inline std::vector<std::string> splitList(const std::string& option, const std::string& text) {
  std::vector<std::string> items;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (item.empty()) throw UsageError("--" + option + ": empty item in '" + text + "'");
    items.push_back(item);
  }
  if (items.empty()) throw UsageError("--" + option + " is empty");
  return items;
}

// "0.05,0.1" -> {0.05, 0.1}. UsageError "--<option> needs <wanted> separated by commas, got
// '<text>'" for an item that is not a number of type T or that `accept` refuses, and one for an
// empty list.
template <typename T, typename Accept>
std::vector<T> parseNumberList(const std::string& option, const std::string& text,
                               const std::string& wanted, Accept accept) {
  std::vector<T> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    std::istringstream parser(item);
    T value{};
    if (!(parser >> value) || !parser.eof() || !accept(value)) {
      throw UsageError("--" + option + " needs " + wanted + " separated by commas, got '" + text +
                       "'");
    }
    values.push_back(value);
  }
  if (values.empty()) throw UsageError("--" + option + " is empty");
  return values;
}

// Any number: "-0.5,2" -> {-0.5, 2}.
template <typename T>
std::vector<T> parseNumbers(const std::string& option, const std::string& text) {
  return parseNumberList<T>(option, text, "numbers", [](T) { return true; });
}

template <typename T>
std::vector<T> parsePositiveList(const std::string& option, const std::string& text) {
  return parseNumberList<T>(option, text, "positive numbers", [](T value) { return value > T{0}; });
}

// An empty tree with our maps' default hit and miss probabilities and clamping, so that both
// sides of a comparison apply the same sensor model.
inline octomap::OcTree makeOctomapTree(double resolution) {
  const OccupancyModel model;
  octomap::OcTree tree(resolution);
  tree.setProbHit(model.prob_hit);
  tree.setProbMiss(model.prob_miss);
  tree.setClampingThresMin(model.clamp_min);
  tree.setClampingThresMax(model.clamp_max);
  return tree;
}

}  // namespace bench
}  // namespace occupancy_fusion
