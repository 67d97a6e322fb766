// Reader of CARMEN robot logs: the FLASER lines (front laser scans with the
// robot's corrected pose), as in the Radish / Freiburg SLAM benchmark
// "corrected" logs.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "occupancy_fusion/sensors/laser_scan.h"

namespace occupancy_fusion {

// FLASER n r_1 ... r_n x y theta odom_x odom_y odom_theta ipc_timestamp
// hostname logger_timestamp
struct CarmenLaserScan {
  LaserScan scan; // beam i at -pi/2 + i * res: res = pi/180 for 180 or 181
                  // beams, pi/360 for 360 or 361 (a 180 degree field of view,
                  // the CARMEN / GMapping convention)
  double x = 0.0; // m, corrected pose of the laser in the log's world frame
  double y = 0.0;
  double theta = 0.0; // rad, counter-clockwise from +x
  double odom_x = 0.0;
  double odom_y = 0.0;
  double odom_theta = 0.0;
  double ipc_timestamp = 0.0; // s
  std::string hostname;
  double logger_timestamp = 0.0; // s
  std::size_t line_number = 0;   // 1-based line of the log
};

struct CarmenReadConfig {
  // The logs store no-returns as large finite values (>= 80 m, or exactly 50 m
  // in ACES) and no valid reading exceeds about 50 m: readings above range_max
  // are no-returns for the sensor model when its
  // LaserRangeConfig.above_range_max_is_no_return is set.
  double range_min = 0.0;    // m
  double range_max = 49.9;   // m
  std::size_t max_scans = 0; // stop after this many FLASER lines; 0 = read all

  void validate() const; // throws std::invalid_argument naming the bad field
};

// Parses one line: nullopt unless it is a FLASER line; throws
// std::runtime_error naming what is wrong for a malformed FLASER line.
std::optional<CarmenLaserScan>
parseCarmenFlaserLine(const std::string &line, const CarmenReadConfig &config);

// A malformed FLASER line that readCarmenLog skipped.
struct CarmenSkippedLine {
  std::size_t line_number = 0; // 1-based
  std::string reason;          // what parseCarmenFlaserLine found wrong
};

// Reads every FLASER line of a log, in file order. A name ending in ".gz" is
// decompressed with `gzip -dc`. A malformed FLASER line is skipped with a
// warning on stderr naming its line (the first few; then a count), and listed
// in `skipped_lines` when given. Throws std::runtime_error if the file cannot
// be read, or if FLASER lines were malformed and none was valid (the message
// names the first bad line).
std::vector<CarmenLaserScan>
readCarmenLog(const std::string &path,
              const CarmenReadConfig &config = CarmenReadConfig(),
              std::vector<CarmenSkippedLine> *skipped_lines = nullptr);

} // namespace occupancy_fusion
