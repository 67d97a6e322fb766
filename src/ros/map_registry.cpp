#include "occupancy_fusion/ros/map_registry.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include <ros/console.h>

#include "occupancy_fusion/mapping/submap_files.h"
#include "occupancy_fusion/params/config_readers.h"

namespace occupancy_fusion {

GridLayer2DConfig SharedMapConfig::layer() const { return laserLayerConfig(voxels); }

void SharedMapConfig::validate() const {
  if (name.empty()) throw std::invalid_argument("map_name must not be empty");
  if (frame_id.empty()) throw std::invalid_argument("frame_id must not be empty");
  voxels.validate();
  reanchoring.validate();
}

SharedMapConfig readSharedMapConfig(const ParameterSource& source) {
  SharedMapConfig config;
  source.get("map_name", &config.name);
  source.get("frame_id", &config.frame_id);
  config.voxels = readVoxelMapConfig(source);
  config.reanchoring = readReanchoringConfig(source);
  config.validate();
  return config;
}

SharedMap::SharedMap(const SharedMapConfig& config)
    : config_(config),
      voxels_(config.voxels),
      layer_(config.layer()),
      checkpoints_(&voxels_, &layer_),
      reanchoring_(config.reanchoring.enabled()
                       ? std::make_unique<MapReanchoring>(&voxels_, &layer_, config.reanchoring)
                       : nullptr) {
  if (!reanchoring_) return;
  try {
    if (resumeCheckpointedSubmaps(checkpoints_, reanchoring_.get())) {
      ROS_INFO("map '%s': %zu submaps resumed with the checkpoint", config_.name.c_str(),
               reanchoring_->fusion().submaps().size() - 1);
    }
  } catch (const std::runtime_error& error) {
    ROS_WARN("map '%s': %s; the resumed map stays where it is", config_.name.c_str(), error.what());
  }
}

CheckpointResult SharedMap::checkpoint(const std::string& stamp) {
  if (reanchoring_) return checkpointWithSubmaps(&checkpoints_, reanchoring_.get(), stamp);
  return checkpoints_.checkpoint(stamp);
}

void SharedMap::reset() {
  {
    // Forgotten first: a frame noted after this is written after the reset too.
    const std::lock_guard<std::mutex> lock(integrated_mutex_);
    integrated_.clear();
  }
  if (reanchoring_) {
    reanchoring_->reset();
    return;
  }
  voxels_.reset();
  layer_.reset();
}

void SharedMap::noteIntegrated(const std::string& source, const ros::Time& stamp) {
  const std::lock_guard<std::mutex> lock(integrated_mutex_);
  integrated_.push_back({++integrated_count_, source, stamp});
  if (integrated_.size() > kIntegratedLogSize) integrated_.pop_front();
  integrated_noted_.notify_all();
}

std::uint64_t SharedMap::integratedCount() const {
  const std::lock_guard<std::mutex> lock(integrated_mutex_);
  return integrated_count_;
}

bool SharedMap::waitForIntegrated(std::uint64_t after,
                                  std::chrono::steady_clock::time_point deadline,
                                  std::uint64_t wake_calls) {
  std::unique_lock<std::mutex> lock(integrated_mutex_);
  integrated_noted_.wait_until(
      lock, deadline, [&] { return integrated_count_ > after || wake_calls_ != wake_calls; });
  return integrated_count_ > after;
}

std::uint64_t SharedMap::wakeCalls() const {
  const std::lock_guard<std::mutex> lock(integrated_mutex_);
  return wake_calls_;
}

void SharedMap::wakeWaiters() {
  const std::lock_guard<std::mutex> lock(integrated_mutex_);
  ++wake_calls_;
  integrated_noted_.notify_all();
}

std::vector<SharedMap::IntegratedFrame> SharedMap::integratedSince(std::uint64_t after) const {
  const std::lock_guard<std::mutex> lock(integrated_mutex_);
  std::vector<IntegratedFrame> frames;
  for (auto it = integrated_.rbegin(); it != integrated_.rend() && it->number > after; ++it) {
    frames.push_back(*it);
  }
  std::reverse(frames.begin(), frames.end());
  return frames;
}

MapRegistry& MapRegistry::instance() {
  static MapRegistry registry;
  return registry;
}

std::shared_ptr<SharedMap> MapRegistry::acquire(const SharedMapConfig& config, bool* created) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::weak_ptr<SharedMap>& slot = maps_[config.name];
  std::shared_ptr<SharedMap> map = slot.lock();
  if (created) *created = !map;
  if (!map) {
    map = std::make_shared<SharedMap>(config);
    slot = map;
    return map;
  }
  if (map->config().voxels.resolution != config.voxels.resolution) {
    std::ostringstream message;
    message << "resolution " << config.voxels.resolution << " does not match the resolution "
            << map->config().voxels.resolution << " of the shared map '" << config.name
            << "' already created in this nodelet manager; give every nodelet of a manager the "
               "same resolution, or a different map_name";
    throw std::invalid_argument(message.str());
  }
  if (map->frameId() != config.frame_id) {
    throw std::invalid_argument("frame_id '" + config.frame_id + "' does not match the frame '" +
                                map->frameId() + "' of the shared map '" + config.name +
                                "' already created in this nodelet manager");
  }
  return map;
}

std::size_t MapRegistry::liveCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::size_t live = 0;
  for (const auto& entry : maps_) live += entry.second.expired() ? 0 : 1;
  return live;
}

}  // namespace occupancy_fusion
