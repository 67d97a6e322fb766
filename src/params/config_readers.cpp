#include "occupancy_fusion/params/config_readers.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace occupancy_fusion {
namespace {

constexpr double kBytesPerMebibyte = 1024.0 * 1024.0;

std::size_t readMemoryBound(const ParameterSource& source, const char* name = "max_memory_mb") {
  double megabytes = 0.0;
  source.get(name, &megabytes);
  if (!(megabytes >= 0.0) || !std::isfinite(megabytes)) {
    throw std::invalid_argument(std::string(name) + " must be >= 0 (0: unbounded), got " +
                                std::to_string(megabytes));
  }
  return static_cast<std::size_t>(megabytes * kBytesPerMebibyte);
}

BlockStorage readBlockStorage(const ParameterSource& source) {
  std::string name = "dense";
  source.get("block_storage", &name);
  if (name == "dense") return BlockStorage::kDense;
  if (name == "hybrid") return BlockStorage::kHybrid;
  throw std::invalid_argument("block_storage must be dense or hybrid, got '" + name + "'");
}

}  // namespace

OccupancyModel readOccupancyModel(const ParameterSource& source) {
  OccupancyModel model;
  source.get("sensor_model/hit", &model.prob_hit);
  source.get("sensor_model/miss", &model.prob_miss);
  source.get("sensor_model/min", &model.clamp_min);
  source.get("sensor_model/max", &model.clamp_max);
  source.get("occupancy_threshold", &model.occupancy_threshold);
  model.validate();  // its messages name the parameters above
  return model;
}

VoxelMapConfig readVoxelMapConfig(const ParameterSource& source) {
  VoxelMapConfig config;
  source.get("resolution", &config.resolution);
  config.model = readOccupancyModel(source);
  config.max_memory_bytes = readMemoryBound(source);
  source.get("spill_folder", &config.spill_folder);
  double spill_max_mb = 0.0;
  source.get("spill_max_mb", &spill_max_mb);
  if (!(spill_max_mb >= 0.0) || !std::isfinite(spill_max_mb)) {
    throw std::invalid_argument("spill_max_mb must be >= 0 (0: as much as the disk holds), got " +
                                std::to_string(spill_max_mb));
  }
  config.spill_max_bytes = static_cast<std::size_t>(spill_max_mb * kBytesPerMebibyte);
  source.get("checkpoint_period", &config.checkpoint_period);
  config.layer_max_memory_bytes = readMemoryBound(source, "layer_max_memory_mb");
  config.block_storage = readBlockStorage(source);
  config.validate();
  return config;
}

FusedGridConfig readFusedGridConfig(const ParameterSource& source) {
  FusedGridConfig config;
  source.get("occupancy_min_z", &config.min_z);
  source.get("occupancy_max_z", &config.max_z);
  config.validate();
  return config;
}

void MapperNodeletConfig::validate() const {
  if (queue_size < 1) {
    throw std::invalid_argument("queue_size must be >= 1, not " + std::to_string(queue_size));
  }
  if (threads < 0 || threads > kMaxThreads) {
    throw std::invalid_argument("threads must be in [0, " + std::to_string(kMaxThreads) +
                                "] (0: the OpenMP default), not " + std::to_string(threads));
  }
}

MapperNodeletConfig readMapperNodeletConfig(const ParameterSource& source) {
  MapperNodeletConfig config;
  source.get("queue_size", &config.queue_size);
  source.get("threads", &config.threads);
  config.validate();
  return config;
}

}  // namespace occupancy_fusion
