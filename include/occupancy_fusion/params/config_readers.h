// One reader per core configuration struct, over any ParameterSource (the ROS parameter server in
// the nodelets, a YAML file in offline_mapper and benchmark), so both configure the core the same
// way. Parameter names follow octomap_server where the meaning is the same. Absent keys keep the
// struct's in-class default. Each reader validates what it read and throws std::invalid_argument
// naming the offending parameter.
#pragma once

#include "occupancy_fusion/map/occupancy_model.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/params/parameter_source.h"

namespace occupancy_fusion {

// sensor_model/hit, sensor_model/miss, sensor_model/min, sensor_model/max (probabilities),
// occupancy_threshold (probability above which a voxel or cell is occupied).
OccupancyModel readOccupancyModel(const ParameterSource& source);

// resolution (m), the occupancy model above, max_memory_mb (MiB, 0 = unbounded).
VoxelMapConfig readVoxelMapConfig(const ParameterSource& source);

}  // namespace occupancy_fusion
