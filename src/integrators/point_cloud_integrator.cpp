#include "occupancy_fusion/integrators/point_cloud_integrator.h"

#include <omp.h>

#include <algorithm>
#include <bitset>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "occupancy_fusion/integrators/ray_traversal.h"

namespace occupancy_fusion {

// ---------------------------------------------------------------------------------------------
// VoxelUpdateSet

void VoxelUpdateSet::merge(const VoxelUpdateSet& other) {
  cached_ = nullptr;
  blocks_.reserve(blocks_.size() + other.blocks_.size());
  for (const auto& [key, theirs] : other.blocks_) {
    BlockMasks& ours = blocks_[key];
    for (int w = 0; w < kWords; ++w) {
      ours.free[w] |= theirs.free[w];
      ours.occupied[w] |= theirs.occupied[w];
    }
  }
}

void VoxelUpdateSet::clear() {
  blocks_.clear();
  cached_ = nullptr;
}

const VoxelUpdateSet::BlockMasks* VoxelUpdateSet::find(const BlockIndex& block) const {
  const auto it = blocks_.find(packBlock(block));
  return it == blocks_.end() ? nullptr : &it->second;
}

bool VoxelUpdateSet::isOccupied(const VoxelIndex& index) const {
  const BlockMasks* masks = find(VoxelMap::blockOf(index));
  if (masks == nullptr) return false;
  const int linear = VoxelMap::linearIndexInBlock(index);
  return (masks->occupied[linear >> 6] >> (linear & 63)) & 1u;
}

bool VoxelUpdateSet::isFree(const VoxelIndex& index) const {
  const BlockMasks* masks = find(VoxelMap::blockOf(index));
  if (masks == nullptr) return false;
  const int linear = VoxelMap::linearIndexInBlock(index);
  const std::uint64_t word = masks->free[linear >> 6] & ~masks->occupied[linear >> 6];
  return (word >> (linear & 63)) & 1u;
}

std::size_t VoxelUpdateSet::occupiedCount() const {
  std::size_t count = 0;
  for (const auto& entry : blocks_) {
    for (std::uint64_t word : entry.second.occupied) count += std::bitset<64>(word).count();
  }
  return count;
}

std::size_t VoxelUpdateSet::freeCount() const {
  std::size_t count = 0;
  for (const auto& entry : blocks_) {
    const BlockMasks& masks = entry.second;
    for (int w = 0; w < kWords; ++w) {
      count += std::bitset<64>(masks.free[w] & ~masks.occupied[w]).count();
    }
  }
  return count;
}

std::vector<BlockIndex> VoxelUpdateSet::blocks() const {
  std::vector<BlockIndex> result;
  result.reserve(blocks_.size());
  for (const auto& entry : blocks_) result.push_back(unpackBlock(entry.first));
  return result;
}

// ---------------------------------------------------------------------------------------------
// PointCloudIntegrator

void PointCloudIntegratorConfig::validate() const {
  if (std::isnan(max_range)) {
    throw std::invalid_argument("PointCloudIntegratorConfig.max_range must not be NaN");
  }
}

PointCloudIntegrator::PointCloudIntegrator(const PointCloudIntegratorConfig& config)
    : config_(config) {
  config_.validate();
}

namespace {

// The same range as VoxelMap::isInRange, without needing a map.
bool isRepresentable(const Eigen::Vector3d& point, double resolution) {
  const double limit = VoxelMap::kMaxCoordinateVoxels * resolution;
  return point.allFinite() && (point.array().abs() < limit).all();
}

// One point of OctoMap's computeUpdate (its no-bounding-box branch).
void castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& point, double max_range,
             double resolution, VoxelUpdateSet* update) {
  const Eigen::Vector3d ray = point - origin;
  const double distance = ray.norm();
  auto mark_free = [update](const VoxelIndex& index) { update->markFree(index); };
  if (max_range < 0.0 || distance <= max_range) {
    forEachVoxelOnRay(origin, point, resolution, RayEnd::kExclude, mark_free);
    update->markOccupied(voxelIndexOf(point, resolution));
  } else {
    const Eigen::Vector3d clipped_end = origin + ray * (max_range / distance);
    forEachVoxelOnRay(origin, clipped_end, resolution, RayEnd::kExclude, mark_free);
  }
}

// discretize: the centre of each end voxel once, in the order of the voxel's first point, as
// OcTree's computeDiscreteUpdate builds its discretized cloud; points outside the representable
// range are left out (and counted).
std::vector<Eigen::Vector3f> endVoxelCentres(const std::vector<Eigen::Vector3f>& points,
                                             double resolution, std::size_t* skipped) {
  std::vector<Eigen::Vector3f> centres;
  SpatialKeySet seen;
  for (const Eigen::Vector3f& p : points) {
    const Eigen::Vector3d point = p.cast<double>();
    if (!isRepresentable(point, resolution)) {
      ++*skipped;
      continue;
    }
    const VoxelIndex voxel = voxelIndexOf(point, resolution);
    if (!seen.insert(packKey(voxel)).second) continue;
    centres.push_back(((voxel.cast<double>().array() + 0.5) * resolution).matrix().cast<float>());
  }
  return centres;
}

}  // namespace

IntegrationStats PointCloudIntegrator::computeUpdate(
    const std::vector<Eigen::Vector3f>& points_in_map, const Eigen::Vector3d& sensor_origin_in_map,
    double resolution, VoxelUpdateSet* update) const {
  update->clear();
  IntegrationStats stats;
  stats.points = points_in_map.size();
  if (!isRepresentable(sensor_origin_in_map, resolution)) {
    stats.skipped_points = stats.points;
    return stats;
  }
  std::size_t skipped = 0;
  std::vector<Eigen::Vector3f> centres;
  if (config_.discretize) centres = endVoxelCentres(points_in_map, resolution, &skipped);
  const std::vector<Eigen::Vector3f>& ends = config_.discretize ? centres : points_in_map;
  const int count = static_cast<int>(ends.size());
  const int threads = std::max(1, std::min(omp_get_max_threads(), count / 256));
  std::vector<VoxelUpdateSet> partial(threads > 1 ? threads - 1 : 0);
#pragma omp parallel num_threads(threads) reduction(+ : skipped)
  {
    const int thread = omp_get_thread_num();
    VoxelUpdateSet* local = thread == 0 ? update : &partial[thread - 1];
    // Chunks of neighbouring rays (image order) keep the sets of different threads apart;
    // handing them out dynamically keeps both threads busy when rays differ in length or a
    // core is taken by another process.
#pragma omp for schedule(dynamic, 512)
    for (int i = 0; i < count; ++i) {
      const Eigen::Vector3d point = ends[i].cast<double>();
      if (!isRepresentable(point, resolution)) {
        ++skipped;
        continue;
      }
      castRay(sensor_origin_in_map, point, config_.max_range, resolution, local);
    }
  }
  for (const VoxelUpdateSet& other : partial) update->merge(other);
  stats.skipped_points = skipped;
  stats.rays = config_.discretize ? ends.size() : stats.points - skipped;
  return stats;
}

void PointCloudIntegrator::apply(const VoxelUpdateSet& update, float hit_log_odds,
                                 float miss_log_odds, VoxelMap* map) {
  const float min_log_odds = map->minLogOdds();
  const float max_log_odds = map->maxLogOdds();
  map->updateBlocks(update.blocks(), [&](const BlockIndex& block_index, VoxelBlock& block) {
    const VoxelUpdateSet::BlockMasks* masks = update.find(block_index);
    for (int w = 0; w < VoxelUpdateSet::kWords; ++w) {
      const std::uint64_t occupied = masks->occupied[w];
      for (std::uint64_t bits = occupied; bits != 0; bits &= bits - 1) {
        block.update(64 * w + __builtin_ctzll(bits), hit_log_odds, min_log_odds, max_log_odds);
      }
      for (std::uint64_t bits = masks->free[w] & ~occupied; bits != 0; bits &= bits - 1) {
        block.update(64 * w + __builtin_ctzll(bits), miss_log_odds, min_log_odds, max_log_odds);
      }
    }
  });
}

IntegrationStats PointCloudIntegrator::integrate(const std::vector<Eigen::Vector3f>& points_in_map,
                                                 const Eigen::Vector3d& sensor_origin_in_map,
                                                 VoxelMap* map) const {
  const auto start = std::chrono::steady_clock::now();
  VoxelUpdateSet update;
  IntegrationStats stats =
      computeUpdate(points_in_map, sensor_origin_in_map, map->resolution(), &update);
  if (stats.rays > 0) {
    map->setFocus(sensor_origin_in_map);
    apply(update, map->model().hitLogOdds(), map->model().missLogOdds(), map);
  }
  stats.free_voxels = update.freeCount();
  stats.occupied_voxels = update.occupiedCount();
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

}  // namespace occupancy_fusion
