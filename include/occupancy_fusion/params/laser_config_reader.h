// Readers of the laser mapper's configuration over any ParameterSource (the ROS parameter server
// in the LaserMapper nodelet, a YAML file in offline_mapper and benchmark), so both configure the
// laser core the same way. The layout follows costmap_2d's observation sources:
//
//   laser:                        # defaults shared by every source
//     method: exact
//     range_sigma: 0.05
//   observation_sources: "front rear"
//   front: {topic: front/scan, method: mipmap}   # a source's keys override laser/
//   rear:  {topic: rear/scan, sensor_frame: rear_laser}
//   local_grid: {resolution: 0.05, size_x: 20.0, size_y: 20.0, frame_id: base_link}
//
// Absent keys keep the defaults; every reader validates what it read and throws
// std::invalid_argument naming the offending parameter with its full key (e.g.
// "front/range_sigma").
#pragma once

#include <string>
#include <vector>

#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"
#include "occupancy_fusion/params/parameter_source.h"

namespace occupancy_fusion {

// Keys under `prefix` ("" for the top level, else ending in '/', e.g. "laser/" or "front/"):
//   method (exact|sampling|mipmap|lines), range_resolution (m), range_sigma (m), prior (0..1),
//   min_log_ratio, max_log_ratio, no_return_free_length (m), above_range_max_is_no_return (bool),
//   max_samples_per_axis, mipmap_safety_radius (m), exact_cache_capacity.
// Keys absent under the prefix keep the value in `defaults`.
PolarLaserIntegratorConfig readPolarLaserIntegratorConfig(
    const ParameterSource& source, const std::string& prefix,
    const PolarLaserIntegratorConfig& defaults = PolarLaserIntegratorConfig());

// One laser observation source.
struct LaserSourceConfig {
  std::string name;          // the source's key in observation_sources
  std::string topic;         // sensor_msgs/LaserScan topic; default: the source's name
  std::string sensor_frame;  // overrides the scan's header.frame_id when not empty
  double max_tilt = 0.1;     // rad: largest tilt of the scan plane from the map's x-y plane
  PolarLaserIntegratorConfig integrator;

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// Source `name` from keys `name/...`: topic, sensor_frame, max_tilt and the integrator keys above;
// every absent integrator key and max_tilt fall back to the top-level `laser/` block, then to the
// in-class defaults.
LaserSourceConfig readLaserSourceConfig(const ParameterSource& source, const std::string& name);

// observation_sources: space-separated source names (costmap_2d's style) or a list of names;
// every source as readLaserSourceConfig. Throws when absent, empty or a name repeats.
std::vector<LaserSourceConfig> readLaserSourceConfigs(const ParameterSource& source);

// The vehicle-frame local grid (the paper's V-grid) and how it is published.
struct LocalGridPublishConfig {
  LocalLaserGridConfig grid;
  std::string frame_id = "base_link";  // vehicle frame the grid is centred on (REP-105)
  double publish_rate = 10.0;          // Hz: local grid fusion and publication rate
  void validate() const;               // throws std::invalid_argument naming the bad field
};

// local_grid/resolution (m), local_grid/size_x (m), local_grid/size_y (m), local_grid/frame_id,
// local_grid/publish_rate (Hz, > 0).
LocalGridPublishConfig readLocalGridPublishConfig(const ParameterSource& source);

// Everything the laser mapper reads.
struct LaserMapperConfig {
  std::string map_frame = "map";  // frame of the shared 2D layer (octomap_server's frame_id)
  bool write_world_layer = true;  // accumulate scans into the shared map's 2D layer
  std::vector<LaserSourceConfig> sources;
  LocalGridPublishConfig local_grid;
};

// frame_id, write_world_layer, the sources and the local grid above.
LaserMapperConfig readLaserMapperConfig(const ParameterSource& source);

}  // namespace occupancy_fusion
