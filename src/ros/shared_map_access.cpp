#include "occupancy_fusion/ros/shared_map_access.h"

#include <ros/console.h>

namespace occupancy_fusion {
namespace {

bool sameModel(const OccupancyModel& a, const OccupancyModel& b) {
  return a.prob_hit == b.prob_hit && a.prob_miss == b.prob_miss && a.clamp_min == b.clamp_min &&
         a.clamp_max == b.clamp_max && a.occupancy_threshold == b.occupancy_threshold;
}

}  // namespace

std::shared_ptr<SharedMap> acquireSharedMap(const ParameterSource& parameters,
                                            const std::string& nodelet_name) {
  const SharedMapConfig wanted = readSharedMapConfig(parameters);
  bool created = false;
  std::shared_ptr<SharedMap> map = MapRegistry::instance().acquire(wanted, &created);
  if (created) {
    ROS_INFO("%s: created map '%s' (frame '%s', resolution %.3f m)", nodelet_name.c_str(),
             map->name().c_str(), map->frameId().c_str(), map->voxels().resolution());
    return map;
  }
  ROS_INFO("%s: sharing map '%s' (frame '%s', resolution %.3f m)", nodelet_name.c_str(),
           map->name().c_str(), map->frameId().c_str(), map->voxels().resolution());
  const VoxelMapConfig& existing = map->config().voxels;
  if (!sameModel(existing.model, wanted.voxels.model) ||
      existing.max_memory_bytes != wanted.voxels.max_memory_bytes ||
      existing.spill_folder != wanted.voxels.spill_folder ||
      existing.checkpoint_period != wanted.voxels.checkpoint_period) {
    ROS_WARN(
        "%s: sensor_model/*, max_memory_mb, spill_folder or checkpoint_period differ from those "
        "of the shared map '%s', "
        "which keeps the settings of the nodelet that created it",
        nodelet_name.c_str(), map->name().c_str());
  }
  // The storage changes the memory only, never a voxel: worth a note, not a warning.
  if (existing.block_storage != wanted.voxels.block_storage) {
    ROS_INFO("%s: the shared map '%s' keeps block_storage '%s' of the nodelet that created it",
             nodelet_name.c_str(), map->name().c_str(),
             existing.block_storage == BlockStorage::kHybrid ? "hybrid" : "dense");
  }
  return map;
}

}  // namespace occupancy_fusion
