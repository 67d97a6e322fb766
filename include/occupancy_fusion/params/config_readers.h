// One reader per core configuration struct, over any ParameterSource (the ROS parameter server in
// the nodelets, a YAML file in offline_mapper and benchmark), so both configure the core the same
// way. Parameter names follow octomap_server where the meaning is the same. Absent keys keep the
// struct's in-class default. Each reader validates what it read and throws std::invalid_argument
// naming the offending parameter.
#pragma once

#include "occupancy_fusion/integrators/point_cloud_integrator.h"
#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/occupancy_model.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/params/parameter_source.h"

namespace occupancy_fusion {

// sensor_model/hit, sensor_model/miss, sensor_model/min, sensor_model/max (probabilities),
// occupancy_threshold (probability above which a voxel or cell is occupied).
OccupancyModel readOccupancyModel(const ParameterSource& source);

// resolution (m), the occupancy model above, max_memory_mb (MiB, 0 = unbounded), spill_folder
// (the store the bound's evicted blocks go to; empty: they are dropped), spill_max_mb (MiB, the
// store's limit on disk; 0 = the disk's), checkpoint_period (s; 0 = none: with spill_folder, the
// map resumes from the store's last checkpoint and its owner checkpoints it this often),
// layer_max_memory_mb (MiB, the 2D laser layer's bound; its tiles beyond it go to the same store;
// 0 = unbounded).
VoxelMapConfig readVoxelMapConfig(const ParameterSource& source);

// occupancy_min_z, occupancy_max_z (m, map frame; the height band projected into the 2D grid,
// unbounded when absent).
FusedGridConfig readFusedGridConfig(const ParameterSource& source);

// What a mapper nodelet reads besides its map and integrator: queue_size (messages, >= 1: the
// subscribers' and the tf2 filter's queues) and threads (the OpenMP threads of its integrations,
// in [0, kMaxThreads]; 0: the integrating thread's own default).
struct MapperNodeletConfig {
  static constexpr int kMaxThreads = 256;  // more is a typo, not a machine
  int queue_size = 5;
  int threads = 0;
  void validate() const;  // throws std::invalid_argument naming the bad parameter
};
MapperNodeletConfig readMapperNodeletConfig(const ParameterSource& source);

// Readers of integrator configs are defined inline: the map library, which holds the readers
// above, must not depend on the integrators library (it links the other way round).

// sensor_model/max_range (m, negative = unlimited), discretize, clear_passed,
// passed_miss_probability, passed_margin.
inline PointCloudIntegratorConfig readPointCloudIntegratorConfig(const ParameterSource& source) {
  PointCloudIntegratorConfig config;
  source.get("sensor_model/max_range", &config.max_range);
  source.get("discretize", &config.discretize);
  source.get("clear_passed", &config.clear_passed);
  source.get("passed_miss_probability", &config.passed_miss_probability);
  source.get("passed_margin", &config.passed_margin);
  config.validate();
  return config;
}

}  // namespace occupancy_fusion
