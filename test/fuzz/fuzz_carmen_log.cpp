// CARMEN log lines -> CarmenLaserScan (parseCarmenFlaserLine, src/sensors/carmen_log.cpp), as the
// offline mapper reads a log: one call per line. Any line must be skipped (nullopt), rejected with
// std::runtime_error, or give a scan that passes LaserScan::validate() with a finite pose.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "occupancy_fusion/sensors/carmen_log.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occupancy_fusion;
  std::istringstream text(std::string(reinterpret_cast<const char*>(data), size));
  const CarmenReadConfig config;
  std::string line;
  while (std::getline(text, line)) {
    try {
      const std::optional<CarmenLaserScan> scan = parseCarmenFlaserLine(line, config);
      if (!scan) continue;
      scan->scan.validate();
      if (!(std::isfinite(scan->x) && std::isfinite(scan->y) && std::isfinite(scan->theta))) {
        std::abort();
      }
    } catch (const std::runtime_error&) {
    }
  }
  return 0;
}
