// Publishes a shared map (topics of octomap_server) and serves its services. Used by the
// MapServer nodelet and by a mapper nodelet that runs alone and publishes its own map.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>
#include <std_srvs/Empty.h>

#include "occupancy_fusion/BoundingBoxQuery.h"
#include "occupancy_fusion/SaveMap.h"
#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/params/parameter_source.h"
#include "occupancy_fusion/ros/map_registry.h"
#include "occupancy_fusion/ros/occupied_voxel_cache.h"

namespace occupancy_fusion {

struct MapPublisherConfig {
  double publish_rate = 1.0;  // Hz, how often watched outputs are refreshed
  // Hz: projected_map is sent soon after each frame a mapper integrated, at most this often
  // (0: at publish_rate, as the other outputs).
  double projected_map_rate = 50.0;
  std::string save_prefix = "map";  // ~save_map with an empty prefix writes <save_prefix>.ot etc.
  FusedGridConfig grid;             // occupancy_min_z / occupancy_max_z

  void validate() const;  // throws std::invalid_argument naming the bad parameter
};

// publish_rate, save_prefix, occupancy_min_z, occupancy_max_z.
MapPublisherConfig readMapPublisherConfig(const ParameterSource& source);

// Saves a shared map with saveMap (mapping/map_saving.h: the files, what is written when, and
// the errors), in the height band `grid`, warning about voxels OctoMap's keys cannot hold.
// `lock_statistics`, if given, records how long each read of the map took.
class MapLockStatistics;
void saveMapFiles(SharedMap& map, const FusedGridConfig& grid, const std::string& prefix,
                  std::vector<std::string>* written, MapLockStatistics* lock_statistics = nullptr);

// Wall time (ms) of the parts of the last publishing cycle, and what they handled. Outputs
// without subscribers, or unchanged since they were last sent, cost nothing and report 0.
struct PublishTimings {
  std::uint64_t cycles = 0;                // publishing cycles so far
  double cache_ms = 0.0;                   // refreshing the occupied-voxel cache
  std::size_t cache_blocks_refreshed = 0;  // blocks re-read for it
  bool cache_full_rebuild = false;
  double markers_ms = 0.0;          // occupied_cells_vis_array
  double cloud_ms = 0.0;            // octomap_point_cloud_centers
  double binary_ms = 0.0;           // octomap_binary (whole-map conversion)
  std::size_t occupied_voxels = 0;  // in the cache
  std::size_t map_blocks = 0;       // allocated in the map
};

// projected_map's last update, sent from a thread of its own as frames are integrated.
struct GridTimings {
  std::uint64_t published = 0;            // projected_map messages sent so far
  double grid_ms = 0.0;                   // fused 2D view update + message
  std::size_t grid_blocks_processed = 0;  // map blocks the view re-read
};

// How long the MapPublisher keeps the shared map locked, measured from the outside: every call
// into the VoxelMap or GridLayer2D takes the map's lock (shared for reads, exclusive for clear and
// reset) and holds it at most for the call's duration, so the longest call bounds how long the
// publisher or one of its services can keep a mapper from integrating. Thread-safe: the timer and
// the services may run on different threads.
class MapLockStatistics {
 public:
  // One call into the map that took `milliseconds`; `what` names it (a string literal).
  void recordHold(const char* what, double milliseconds);
  // How long a trivial read (map version) waited: the time a mapper's write still held the lock.
  void recordReadWait(double milliseconds);

  double longestHoldMs() const;
  std::string longestHoldCall() const;
  double longestReadWaitMs() const;

 private:
  mutable std::mutex mutex_;
  double longest_hold_ms_ = 0.0;
  const char* longest_hold_call_ = "none";
  double longest_read_wait_ms_ = 0.0;
};

class MapPublisher {
 public:
  // Topics on node_handle, services and diagnostics under private_node_handle. `name` labels log
  // lines and diagnostics.
  MapPublisher(const ros::NodeHandle& node_handle, const ros::NodeHandle& private_node_handle,
               const std::string& name, std::shared_ptr<SharedMap> map,
               const MapPublisherConfig& config);
  // Stops the timer and projected_map's thread first, waiting for a running publishing cycle.
  ~MapPublisher();
  MapPublisher(const MapPublisher&) = delete;
  MapPublisher& operator=(const MapPublisher&) = delete;

  const PublishTimings& lastTimings() const { return timings_; }
  GridTimings lastGridTimings() const;
  const MapLockStatistics& lockStatistics() const { return lock_statistics_; }

 private:
  // Versions of the map and layer an output was built from, so unchanged outputs are not resent.
  struct SentVersion {
    std::uint64_t voxels = 0;
    std::uint64_t layer = 0;
    bool operator==(const SentVersion& other) const {
      return voxels == other.voxels && layer == other.layer;
    }
  };

  void onTimer(const ros::WallTimerEvent& event);
  std::uint64_t movesResampled() const;  // the map's corrections so far (0: no reanchoring)
  static constexpr double kCorrectionCheckSeconds = 0.1;
  void publishCycle();
  bool needsSending(const ros::Publisher& publisher, const SentVersion& sent) const;
  SentVersion currentVersion() const;
  void refreshCache();
  void publishGrid(const ros::Time& stamp);
  void sendGridAsFramesArrive();  // projected_map's thread
  void publishMarkers(const ros::Time& stamp);
  void publishCloud(const ros::Time& stamp);
  void publishBinary(const ros::Time& stamp);
  void fillDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status);

  bool onReset(std_srvs::Empty::Request& request, std_srvs::Empty::Response& response);
  bool onClearBox(BoundingBoxQuery::Request& request, BoundingBoxQuery::Response& response);
  bool onSaveMap(SaveMap::Request& request, SaveMap::Response& response);

  std::string name_;
  std::shared_ptr<SharedMap> map_;
  MapPublisherConfig config_;

  OccupiedVoxelCache cache_;
  FusedGridView grid_view_;
  PublishTimings timings_;
  MapLockStatistics lock_statistics_;

  SentVersion grid_sent_, markers_sent_, cloud_sent_, binary_sent_;
  ros::Publisher grid_publisher_, markers_publisher_, cloud_publisher_, binary_publisher_;
  ros::Publisher grid_stamps_publisher_;  // projected_map_stamps: what each projected_map holds
  std::uint64_t grid_frames_listed_ = 0;  // the last frame number of the map's log sent with it
  ros::ServiceServer reset_service_, clear_box_service_, save_map_service_;
  // Wall clock: with use_sim_time a bag that has ended stops ROS time, and a subscriber joining
  // then must still get the current map, not a stale latched one.
  ros::WallTimer timer_;
  diagnostic_updater::Updater diagnostics_;
  ros::WallTime next_diagnostics_;  // diagnostics are published once per wall-clock second
  ros::WallTime next_cycle_;        // the next publishCycle() due by publish_rate
  std::uint64_t moves_sent_ = 0;    // movesResampled() at the last cycle
  mutable std::mutex grid_timings_mutex_;
  GridTimings grid_timings_;
  std::mutex stop_mutex_;
  std::condition_variable stop_requested_;
  bool stopping_ = false;
  std::thread grid_thread_;  // last: started when everything it uses is built
};

}  // namespace occupancy_fusion
