// The shared map: nodelets loaded into one manager (one process) write to and read from one map
// object, found by name in a process-wide registry. The registry holds weak references, so the
// map lives exactly as long as some nodelet uses it; the first user creates it from its own
// parameters and later users must agree on the geometry.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <ros/time.h>

#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/map_checkpoints.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/mapping/map_reanchoring.h"
#include "occupancy_fusion/params/parameter_source.h"

namespace occupancy_fusion {

struct SharedMapConfig {
  std::string name = "map";       // registry key (parameter map_name)
  std::string frame_id = "map";   // frame the map is expressed in (parameter frame_id)
  VoxelMapConfig voxels;          // resolution, sensor_model/*, max_memory_mb
  ReanchoringConfig reanchoring;  // reanchoring/*: submaps placed by the localisation
  // The 2D layer shares the 3D map's resolution and sensor model, so that the fused view
  // combines cells of the same size.
  GridLayer2DConfig layer() const;

  void validate() const;  // throws std::invalid_argument naming the bad parameter
};

// map_name, frame_id, and everything readVoxelMapConfig and readReanchoringConfig read.
SharedMapConfig readSharedMapConfig(const ParameterSource& source);

// The 3D voxel map and the 2D laser layer of one map, and a log of the frames integrated into
// them. The maps are thread-safe on their own (see VoxelMap); the log has a lock of its own.
class SharedMap {
 public:
  explicit SharedMap(const SharedMapConfig& config);

  const SharedMapConfig& config() const { return config_; }
  const std::string& name() const { return config_.name; }
  const std::string& frameId() const { return config_.frame_id; }
  VoxelMap& voxels() { return voxels_; }
  const VoxelMap& voxels() const { return voxels_; }
  GridLayer2D& layer() { return layer_; }
  const GridLayer2D& layer() const { return layer_; }
  // The submaps and their corrections (nullptr: reanchoring/source none). Every mapper's session
  // places its frames through it.
  MapReanchoring* reanchoring() { return reanchoring_.get(); }
  const MapReanchoring* reanchoring() const { return reanchoring_.get(); }

  void reset();  // forgets everything: all voxels and cells unknown again, and the submaps
  // A checkpoint of the voxels and the laser layer to the map's store (checkpoint_period), with
  // the submaps when the map follows its localisation.
  CheckpointResult checkpoint(const std::string& stamp);
  std::size_t resumedLayerTiles() const { return checkpoints_.resumedTiles(); }

  // A frame of `source` (its input topic) stamped `stamp` is in the map: called by a mapper after
  // the write. The map keeps the last kIntegratedLogSize of them, numbered in that order.
  void noteIntegrated(const std::string& source, const ros::Time& stamp);
  struct IntegratedFrame {
    std::uint64_t number;  // 1, 2, ... in the order noted
    std::string source;
    ros::Time stamp;
  };
  static constexpr std::size_t kIntegratedLogSize = 4096;
  // The frames noted after frame number `after` (0: all kept), oldest first. Read before the map
  // is read for an output, every frame it returns is in what is read next.
  std::vector<IntegratedFrame> integratedSince(std::uint64_t after) const;
  std::uint64_t integratedCount() const;  // the number of the last frame noted (0: none)
  // Waits until a frame after number `after` is noted, `deadline` passes or wakeWaiters() has
  // been called since wakeCalls() returned `wake_calls`; true when such a frame has been noted.
  bool waitForIntegrated(std::uint64_t after, std::chrono::steady_clock::time_point deadline,
                         std::uint64_t wake_calls);
  std::uint64_t wakeCalls() const;
  void wakeWaiters();

 private:
  SharedMapConfig config_;
  VoxelMap voxels_;
  GridLayer2D layer_;
  MapCheckpoints checkpoints_;  // after voxels_ and layer_: restores the layer's resumed tiles
  // After checkpoints_: what a checkpoint resumed is the map's fixed part, never moved.
  std::unique_ptr<MapReanchoring> reanchoring_;
  mutable std::mutex integrated_mutex_;
  std::deque<IntegratedFrame> integrated_;  // the last kIntegratedLogSize frames noted
  std::uint64_t integrated_count_ = 0;
  std::condition_variable integrated_noted_;
  std::uint64_t wake_calls_ = 0;  // wakeWaiters() so far
};

class MapRegistry {
 public:
  static MapRegistry& instance();  // process-wide

  // The live map called config.name, or a new one built from config when there is none.
  // Throws std::invalid_argument when a live map of that name has another resolution or frame.
  // *created (optional) tells which happened, so callers can warn about ignored settings.
  std::shared_ptr<SharedMap> acquire(const SharedMapConfig& config, bool* created = nullptr);

  std::size_t liveCount() const;  // maps that still have a user

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::weak_ptr<SharedMap>> maps_;
};

}  // namespace occupancy_fusion
