// MapServer nodelet: gets the shared map of its manager and publishes it (MapPublisher). It can
// resume a saved map at start (~load_map) and save the map when it is unloaded
// (~save_on_shutdown), so that a restart loses nothing; with checkpoint_period and spill_folder
// it checkpoints the map to its store that often (and once more when unloaded), and a map
// created on that store resumed its last checkpoint. With reanchoring/source path it reads the
// SLAM system's optimised keyframes (nav_msgs/Path on reanchoring/path_topic) and re-places the
// map's submaps by them (mapping/map_reanchoring.h).
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "occupancy_fusion/map/saved_map.h"
#include "occupancy_fusion/mapping/submap_files.h"
#include "occupancy_fusion/ros/keyframe_path.h"
#include "occupancy_fusion/ros/map_publisher.h"
#include "occupancy_fusion/ros/ros_parameter_source.h"
#include "occupancy_fusion/ros/shared_map_access.h"

namespace occupancy_fusion {

// What the MapServer keeps across restarts (parameters load_map and save_on_shutdown).
struct MapPersistenceConfig {
  std::string load_map;          // .ot (exact log-odds) or .bt (labels) file; empty: start empty
  std::string save_on_shutdown;  // path prefix; empty: no save when the nodelet is unloaded
  // reanchoring/source path: the topic of the SLAM system's keyframes (nav_msgs/Path).
  std::string path_topic = "slam/path";
};

MapPersistenceConfig readMapPersistenceConfig(const ParameterSource& source) {
  MapPersistenceConfig config;
  source.get("load_map", &config.load_map);
  source.get("save_on_shutdown", &config.save_on_shutdown);
  source.get("reanchoring/path_topic", &config.path_topic);
  return config;
}

class MapServer : public nodelet::Nodelet {
 public:
  // Unloading the nodelet (or stopping its manager) saves the map. Mappers of the manager may
  // still be writing: the save reads through the map's shared lock, and the map lives as long as
  // this nodelet holds it.
  ~MapServer() override {
    if (!map_) return;
    checkpoint_timer_.stop();
    if (map_->voxels().spillStatus().checkpoints) checkpoint();
    if (persistence_.save_on_shutdown.empty()) return;
    std::vector<std::string> written;
    try {
      saveMapFiles(*map_, grid_config_, persistence_.save_on_shutdown, &written);
      NODELET_INFO("save_on_shutdown: saved map '%s' as %s.{ot,bt,pgm,yaml,laser.yaml,laser.npy}",
                   map_->name().c_str(), persistence_.save_on_shutdown.c_str());
    } catch (const std::exception& error) {
      NODELET_ERROR("save_on_shutdown: saving map '%s' failed (%zu files written): %s",
                    map_->name().c_str(), written.size(), error.what());
    }
  }

 private:
  void onInit() override {
    const RosParameterSource parameters(getPrivateNodeHandle());
    try {
      persistence_ = readMapPersistenceConfig(parameters);
      std::shared_ptr<SharedMap> map = acquireSharedMap(parameters, getName());
      if (!persistence_.load_map.empty()) loadMap(persistence_.load_map, map.get());
      startReanchoring(map.get());
      const MapPublisherConfig publisher_config = readMapPublisherConfig(parameters);
      grid_config_ = publisher_config.grid;
      publisher_ = std::make_unique<MapPublisher>(getNodeHandle(), getPrivateNodeHandle(),
                                                  getName(), map, publisher_config);
      map_ = std::move(map);  // only now: a nodelet that failed to start saves nothing
      startCheckpoints();
    } catch (const std::invalid_argument& error) {
      NODELET_FATAL("invalid parameter: %s", error.what());
      throw;
    } catch (const std::runtime_error& error) {
      NODELET_FATAL("%s", error.what());
      throw;
    }
  }

  // Refuses to start on a bad file: a user who asked to resume a map must not silently get an
  // empty one (and overwrite the saved map at shutdown).
  void loadMap(const std::string& path, SharedMap* map) {
    ResumedMap resumed;
    try {
      resumed = resumeSavedMap(path, &map->voxels(), &map->layer());
    } catch (const std::exception& error) {
      throw std::runtime_error("load_map: cannot resume from '" + path + "': " + error.what() +
                               " (fix the path, or set load_map to \"\" to start an empty map)");
    }
    if (resumed.known_voxels_before > 0) {
      NODELET_WARN(
          "load_map: map '%s' already held %zu known voxels (a mapper started first); "
          "the file's voxels replaced those it contains",
          map->name().c_str(), resumed.known_voxels_before);
    }
    if (resumed.labels_only) {
      NODELET_WARN(
          "load_map: %s is a .bt file, which holds labels only: occupied voxels start "
          "at the upper clamping bound and free ones at the lower; save and load .ot "
          "files to resume every log-odds exactly",
          path.c_str());
    }
    if (!resumed.layer_found) {
      NODELET_INFO("load_map: no laser layer file %s beside it: the 2D laser layer starts empty",
                   resumed.layer_yaml.c_str());
    }
    NODELET_INFO("load_map: map '%s' resumed from %s (%zu known voxels, %zu laser layer cells)",
                 map->name().c_str(), path.c_str(), resumed.known_voxels, resumed.layer_cells);
  }

  // A loaded map has no trajectory to follow: it stays where it is. With a path, its corrections.
  void startReanchoring(SharedMap* map) {
    MapReanchoring* reanchoring = map->reanchoring();
    if (reanchoring == nullptr) return;
    if (!persistence_.load_map.empty()) resumeSubmaps(reanchoring);
    const ReanchoringConfig& config = reanchoring->config();
    NODELET_INFO(
        "map '%s' follows its localisation (reanchoring/source %s): frames placed by "
        "%s, a submap every %.1f m",
        map->name().c_str(), sourceName(config.source), config.odom_frame.c_str(),
        config.submap_distance);
    if (config.source != ReanchoringConfig::Source::kPath) return;
    // On the manager's shared threads, not this nodelet's own queue: a correction takes up to
    // seconds (its laser scans drawn again), and on that queue it held the publishing timer, so
    // the re-sampled map waited for the whole correction before it was sent.
    path_subscriber_ =
        getMTNodeHandle().subscribe(persistence_.path_topic, 1, &MapServer::onPath, this);
  }

  // The submaps saved beside the loaded map, so that it moves with later corrections; without
  // them (or when they cannot be read) the loaded map stays where it is.
  void resumeSubmaps(MapReanchoring* reanchoring) {
    const std::string path = submapFilePath(persistence_.load_map);
    try {
      if (readSubmapFile(reanchoring, path)) {
        NODELET_INFO(
            "load_map: %zu submaps resumed from %s: the loaded map follows later "
            "corrections",
            reanchoring->fusion().submaps().size() - 1, path.c_str());
        return;
      }
      reanchoring->fusion().fixWrittenSoFar();
      NODELET_INFO("load_map: no %s beside it: the loaded map stays where it is", path.c_str());
    } catch (const std::runtime_error& error) {
      NODELET_WARN("load_map: %s; the loaded map stays where it is", error.what());
    }
  }

  void onPath(const nav_msgs::Path::ConstPtr& path) {
    const auto strip = [](const std::string& frame) {
      return frame.rfind('/', 0) == 0 ? frame.substr(1) : frame;
    };
    if (strip(path->header.frame_id) != strip(map_->frameId())) {
      NODELET_WARN_THROTTLE(10.0, "path on '%s' is in frame '%s', not the map's '%s': ignored",
                            path_subscriber_.getTopic().c_str(), path->header.frame_id.c_str(),
                            map_->frameId().c_str());
      return;
    }
    const SubmapMoveResult result =
        map_->reanchoring()->applyPath(keyframesOf(*path), path->header.stamp.toSec());
    const ReanchoringStatistics statistics = map_->reanchoring()->statistics();
    if (statistics.path_corrections == 0 && !path->poses.empty()) {
      NODELET_WARN_THROTTLE(10.0,
                            "none of the path's %zu keyframes is within the odometry heard "
                            "(reanchoring/base_frame '%s' in '%s'): no submap placed",
                            path->poses.size(), map_->reanchoring()->config().base_frame.c_str(),
                            map_->reanchoring()->config().odom_frame.c_str());
    }
    if (result.moved == 0) return;
    NODELET_INFO("path of %zu keyframes: %zu submaps re-placed, %zu blocks rebuilt in %.0f ms",
                 path->poses.size(), result.moved, result.blocks_rewritten, 1e3 * result.seconds);
  }

  // checkpoint_period (a map parameter): the map's store keeps a checkpoint that often.
  void startCheckpoints() {
    const VoxelMap& voxels = map_->voxels();
    const double period = voxels.config().checkpoint_period;
    if (!(period > 0)) return;
    const SpillStatus status = voxels.spillStatus();
    if (!status.checkpoints) {
      NODELET_ERROR(
          "checkpoint_period %.1f s: no checkpoints, the store in spill_folder '%s' "
          "is not open: %s",
          period, voxels.config().spill_folder.c_str(),
          voxels.config().spill_folder.empty() ? "spill_folder is not set"
                                               : status.last_error.c_str());
      return;
    }
    NODELET_INFO(
        "map '%s' checkpointed to %s every %.1f s; resumed %zu blocks and %zu laser "
        "layer tiles (%s)",
        map_->name().c_str(), voxels.config().spill_folder.c_str(), period, status.resumed_blocks,
        map_->resumedLayerTiles(),
        status.resumed_stamp.empty() ? "no checkpoint there, a new map"
                                     : status.resumed_stamp.c_str());
    checkpoint_timer_ = getNodeHandle().createWallTimer(
        ros::WallDuration(period), [this](const ros::WallTimerEvent&) { checkpoint(); });
  }

  void checkpoint() {
    const std::string stamp = checkpointStampNow();
    const CheckpointResult result = map_->checkpoint(stamp);
    if (!result.written) {
      NODELET_WARN_THROTTLE(60.0, "checkpoint of map '%s' failed (mapping goes on): %s",
                            map_->name().c_str(), map_->voxels().spillStatus().last_error.c_str());
      return;
    }
    NODELET_DEBUG("checkpoint %s: %zu blocks written, %zu removed, %.1f ms locked, %.1f ms sync",
                  stamp.c_str(), result.blocks_written, result.blocks_removed,
                  1e3 * result.locked_seconds, 1e3 * result.sync_seconds);
  }

  MapPersistenceConfig persistence_;
  ros::WallTimer checkpoint_timer_;
  FusedGridConfig grid_config_;
  std::shared_ptr<SharedMap> map_;
  std::unique_ptr<MapPublisher> publisher_;
  ros::Subscriber path_subscriber_;
};

}  // namespace occupancy_fusion

PLUGINLIB_EXPORT_CLASS(occupancy_fusion::MapServer, nodelet::Nodelet)
