// OctoMap-equivalent point-cloud integration: free space along each ray, a hit at its end point,
// one update per voxel per cloud (OcTree::insertPointCloud with lazy_eval = false, and
// discretize as configured).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

// The voxels one cloud marks free and occupied, kept as two bit masks per 8^3 block: inserting a
// voxel twice is free, a voxel in both sets counts as occupied (OctoMap's rule: occupied wins),
// and applying the set to a VoxelMap works block by block.
class VoxelUpdateSet {
 public:
  static constexpr int kWords = VoxelBlock::kVolume / 64;
  struct BlockMasks {
    std::array<std::uint64_t, kWords> free{};
    std::array<std::uint64_t, kWords> occupied{};
  };

  VoxelUpdateSet() { forgetRecentBlocks(); }
  VoxelUpdateSet(const VoxelUpdateSet&) = default;
  VoxelUpdateSet& operator=(const VoxelUpdateSet&) = default;
  // The source is left empty (its recent blocks would name slots it no longer has).
  VoxelUpdateSet(VoxelUpdateSet&& other) noexcept
      : slots_(std::move(other.slots_)),
        keys_(std::move(other.keys_)),
        masks_(std::move(other.masks_)),
        recent_(other.recent_),
        last_(other.last_) {
    other.clear();
  }
  VoxelUpdateSet& operator=(VoxelUpdateSet&& other) noexcept {
    slots_ = std::move(other.slots_);
    keys_ = std::move(other.keys_);
    masks_ = std::move(other.masks_);
    recent_ = other.recent_;
    last_ = other.last_;
    other.clear();
    return *this;
  }

  void markFree(const VoxelIndex& index) { mark(index, false); }
  void markOccupied(const VoxelIndex& index) { mark(index, true); }
  // markOccupied, and whether the voxel was not marked occupied before (a set of voxels that is
  // cheap where consecutive ones share blocks).
  bool markOccupiedFirst(const VoxelIndex& index) { return mark(index, true); }
  // markFree for each voxel of the ray's walk from current() up to, not including, its end
  // voxel (OctoMap's free space of a hit); the ray is left at the end voxel. The same marks as
  // markFree per voxel, with the block's words found once per block the ray enters.
  void markFreeTowardsEnd(RayTraversal* ray);
  // Union with another set (e.g. one computed on another thread).
  void merge(const VoxelUpdateSet& other);
  void clear();

  bool isOccupied(const VoxelIndex& index) const;
  bool isFree(const VoxelIndex& index) const;  // marked free and not occupied
  std::size_t occupiedCount() const;
  std::size_t freeCount() const;  // free and not occupied
  bool empty() const { return keys_.empty(); }

  std::vector<BlockIndex> blocks() const;
  // nullptr if nothing in that block is marked.
  const BlockMasks* find(const BlockIndex& block) const;
  // fn(const VoxelIndex&) for each occupied / each free-and-not-occupied voxel, in no order.
  template <typename Fn>
  void forEachOccupied(Fn&& fn) const {
    forEachBit(std::forward<Fn>(fn), [](const BlockMasks& m, int w) { return m.occupied[w]; });
  }
  template <typename Fn>
  void forEachFree(Fn&& fn) const {
    forEachBit(std::forward<Fn>(fn),
               [](const BlockMasks& m, int w) { return m.free[w] & ~m.occupied[w]; });
  }

  // The table's block keys (spatial_key.h's 3D encoding).
  static std::uint64_t packBlock(const BlockIndex& block) { return packKey(block); }
  static BlockIndex unpackBlock(std::uint64_t key) { return unpackKey3(key); }

 private:
  // A block's masks by slot: slots stay put when blocks are added, so the recent blocks below
  // can name them.
  struct RecentBlock {
    BlockIndex block;
    std::uint32_t slot;
  };
  static constexpr int kRecentBlocks = 1024;  // direct-mapped by the block's coordinates

  void forgetRecentBlocks() {
    // No block has these coordinates: indices are at most 2^20 voxels from the origin.
    constexpr int kNone = std::numeric_limits<int>::min();
    recent_.fill({BlockIndex(kNone, kNone, kNone), 0});
    last_ = recent_[0];
  }
  std::uint32_t slotOf(const BlockIndex& block);

  // The occupied or free mask words of the voxel's block, and the voxel's bit in them.
  std::uint64_t* maskWordsOf(const VoxelIndex& index, bool occupied, int* linear) {
    // Same block and in-block index as VoxelMap::blockOf / linearIndexInBlock, inlined for the
    // hot loop (arithmetic shift floors negative indices).
    constexpr int kShift = VoxelBlock::kSideLog2;
    constexpr int kMask = VoxelBlock::kSide - 1;
    const BlockIndex block(index.x() >> kShift, index.y() >> kShift, index.z() >> kShift);
    // Rays walk neighbouring voxels, so most marks hit the block of the previous one, and
    // consecutive rays from one origin pass the same blocks: the table is the last resort.
    if (block != last_.block) last_ = {block, slotOf(block)};
    *linear = VoxelBlock::linearIndex(index.x() & kMask, index.y() & kMask, index.z() & kMask);
    BlockMasks& masks = masks_[last_.slot];
    return (occupied ? masks.occupied : masks.free).data();
  }

  // Returns whether the bit was clear before.
  bool mark(const VoxelIndex& index, bool occupied) {
    int linear = 0;
    std::uint64_t& word = maskWordsOf(index, occupied, &linear)[linear >> 6];
    const std::uint64_t bit = std::uint64_t{1} << (linear & 63);
    const bool first = (word & bit) == 0;
    word |= bit;
    return first;
  }

  template <typename Fn, typename WordFn>
  void forEachBit(Fn&& fn, WordFn&& word_of) const {
    for (std::size_t slot = 0; slot < keys_.size(); ++slot) {
      const BlockIndex block = unpackBlock(keys_[slot]);
      for (int w = 0; w < kWords; ++w) {
        for (std::uint64_t bits = word_of(masks_[slot], w); bits != 0; bits &= bits - 1) {
          const int linear = 64 * w + __builtin_ctzll(bits);
          fn(VoxelIndex(block * VoxelBlock::kSide + VoxelBlock::localIndex(linear)));
        }
      }
    }
  }

  SpatialKeyMap<std::uint32_t> slots_;  // block key -> slot
  std::vector<std::uint64_t> keys_;     // per slot
  std::vector<BlockMasks> masks_;       // per slot
  std::array<RecentBlock, kRecentBlocks> recent_;
  RecentBlock last_;  // the block of the last mark
};

struct PointCloudIntegratorConfig {
  // m; points farther from the sensor only clear free space up to this distance and add no hit.
  // Negative: unlimited. octomap_server's sensor_model/max_range.
  double max_range = -1.0;
  // octomap_server's / OcTree::insertPointCloud's discretize = true: the points falling into one
  // voxel share one ray, to that voxel's centre (in the order of each voxel's first point), so a
  // dense cloud costs its end voxels' rays, not its points'. The map equals liboctomap's
  // discretized insertion voxel for voxel; the free space differs from the plain mode's where
  // rays to the points of one voxel pass other voxels than the ray to its centre.
  bool discretize = false;
  // Beyond OctoMap: a voxel that is occupied in the map, that a ray of the cloud passes on its
  // way to a point behind it, and that no ray of the cloud ends within passed_margin voxels of (on
  // each axis), takes a miss of passed_miss_probability instead of the map's miss: what has left
  // the view is cleared in 4 clouds instead of 9, while a surface the cloud still sees (rays end
  // on it, also those that graze it) keeps OctoMap's update. false: OctoMap's update exactly.
  bool clear_passed = false;
  double passed_miss_probability = 0.25;  // in (0, 0.5): log-odds -1.10
  int passed_margin = 1;                  // voxels, >= 0

  void validate() const;  // throws std::invalid_argument naming the bad field
};

struct IntegrationStats {
  std::size_t points = 0;           // points in the cloud
  std::size_t skipped_points = 0;   // non-finite or outside the map's coordinate range
  std::size_t rays = 0;             // rays cast (points - skipped_points; discretize: end voxels)
  std::size_t free_voxels = 0;      // voxels updated as free
  std::size_t occupied_voxels = 0;  // voxels updated as occupied
  std::size_t passed_voxels = 0;    // of the free ones, occupied voxels cleared as passed
  double seconds = 0.0;             // wall time of the call
};

// Integrates point clouds exactly as OctoMap's OcTree::insertPointCloud(cloud, origin, max_range,
// lazy_eval = false, discretize = false): each ray start -> point marks the voxels it crosses
// free, except the voxel holding the point, which is marked occupied; a point beyond max_range
// marks free the voxels up to origin + max_range * direction (that end voxel excluded) and no
// hit. Each voxel then gets one update per cloud: a hit if any ray ended in it, else a miss.
// Rays are cast on omp_get_max_threads() threads. (Beware: OctoMap's insertPointCloud, compiled
// from its headers into an OpenMP program, sets that count to its own, 1 in Debian's build.)
class PointCloudIntegrator {
 public:
  explicit PointCloudIntegrator(const PointCloudIntegratorConfig& config = {});  // validates

  const PointCloudIntegratorConfig& config() const { return config_; }

  // Casts the rays of one cloud (map frame) into `update` (cleared first), without touching a
  // map. Fills every field of the stats except seconds and the voxel counts.
  IntegrationStats computeUpdate(const std::vector<Eigen::Vector3f>& points_in_map,
                                 const Eigen::Vector3d& sensor_origin_in_map, double resolution,
                                 VoxelUpdateSet* update) const;

  // computeUpdate, then one write call into the map (hits and misses from the map's model), and
  // the map's focus moves to the sensor origin. A sensor origin outside the map's range skips the
  // whole cloud.
  IntegrationStats integrate(const std::vector<Eigen::Vector3f>& points_in_map,
                             const Eigen::Vector3d& sensor_origin_in_map, VoxelMap* map) const;

  // Applies an update set in one VoxelMap::updateBlocks call: the map's hit to occupied voxels,
  // its miss to the other marked ones, or with clear_passed the passed miss to those the map
  // holds occupied with no end voxel of the update near; returns how many took that.
  std::size_t apply(const VoxelUpdateSet& update, VoxelMap* map) const;

 private:
  PointCloudIntegratorConfig config_;
};

}  // namespace occupancy_fusion
