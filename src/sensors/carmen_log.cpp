#include "occupancy_fusion/sensors/carmen_log.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace occupancy_fusion {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Malformed lines named one by one on stderr; the rest only counted.
constexpr std::size_t kNamedSkippedLines = 5;

// A 180 degree field of view: n beams span pi, either with n - 1 gaps (odd n)
// or n (even n).
double beamSpacing(int beams) {
  return beams % 2 == 1 ? kPi / (beams - 1) : kPi / beams;
}

std::string shellQuoted(const std::string &text) {
  std::string quoted = "'";
  for (char c : text)
    quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

bool endsWith(const std::string &text, const std::string &suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Calls fn(line) for each line of the file, decompressing .gz through gzip.
template <typename Fn> void forEachLine(const std::string &path, Fn &&fn) {
  if (!endsWith(path, ".gz")) {
    std::ifstream in(path);
    if (!in)
      throw std::runtime_error("cannot open CARMEN log " + path);
    std::string line;
    while (std::getline(in, line) && fn(line)) {
    }
    return;
  }
  std::ifstream probe(path);
  if (!probe)
    throw std::runtime_error("cannot open CARMEN log " + path);
  FILE *pipe = popen(("gzip -dc -- " + shellQuoted(path)).c_str(), "r");
  if (pipe == nullptr)
    throw std::runtime_error("cannot run gzip for " + path);
  std::string line;
  char buffer[1 << 16];
  bool more = true;
  while (more && std::fgets(buffer, sizeof(buffer), pipe) != nullptr) {
    line += buffer;
    if (line.empty() || line.back() != '\n')
      continue; // a longer line: keep reading
    line.pop_back();
    more = fn(line);
    line.clear();
  }
  if (more && !line.empty())
    fn(line);
  const int status = pclose(pipe);
  if (more && status != 0)
    throw std::runtime_error("gzip failed to decompress " + path);
}

} // namespace

void CarmenReadConfig::validate() const {
  if (!(std::isfinite(range_min) && range_min >= 0.0)) {
    throw std::invalid_argument(
        "CarmenReadConfig.range_min must be finite and >= 0");
  }
  if (!(std::isfinite(range_max) && range_max > range_min)) {
    throw std::invalid_argument(
        "CarmenReadConfig.range_max must be finite and > range_min");
  }
}

std::optional<CarmenLaserScan>
parseCarmenFlaserLine(const std::string &line, const CarmenReadConfig &config) {
  std::istringstream in(line);
  std::string tag;
  if (!(in >> tag) || tag != "FLASER")
    return std::nullopt;
  int beams = 0;
  if (!(in >> beams) || beams < 2)
    throw std::runtime_error("FLASER: bad beam count");
  CarmenLaserScan out;
  out.scan.angle_min = -0.5 * kPi;
  out.scan.angle_increment = beamSpacing(beams);
  out.scan.range_min = config.range_min;
  out.scan.range_max = config.range_max;
  // Grown as ranges are read: a corrupt count (say 2000000000) must not
  // allocate gigabytes before the line runs out of numbers.
  for (int beam = 0; beam < beams; ++beam) {
    float range = 0.0f;
    if (!(in >> range))
      throw std::runtime_error("FLASER: fewer ranges than its beam count");
    out.scan.ranges.push_back(range);
  }
  if (!(in >> out.x >> out.y >> out.theta >> out.odom_x >> out.odom_y >>
        out.odom_theta)) {
    throw std::runtime_error("FLASER: missing pose");
  }
  if (!(std::isfinite(out.x) && std::isfinite(out.y) &&
        std::isfinite(out.theta))) {
    throw std::runtime_error("FLASER: pose is not finite");
  }
  if (!(in >> out.ipc_timestamp >> out.hostname >> out.logger_timestamp)) {
    throw std::runtime_error("FLASER: missing timestamps or hostname");
  }
  return out;
}

std::vector<CarmenLaserScan>
readCarmenLog(const std::string &path, const CarmenReadConfig &config,
              std::vector<CarmenSkippedLine> *skipped_lines) {
  config.validate();
  std::vector<CarmenLaserScan> scans;
  std::vector<CarmenSkippedLine> skipped;
  std::size_t line_number = 0;
  forEachLine(path, [&](const std::string &line) {
    ++line_number;
    try {
      std::optional<CarmenLaserScan> scan = parseCarmenFlaserLine(line, config);
      if (scan) {
        scan->line_number = line_number;
        scans.push_back(std::move(*scan));
      }
    } catch (const std::runtime_error &error) {
      // One corrupt line (a truncated write, a bad sector) must not cost the
      // whole log: skip it, name it, and count it.
      skipped.push_back({line_number, error.what()});
      if (skipped.size() <= kNamedSkippedLines) {
        std::cerr << "warning: " << path << ":" << line_number << ": "
                  << error.what() << ": line skipped\n";
      }
    }
    return config.max_scans == 0 || scans.size() < config.max_scans;
  });
  if (!skipped.empty()) {
    if (scans.empty()) {
      throw std::runtime_error(path + ":" +
                               std::to_string(skipped.front().line_number) +
                               ": " + skipped.front().reason + " (" +
                               std::to_string(skipped.size()) +
                               " malformed FLASER lines, no valid one)");
    }
    std::cerr << "warning: " << path << ": " << skipped.size()
              << " malformed FLASER line(s) skipped, " << scans.size()
              << " read\n";
  }
  if (skipped_lines != nullptr)
    *skipped_lines = std::move(skipped);
  return scans;
}

} // namespace occupancy_fusion
