#include "occupancy_fusion/integrators/point_cloud_integrator.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <bitset>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "occupancy_fusion/integrators/ray_traversal.h"

namespace occupancy_fusion {

// ---------------------------------------------------------------------------------------------
// VoxelUpdateSet

std::uint32_t VoxelUpdateSet::slotOf(const BlockIndex& block) {
  // Unsigned: the products wrap.
  const auto coordinate = [&block](int axis) { return static_cast<std::uint32_t>(block[axis]); };
  RecentBlock& recent =
      recent_[(coordinate(0) * 73856093u ^ coordinate(1) * 19349663u ^ coordinate(2) * 83492791u) %
              kRecentBlocks];
  if (recent.block == block) return recent.slot;
  const std::uint64_t key = packBlock(block);
  const auto [it, inserted] = slots_.try_emplace(key, static_cast<std::uint32_t>(keys_.size()));
  if (inserted) {
    keys_.push_back(key);
    masks_.emplace_back();
  }
  recent = {block, it->second};
  return it->second;
}

void VoxelUpdateSet::markFreeTowardsEnd(RayTraversal* ray) {
  const int steps = ray->stepsToEnd();
  if (steps == 0) return;
  constexpr int kMask = VoxelBlock::kSide - 1;
  int linear = 0;  // the current voxel's bit in `words`, its block's free mask
  std::uint64_t* words = maskWordsOf(ray->current(), false, &linear);
  const auto set_bit = [&] { words[linear >> 6] |= std::uint64_t{1} << (linear & 63); };
  set_bit();
  // A step along an axis moves the bit by that axis' stride, unless it leaves the block: then
  // the new voxel's local coordinate on that axis is the first one in the step's direction.
  const int strides[3] = {ray->stepOf(0), ray->stepOf(1) * VoxelBlock::kSide,
                          ray->stepOf(2) * VoxelBlock::kSide * VoxelBlock::kSide};
  const int entry_local[3] = {ray->stepOf(0) > 0 ? 0 : kMask, ray->stepOf(1) > 0 ? 0 : kMask,
                              ray->stepOf(2) > 0 ? 0 : kMask};
  ray->walkAxesTowardsEnd(steps - 1, [&](const VoxelIndex& voxel, auto axis) {
    constexpr int a = decltype(axis)::value;
    if ((voxel[a] & kMask) == entry_local[a]) {
      words = maskWordsOf(voxel, false, &linear);  // a new block
    } else {
      linear += strides[a];
    }
    set_bit();
  });
  ray->next();  // onto the end voxel
}

void VoxelUpdateSet::merge(const VoxelUpdateSet& other) {
  slots_.reserve(keys_.size() + other.keys_.size());
  for (std::size_t theirs = 0; theirs < other.keys_.size(); ++theirs) {
    BlockMasks& ours = masks_[slotOf(unpackBlock(other.keys_[theirs]))];
    for (int w = 0; w < kWords; ++w) {
      ours.free[w] |= other.masks_[theirs].free[w];
      ours.occupied[w] |= other.masks_[theirs].occupied[w];
    }
  }
}

void VoxelUpdateSet::clear() {
  slots_.clear();
  keys_.clear();
  masks_.clear();
  forgetRecentBlocks();
}

const VoxelUpdateSet::BlockMasks* VoxelUpdateSet::find(const BlockIndex& block) const {
  const auto it = slots_.find(packBlock(block));
  return it == slots_.end() ? nullptr : &masks_[it->second];
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
  for (const BlockMasks& masks : masks_) {
    for (std::uint64_t word : masks.occupied) count += std::bitset<64>(word).count();
  }
  return count;
}

std::size_t VoxelUpdateSet::freeCount() const {
  std::size_t count = 0;
  for (const BlockMasks& masks : masks_) {
    for (int w = 0; w < kWords; ++w) {
      count += std::bitset<64>(masks.free[w] & ~masks.occupied[w]).count();
    }
  }
  return count;
}

std::vector<BlockIndex> VoxelUpdateSet::blocks() const {
  std::vector<BlockIndex> result;
  result.reserve(keys_.size());
  for (std::uint64_t key : keys_) result.push_back(unpackBlock(key));
  return result;
}

// ---------------------------------------------------------------------------------------------
// PointCloudIntegrator

void PointCloudIntegratorConfig::validate() const {
  if (std::isnan(max_range)) {
    throw std::invalid_argument("PointCloudIntegratorConfig.max_range must not be NaN");
  }
  if (!(passed_miss_probability > 0.0 && passed_miss_probability < 0.5)) {
    throw std::invalid_argument(
        "PointCloudIntegratorConfig.passed_miss_probability must lie in (0, 0.5)");
  }
  if (passed_margin < 0 || passed_margin > 8) {
    throw std::invalid_argument("PointCloudIntegratorConfig.passed_margin must lie in [0, 8]");
  }
}

PointCloudIntegrator::PointCloudIntegrator(const PointCloudIntegratorConfig& config)
    : config_(config) {
  config_.validate();
}

namespace {

// The same range as VoxelMap::isInRange, without needing a map. NaN and infinity fail the
// comparisons.
inline bool isRepresentable(const Eigen::Vector3d& point, double resolution) {
  const double limit = VoxelMap::kMaxCoordinateVoxels * resolution;
  return (std::abs(point.x()) < limit) & (std::abs(point.y()) < limit) &
         (std::abs(point.z()) < limit);
}

// One point of OctoMap's computeUpdate (its no-bounding-box branch).
void castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& point, double max_range,
             double resolution, VoxelUpdateSet* update) {
  const Eigen::Vector3d ray = point - origin;
  const double distance = ray.norm();
  if (max_range < 0.0 || distance <= max_range) {
    RayTraversal walk(origin, point, resolution);
    update->markFreeTowardsEnd(&walk);
    update->markOccupied(voxelIndexOf(point, resolution));
  } else {
    const Eigen::Vector3d clipped_end = origin + ray * (max_range / distance);
    RayTraversal walk(origin, clipped_end, resolution);
    update->markFreeTowardsEnd(&walk);
  }
}

// The end voxels of points [first, last) in the order of each one's first point, marked in
// `seen` (bit masks per block: neighbouring end voxels share blocks, so a mark mostly costs no
// table look-up); points outside the representable range are left out (and counted). A point in
// the voxel of the point before it (most of them: a voxel spans several pixels of a row) is
// known already and needs no mark.
void collectEndVoxels(const std::vector<Eigen::Vector3f>& points, std::size_t first,
                      std::size_t last, double resolution, VoxelUpdateSet* seen,
                      std::vector<VoxelIndex>* voxels, std::size_t* skipped) {
  VoxelIndex previous = VoxelIndex::Constant(std::numeric_limits<int>::min());  // no voxel
  for (std::size_t i = first; i < last; ++i) {
    const Eigen::Vector3d point = points[i].cast<double>();
    if (!isRepresentable(point, resolution)) {
      ++*skipped;
      continue;
    }
    const VoxelIndex voxel = voxelIndexOf(point, resolution);
    if (voxel == previous) continue;
    previous = voxel;
    if (seen->markOccupiedFirst(voxel)) voxels->push_back(voxel);
  }
}

// discretize: the centre of each end voxel once, in the order of the voxel's first point, as
// OcTree's computeDiscreteUpdate builds its discretized cloud. The two halves of the cloud are
// collected on two threads; the second half's voxels that the first has too are then dropped.
std::vector<Eigen::Vector3f> endVoxelCentres(const std::vector<Eigen::Vector3f>& points,
                                             double resolution, std::size_t* skipped) {
  constexpr std::size_t kParallelPoints = 8192;
  const int parts = points.size() >= kParallelPoints && omp_get_max_threads() > 1 ? 2 : 1;
  VoxelUpdateSet seen[2];
  std::vector<VoxelIndex> voxels[2];
  std::size_t skipped_in[2] = {0, 0};
#pragma omp parallel for num_threads(parts) schedule(static, 1) if (parts > 1)
  for (int part = 0; part < parts; ++part) {
    collectEndVoxels(points, points.size() * part / parts, points.size() * (part + 1) / parts,
                     resolution, &seen[part], &voxels[part], &skipped_in[part]);
  }
  *skipped += skipped_in[0] + skipped_in[1];
  std::vector<Eigen::Vector3f> centres;
  centres.reserve(voxels[0].size() + voxels[1].size());
  auto add_centre = [&](const VoxelIndex& voxel) {
    centres.push_back(((voxel.cast<double>().array() + 0.5) * resolution).matrix().cast<float>());
  };
  for (const VoxelIndex& voxel : voxels[0]) add_centre(voxel);
  for (const VoxelIndex& voxel : voxels[1]) {
    if (!seen[0].isOccupied(voxel)) add_centre(voxel);
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

namespace {

// Whether a voxel of the update within `margin` voxels of `voxel` (on each axis) is an end voxel.
bool nearEndVoxel(const VoxelUpdateSet& update, const VoxelIndex& voxel, int margin) {
  for (int dz = -margin; dz <= margin; ++dz) {
    for (int dy = -margin; dy <= margin; ++dy) {
      for (int dx = -margin; dx <= margin; ++dx) {
        if (update.isOccupied(voxel + VoxelIndex(dx, dy, dz))) return true;
      }
    }
  }
  return false;
}

}  // namespace

std::size_t PointCloudIntegrator::apply(const VoxelUpdateSet& update, VoxelMap* map) const {
  const OccupancyModel& model = map->model();
  const float hit = model.hitLogOdds();
  const float miss = model.missLogOdds();
  const float passed_miss = static_cast<float>(
      std::log(config_.passed_miss_probability / (1.0 - config_.passed_miss_probability)));
  const float threshold = model.thresholdLogOdds();
  const float min_log_odds = map->minLogOdds();
  const float max_log_odds = map->maxLogOdds();
  std::atomic<std::size_t> passed{0};
  map->updateBlocks(update.blocks(), [&](const BlockIndex& block_index, VoxelBlock& block) {
    const VoxelUpdateSet::BlockMasks* masks = update.find(block_index);
    std::size_t passed_here = 0;
    for (int w = 0; w < VoxelUpdateSet::kWords; ++w) {
      const std::uint64_t occupied = masks->occupied[w];
      for (std::uint64_t bits = occupied; bits != 0; bits &= bits - 1) {
        block.update(64 * w + __builtin_ctzll(bits), hit, min_log_odds, max_log_odds);
      }
      for (std::uint64_t bits = masks->free[w] & ~occupied; bits != 0; bits &= bits - 1) {
        const int linear = 64 * w + __builtin_ctzll(bits);
        // clear_passed: occupied now, passed by a ray, and no ray ends near it: it has left.
        const bool cleared =
            config_.clear_passed && block.log_odds[linear] > threshold &&
            !nearEndVoxel(update, block_index * VoxelBlock::kSide + VoxelBlock::localIndex(linear),
                          config_.passed_margin);
        passed_here += cleared ? 1 : 0;
        block.update(linear, cleared ? passed_miss : miss, min_log_odds, max_log_odds);
      }
    }
    passed += passed_here;
  });
  return passed;
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
    stats.passed_voxels = apply(update, map);
  }
  stats.free_voxels = update.freeCount();
  stats.occupied_voxels = update.occupiedCount();
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

}  // namespace occupancy_fusion
