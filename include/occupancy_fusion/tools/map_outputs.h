// offline_mapper's --single-scan files: one laser scan's grid as Yguel et al.'s Table I
// evaluates it. (The map's own files are saveMap's, mapping/map_saving.h.)
#pragma once

#include <string>
#include <vector>

#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"

namespace occupancy_fusion {

// The grid of one laser scan in the sensor-centred frame, as Yguel et al.'s Table I evaluates
// it: `length` x `depth` metres of `resolution` cells, the sensor at the middle of the grid's
// lower long edge (x from -length/2 to length/2, y from 0 to depth), facing +y into the grid.
struct SingleScanGridConfig {
  double resolution = 0.05;  // m
  double length = 60.0;      // m, the long edge
  double depth = 30.0;       // m

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// The scan's log-ratios (Eq. 8) through config's polar-to-cartesian method; NaN = unobserved.
LogOddsRaster singleScanGrid(const LaserScan& scan, const PolarLaserIntegratorConfig& config,
                             const SingleScanGridConfig& grid);

// Writes prefix.npy (the log-ratios, float32, row 0 = the sensor's edge), prefix.pgm + .yaml
// (map_server files) and prefix.png (y up, one pixel per cell), cells classified occupied above
// threshold_log_odds. Returns the files written.
std::vector<std::string> writeSingleScanOutputs(const LogOddsRaster& grid, float threshold_log_odds,
                                                const std::string& prefix);

}  // namespace occupancy_fusion
