// Sparse, block-allocated 3D log-odds voxel map with an explicit unknown state.
#pragma once

#include <Eigen/Core>
#include <array>
#include <bitset>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <string>
#include <utility>
#include <vector>

#include "occupancy_fusion/map/block_change_log.h"
#include "occupancy_fusion/map/block_store.h"
#include "occupancy_fusion/map/occupancy_model.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/stored_block.h"
#include "occupancy_fusion/map/voxel_block.h"

namespace occupancy_fusion {

using VoxelIndex = Eigen::Vector3i;  // floor(p / resolution), per axis
using BlockIndex = Eigen::Vector3i;  // floor(voxel index / VoxelBlock::kSide), per axis

// How blocks are stored (see VoxelMap, "Block storage"; parameter block_storage). Either way the
// map's contents, as every read and write function sees them, are the same bit for bit.
enum class BlockStorage {
  kDense,   // every block a VoxelBlock
  kHybrid,  // a block with few non-empty bricks keeps only those: less memory, a little more CPU
};

struct VoxelMapConfig {
  double resolution = 0.05;          // m, edge of a voxel
  OccupancyModel model;              // hit/miss/clamping
  std::size_t max_memory_bytes = 0;  // 0: unbounded. See VoxelMap's memory bound.
  // With max_memory_bytes: the folder of the store the evicted blocks go to and come back from
  // (VoxelMap's "Spill store"); empty: evicted blocks are dropped.
  std::string spill_folder;
  std::size_t spill_max_bytes = 0;  // the store's size limit on disk; 0: the disk's
  // s. Above 0, with a spill_folder, with or without a memory bound: the store also keeps the
  // map's checkpoints and is not emptied at construction: the map resumes from its last
  // checkpoint (VoxelMap's "Checkpoints"). Whoever owns the map calls checkpoint() this often.
  double checkpoint_period = 0.0;
  BlockStorage block_storage = BlockStorage::kDense;
  // The 2D laser layer beside the map (map_checkpoints.h): its own bound on tiles in memory,
  // beyond which tiles go to this map's store (a spill_folder is needed). 0: unbounded.
  std::size_t layer_max_memory_bytes = 0;

  void validate() const;  // throws std::invalid_argument naming the bad field
};

struct VoxelUpdate {
  VoxelIndex index;
  float delta;  // log-odds increment
};

// Blocks written or removed after a given map version, for consumers that keep derived data
// (published markers, the projected grid) up to date at a cost proportional to the change.
struct MapChanges {
  std::uint64_t version = 0;        // pass this to the next changesSince()
  bool full_rebuild = false;        // the log no longer reaches back: rebuild from scratch
  std::vector<BlockIndex> changed;  // written since, and still allocated
  std::vector<BlockIndex> removed;  // cleared, evicted or reset since
};

// The spill store's state, for diagnostics.
struct SpillStatus {
  bool enabled = false;  // a memory bound and a spill folder whose store opened
  std::string folder;    // the spill folder under a memory bound, whether or not it opened
  std::size_t spilled_blocks = 0;   // blocks held by the store alone now
  std::size_t blocks_written = 0;   // blocks written to the store, in all
  std::size_t blocks_paged_in = 0;  // blocks brought back into memory by writes, in all
  // Of those, read from the store while the write waited for nothing (before its exclusive lock:
  // readers and other writers went on) and while it held the exclusive lock (a block spilled
  // again by another writer in between, or a single block written through updateVoxel).
  std::size_t blocks_read_ahead = 0;
  std::size_t blocks_read_under_lock = 0;
  std::size_t failures = 0;  // store operations that failed (blocks dropped or unreadable)
  std::string last_error;    // the newest failure, naming the store's folder
  // Checkpoints (VoxelMapConfig::checkpoint_period with a store that opened).
  bool checkpoints = false;
  std::size_t resumed_blocks = 0;       // read from the store's last checkpoint at construction
  std::string resumed_stamp;            // that checkpoint's stamp ("" if none)
  std::size_t checkpoints_written = 0;  // by this map
  std::size_t unsaved_blocks = 0;       // in memory, written since the last checkpoint
  std::string last_checkpoint_stamp;
};

// What one VoxelMap::checkpoint() did.
struct CheckpointResult {
  bool written = false;            // false: no checkpoints, or the store failed (see spillStatus)
  std::size_t blocks_written = 0;  // blocks in memory written since the previous checkpoint
  std::size_t blocks_removed = 0;  // blocks the map lost since (left the checkpoint)
  std::size_t layer_records = 0;   // a companion layer's records written with it
  double locked_seconds = 0.0;     // writers waited this long (the transaction)
  double sync_seconds = 0.0;       // then the flush to disk, writers not waiting
};

using BlockWriteWatcher = CellsWriteWatcher<BlockIndex, VoxelBlock>;

struct VoxelCounts {
  std::size_t occupied = 0;
  std::size_t free = 0;
  std::size_t unknown = 0;
};

// Thread safety: every public member function may be called from any thread. Reads take a
// shared lock and writes an exclusive one, held for the whole call, so one call (a frame's
// applyUpdates or updateBlocks) is atomic for readers. Several integrators may write at once:
// their calls take turns on the lock. updateBlocks runs its callback on several threads at once
// (OpenMP), each on a different block, while the caller's exclusive lock is held. Callbacks of
// forEach* run under the shared lock: they must not call back into the map's write functions.
//
// Block storage: a block is held dense (a VoxelBlock, 2 KB) or, with BlockStorage::kHybrid,
// sparse: only its 2^3-voxel bricks that hold a known voxel (stored_block.h). Every interface
// that hands out a VoxelBlock (updateBlocks, forEachBlock, copyBlock(s)) gives a dense one, a
// sparse block expanded for the call. After each write call, a block it wrote is stored sparse
// when at least one of its 64 bricks is empty (kMaxSparseBricks), else dense: a thin surface
// (stereo) fills a few bricks of each block, while a block of free space (depth, point clouds)
// stays dense and is looked at again only when it loses known voxels.
//
// Memory bound: after each write call, if the voxel storage (blocks and hash table) exceeds
// max_memory_bytes, the blocks
// farthest from the focus (the last sensor origin given to setFocus) are dropped, their voxels
// becoming unknown, until the map uses at most 90 % of the bound. Dropped blocks are counted in
// evictedBlockCount() and reported as removed by changesSince().
//
// Spill store: with a memory bound and a spill_folder, the blocks the bound evicts are written to
// a BlockStore in that folder instead (in one transaction per eviction) and leave memory, but not
// the map: every read (point queries, forEach*, copyBlock(s), counts) gives what a map without
// the bound would give, reading a spilled block from the store (forEach* stream them, one block
// in memory at a time); a write of a spilled block (updateBlocks, applyUpdates, ...) first brings
// it back into memory. Reads leave spilled blocks where they are, so they never grow the memory
// and run under the shared lock as before (the store allows parallel readers). Spilling is
// not a change: changesSince() does not report spilled blocks. A store operation that fails
// while mapping (a full disk, spill_max_bytes reached, a damaged entry) never throws out of a
// write: a block that cannot be spilled is dropped as without a store, one that cannot be read
// back reads as unknown (and is dropped when written), and spillStatus() counts the failure.
// The store is emptied when the map is constructed (unless it resumes, below) and by reset().
//
// Checkpoints: with VoxelMapConfig::checkpoints, checkpoint() writes the blocks written since the
// previous one to the store in one transaction (all or nothing), and flushes it to disk: the
// store then holds the map as it was at that call. Evicted blocks already in the checkpoint
// unchanged are not written again. A map constructed on the folder resumes from the last
// checkpoint: the blocks written after it (also those spilled) are discarded, so the map equals
// the checkpoint exactly. Resumed blocks come into memory up to 90 % of the memory bound; the
// rest stay in the store (spilled).
class VoxelMap {
 public:
  // Validates config; with a memory bound and a spill folder, opens (or creates) the store. When
  // it cannot (unwritable, damaged, in use, written with another resolution) the map works
  // without it, evicting as without a folder, and spillStatus() gives the reason naming the
  // folder (enabled false, one failure).
  explicit VoxelMap(const VoxelMapConfig& config);
  ~VoxelMap();

  // With BlockStorage::kHybrid, a written block is stored sparse while it has at most this many
  // non-empty bricks (of BrickLayout::kBrickCount).
  static const int kMaxSparseBricks;

  const VoxelMapConfig& config() const { return config_; }
  double resolution() const { return config_.resolution; }
  const OccupancyModel& model() const { return config_.model; }
  float minLogOdds() const { return min_log_odds_; }
  float maxLogOdds() const { return max_log_odds_; }
  float thresholdLogOdds() const { return threshold_log_odds_; }
  Occupancy classify(float log_odds) const {
    return log_odds > threshold_log_odds_ ? Occupancy::kOccupied : Occupancy::kFree;
  }

  // Coordinates. Indices are valid for |coordinate| < kMaxCoordinateVoxels * resolution.
  static constexpr int kMaxBlockCoordinate = kMaxKeyCoordinate3D;  // blocks are keyed by packKey
  static constexpr int kMaxCoordinateVoxels = kMaxBlockCoordinate * VoxelBlock::kSide;
  VoxelIndex indexOf(const Eigen::Vector3d& point) const;
  Eigen::Vector3d centerOf(const VoxelIndex& index) const;
  bool isInRange(const Eigen::Vector3d& point) const;  // finite and representable
  // Inline: the integrators call these for every voxel they read, from another library.
  static BlockIndex blockOf(const VoxelIndex& index) {
    // Arithmetic shift floors negative indices too.
    return {index.x() >> VoxelBlock::kSideLog2, index.y() >> VoxelBlock::kSideLog2,
            index.z() >> VoxelBlock::kSideLog2};
  }
  static int linearIndexInBlock(const VoxelIndex& index) {
    constexpr int mask = VoxelBlock::kSide - 1;
    return VoxelBlock::linearIndex(index.x() & mask, index.y() & mask, index.z() & mask);
  }
  static VoxelIndex voxelIndex(const BlockIndex& block, int linear);

  // Point queries.
  std::optional<float> logOdds(const VoxelIndex& index) const;  // nullopt: unknown
  Occupancy occupancy(const VoxelIndex& index) const;
  Occupancy occupancyAt(const Eigen::Vector3d& point) const { return occupancy(indexOf(point)); }

  // Writes.
  void updateVoxel(const VoxelIndex& index, float delta);
  void applyUpdates(const std::vector<VoxelUpdate>& updates);
  void setLogOdds(const VoxelIndex& index, float log_odds);  // unclamped, for import
  // Allocates the given blocks, then calls fn(block_index, block) for each, in parallel.
  void updateBlocks(const std::vector<BlockIndex>& blocks,
                    const std::function<void(const BlockIndex&, VoxelBlock&)>& fn);
  // octomap_server's clear_bbx: every known voxel whose centre lies in [min, max] becomes free
  // at the lower clamping bound. Returns the number of voxels changed.
  std::size_t clearBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max);
  void reset();
  void setFocus(const Eigen::Vector3d& sensor_origin);
  // Replaces the watcher of every later write call (nullptr: none). `on_switch`, if given, runs
  // first, under the same exclusive lock, with a reader of the blocks as they are (false: no such
  // block), so that the outgoing watcher can read what its writes left with no write between.
  using BlockReader = std::function<bool(const BlockIndex&, VoxelBlock*)>;
  void setWriteWatcher(BlockWriteWatcher* watcher,
                       const std::function<void(const BlockReader&)>& on_switch = {});
  // Rewrites blocks whole: fn(block_index, block) gets each block's contents (all unknown when
  // the map has none) and leaves what the block is to hold; a block left without known voxels is
  // removed. Serial, under one exclusive lock, logged as changes, and unseen by the write
  // watcher: what a submap's move does to the fused map (mapping/submap_fusion.h).
  void rewriteBlocks(const std::vector<BlockIndex>& blocks,
                     const std::function<void(const BlockIndex&, VoxelBlock&)>& fn);
  // See "Checkpoints". stamp: recorded with it (e.g. the time). Writers wait for the transaction
  // (cost: the blocks written since the previous checkpoint), not for the flush to disk.
  // `layer`: a companion layer's records, written in the same transaction (map_checkpoints.h).
  CheckpointResult checkpoint(const std::string& stamp,
                              const BlockStore::LayerRecords* layer = nullptr);
  // A companion layer's records that leave its memory (GridLayer2D's bound: map_checkpoints.h),
  // into this map's store beside the blocks, and read back. false: no store, or it failed (counted
  // in spillStatus()). hasStore(): a spill folder whose store opened.
  bool hasStore() const;
  bool spillLayerRecords(const std::vector<BlockStore::LayerRecord>& records);
  bool readLayerRecord(std::uint64_t key, std::vector<unsigned char>* bytes) const;
  // The companion layer's records of the checkpoint this map resumed (nothing without one).
  void forEachResumedLayerRecord(
      const std::function<void(std::uint64_t, const unsigned char*, std::size_t)>& fn) const;

  // Iteration (under the shared lock). fn(voxel index, log-odds).
  using VoxelFn = std::function<void(const VoxelIndex&, float)>;
  void forEachKnownVoxel(const VoxelFn& fn) const;
  void forEachOccupiedVoxel(const VoxelFn& fn) const;
  void forEachFreeVoxel(const VoxelFn& fn) const;
  // Known voxels whose centres lie in [min, max].
  void forEachKnownVoxelInBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                              const VoxelFn& fn) const;
  VoxelCounts countInBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max) const;
  void forEachBlock(const std::function<void(const BlockIndex&, const VoxelBlock&)>& fn) const;
  // Copies one block; false if it is not allocated.
  bool copyBlock(const BlockIndex& block, VoxelBlock* out) const;
  // Per block (under one shared lock): the voxels held exactly at the lower clamping bound (a
  // clamped-free voxel, which a negative update leaves as it is) and those classified occupied.
  // Blocks not held in memory (absent or spilled) get empty masks.
  using VoxelMask = std::bitset<VoxelBlock::kVolume>;
  struct VoxelStates {
    VoxelMask at_lower_bound;
    VoxelMask occupied;
  };
  std::vector<VoxelStates> voxelStates(const std::vector<BlockIndex>& blocks) const;
  // Every block, copied under one shared lock: a consistent snapshot for long work (converting
  // the whole map to a file or a message) that must not keep writers waiting while it runs.
  using BlockCopy = std::pair<BlockIndex, VoxelBlock>;
  std::vector<BlockCopy> copyBlocks() const;

  // Change log for incremental consumers. Start with version 0 (a full rebuild).
  MapChanges changesSince(std::uint64_t version) const;
  std::uint64_t version() const;

  // Accounting.
  std::size_t blockCount() const;                // in memory and spilled
  std::vector<BlockIndex> blockIndices() const;  // every block, in memory and spilled
  std::size_t knownVoxelCount() const;
  std::size_t memoryBytes() const;  // blocks, hash table, change log and spilled blocks' index
  std::size_t evictedBlockCount() const;  // blocks dropped (their voxels unknown again)
  SpillStatus spillStatus() const;
  struct StorageStats {
    std::size_t dense_blocks = 0;
    std::size_t sparse_blocks = 0;
    std::size_t sparse_bricks = 0;  // non-empty bricks held by the sparse blocks
    std::size_t block_bytes = 0;    // heap bytes of all blocks (allocated, not only used)
    std::size_t table_bytes = 0;    // the block hash table
    std::size_t change_log_bytes = 0;
    std::size_t spilled_blocks = 0;     // held by the spill store alone
    std::size_t spill_index_bytes = 0;  // the in-memory index of the spilled blocks
  };
  StorageStats storageStats() const;

 private:
  using BlockTable = SpatialKeyMap<StoredBlock>;  // keyed by packKey(block)

  using BlockFn = std::function<void(const BlockIndex&, const VoxelBlock&)>;

  // Allocates (dense, or paged in from the spill store), stamps the version and logs the change;
  // caller holds the unique lock.
  StoredBlock& storedForWrite(std::uint64_t key);
  // The same, stored dense until finishWrite() settles it (for per-voxel writes).
  VoxelBlock& blockForWrite(const BlockIndex& block);
  const StoredBlock* findBlock(const BlockIndex& block) const;
  // A block's contents wherever it is (memory or spill store); nullptr if the map has none.
  const VoxelBlock* viewBlock(std::uint64_t key, VoxelBlock* scratch) const;
  // Every block, those in memory first, then the spilled ones streamed from the store.
  void forEachBlockLocked(const BlockFn& fn) const;
  void forEachSpilledBlock(const BlockFn& fn) const;
  bool readSpilled(std::uint64_t key, VoxelBlock* out) const;
  // A spilled block taken out of the store's index for the caller to insert into blocks_;
  // nullopt when the block is not spilled or cannot be read (then it is dropped).
  std::optional<StoredBlock> takeSpilled(std::uint64_t key);
  // A spilled block read from the store (nullptr: it could not be read, and is dropped) taken out
  // of the spilled index, for the caller to insert into blocks_.
  std::optional<StoredBlock> adoptSpilled(std::uint64_t key, const VoxelBlock* block);
  // The spilled ones of a write call's blocks, read from the store in parallel and put in memory.
  // A write call's spilled blocks read from the store before it takes the exclusive lock, each
  // with the spill it was read from (SpilledBlock::spill): a block spilled again in between is
  // read once more under the lock.
  struct ReadAhead {
    std::vector<std::uint64_t> keys;
    std::vector<std::uint64_t> spills;
    std::vector<VoxelBlock> blocks;
    std::vector<char> found;
  };
  ReadAhead readSpilledAhead(const std::vector<BlockIndex>& blocks) const;
  void pageInSpilled(const std::vector<BlockIndex>& blocks, ReadAhead* ahead);
  void forgetSpilled(std::uint64_t key);
  void pageInSpilledInRange(const BlockIndex& lo, const BlockIndex& hi);
  std::vector<std::uint64_t> farthestBlocksOverTarget() const;
  bool spillToStore(const std::vector<std::uint64_t>& keys);
  void openStore();
  void resumeFromStore();
  bool checkpointing() const { return store_ != nullptr && config_.checkpoint_period > 0; }
  void recordStoreFailure(const std::exception& error) const;
  bool hybrid() const { return config_.block_storage == BlockStorage::kHybrid; }
  void settleWrittenBlocks();
  void markChanged(std::uint64_t key);
  void markRemoved(std::uint64_t key);
  void finishWrite();  // bumps the version, enforces the memory bound
  void enforceMemoryBound();
  std::size_t memoryBytesLocked() const;
  std::size_t storageBytesLocked() const;  // blocks and hash table: what the bound limits
  void forEachVoxelIf(const VoxelFn& fn, int which) const;

  VoxelMapConfig config_;
  BlockWriteWatcher* watcher_ = nullptr;
  std::uint64_t watch_since_ = 0;  // the version the watcher was set at
  bool rewriting_ = false;         // rewriteBlocks: its writes are not the watcher's
  float min_log_odds_;
  float max_log_odds_;
  float threshold_log_odds_;

  mutable std::shared_mutex mutex_;
  BlockTable blocks_;
  Eigen::Vector3d focus_ = Eigen::Vector3d::Zero();
  std::uint64_t version_ = 1;
  std::size_t evicted_blocks_ = 0;
  BlockChangeLog change_log_;
  std::size_t block_bytes_ = 0;               // sum of the blocks' bytes()
  std::vector<std::uint64_t> dense_written_;  // blockForWrite's blocks, settled by finishWrite

  std::unique_ptr<BlockStore> store_;  // the spill store, if configured
  // Blocks held by the store alone (never also in blocks_), with their known voxel counts; the
  // store may hold older copies of blocks since paged in, which this index leaves out.
  struct SpilledBlock {
    int known = 0;            // its known voxels
    std::uint64_t spill = 0;  // which spill wrote it (spills_ then); 0: resumed from a checkpoint
  };
  SpatialKeyMap<SpilledBlock> spilled_;
  std::uint64_t spills_ = 0;  // eviction rounds that spilled, ever (not reset: see ReadAhead)
  std::size_t blocks_read_ahead_ = 0, blocks_read_under_lock_ = 0;
  std::size_t spilled_known_voxels_ = 0;
  std::size_t blocks_spilled_ = 0;
  std::size_t blocks_paged_in_ = 0;
  // Checkpoints: blocks in memory written since the last checkpoint (those spilled since are in
  // the store's spill table), and blocks lost since (evicted without the store, unreadable).
  SpatialKeySet unsaved_;
  SpatialKeySet removed_since_checkpoint_;
  std::size_t resumed_blocks_ = 0;
  std::string resumed_stamp_;
  std::uint64_t checkpoint_count_ = 0;  // the store's, this map's included
  std::size_t checkpoints_written_ = 0;
  std::string last_checkpoint_stamp_;
  // Failures can happen in readers (under the shared lock): counted under a lock of their own.
  mutable std::mutex failure_mutex_;
  mutable std::size_t store_failures_ = 0;
  mutable std::string last_store_error_;
};

}  // namespace occupancy_fusion
