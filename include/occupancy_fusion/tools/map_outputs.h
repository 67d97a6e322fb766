// The files offline_mapper writes for one mapped recording.
#pragma once

#include <string>
#include <vector>

#include "occupancy_fusion/integrators/polar_laser_integrator.h"
#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/mapping/mapping_session.h"

namespace occupancy_fusion {

// The log-odds behind the fused 2D view, cell for cell over the same window as `grid` (the
// result of projectToRaster with the same inputs): per column, the largest log-odds among the
// known voxels whose centres lie in config's height band and the known layer cells overlapping
// it; NaN where none is known. Classifying it with the model's threshold gives the fused view
// exactly (its rule "occupied wins, then free" is a maximum). Columns are the map's
// resolution; the layer must have the same resolution (offline_mapper's laser layer does).
LogOddsRaster fusedLogOdds(const VoxelMap& map, const GridLayer2D* layer,
                           const FusedGridConfig& config, const OccupancyRaster& grid);

struct MapOutputs {
  std::vector<std::string> files;  // every file written, in order
  int grid_width = 0;              // cells of the fused 2D view (0: nothing known, no 2D files)
  int grid_height = 0;
  std::size_t octomap_skipped_voxels = 0;  // outside OctoMap's key range, not in .bt/.ot
};

// Writes dir/name.bt and .ot (OctoMap), .pcd (every known voxel: centre and probability),
// .laser.npy + .laser.yaml (the laser layer, which the MapServer's load_map resumes with the .ot),
// .pgm + .yaml (map_server files of the fused 2D view), .npy (fusedLogOdds, float32, row 0 = the
// lowest y) and .png (the 2D view, y up). With nothing known there is no 2D view: the 2D files
// are left out. Throws std::runtime_error naming a file that cannot be written.
MapOutputs writeMapOutputs(const MappingSession& mapper, const std::string& dir,
                           const std::string& name);

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
