// An on-disk store of voxel blocks in a folder, on LMDB (an embedded, memory-mapped B+tree with
// ACID transactions): where VoxelMap puts the blocks its memory bound evicts, and reads them back
// from (docs/architecture.md, "Spill store").
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <shared_mutex>
#include <string>
#include <vector>

#include "occupancy_fusion/map/voxel_block.h"

struct MDB_env;  // lmdb.h's, kept out of this header
struct MDB_txn;
struct MDB_val;

namespace occupancy_fusion {

struct BlockStoreConfig {
  std::string folder;        // created if missing; LMDB's data.mdb and lock.mdb go into it
  double resolution = 0.05;  // m, the map's: recorded in a new store, required of an old one
  // The store's size limit (LMDB's map size): it starts at initial_bytes and doubles whenever a
  // write needs more, up to max_bytes (0: no limit but the disk's).
  std::size_t initial_bytes = std::size_t{64} << 20;
  std::size_t max_bytes = 0;
};

// Keys are packed block indices (spatial_key.h's packKey), values the blocks' BrickEncoding.
// Two tables of blocks: the checkpoint (the map as it was at the last checkpoint(), written in
// one transaction: all of it or none) and the blocks spilled since (put()), which are newer; the
// store's contents (get, forEach, size) are the checkpoint with the spilled blocks over it.
// Beside the blocks, a metadata table holds the format version, the block side and the map's
// resolution, and the last checkpoint's number and stamp. Every failure throws std::runtime_error
// naming the folder: a folder that cannot be created or written, a store of another resolution,
// block side or format, a damaged store, a write that does not fit in max_bytes, a folder in use by
// another store (in this process or another: the store holds an exclusive flock on in_use.lock in
// its folder while open).
//
// Commits are not flushed to disk one by one (MDB_NOSYNC): a process that dies keeps every
// committed write (they are in the system's page cache), a system crash may lose the newest.
//
// Thread safety: reads (get, forEach, size) may run in parallel with each other, a read may be
// nested in another's callback, but a write (put, clear, checkpoint) must not run alongside any
// other call (growing the store remaps it): the owner's lock keeps them apart, as VoxelMap's does.
// sync() alone may run alongside anything.
class BlockStore {
 public:
  static constexpr int kFormatVersion = 1;

  explicit BlockStore(const BlockStoreConfig& config);
  ~BlockStore();
  BlockStore(const BlockStore&) = delete;
  BlockStore& operator=(const BlockStore&) = delete;

  const std::string& folder() const { return config_.folder; }
  double resolution() const { return config_.resolution; }

  // Writes (or replaces) the blocks keys[i], block_at(i), in one transaction: all or nothing.
  // block_at(i)'s reference need only last until the next call of block_at.
  using BlockSource = std::function<const VoxelBlock&(std::size_t)>;
  void put(const std::vector<std::uint64_t>& keys, const BlockSource& block_at);
  void put(std::uint64_t key, const VoxelBlock& block);
  // The block of `key` (version 0); false when the store does not hold it.
  bool get(std::uint64_t key, VoxelBlock* out) const;
  // Every block, in increasing key order, read in one transaction (a consistent view), decoded
  // one at a time: memory stays one block whatever the store's size.
  void forEach(const std::function<void(std::uint64_t, const VoxelBlock&)>& fn) const;
  // Removes every block (and the checkpoint's number and stamp); the metadata stays.
  void clear();
  // Removes the blocks (and layer records) spilled since the last checkpoint: the store holds the
  // checkpoint alone
  // (what a resumed map starts from; blocks spilled after it belong to no consistent map).
  void clearSpilled();

  // A checkpoint: in one transaction, the spilled blocks join the checkpoint, the blocks keys[i]
  // (block_at(i)) are written over it and the `removed` ones leave it. Cost: the blocks changed
  // since the last one, not the map's size.
  struct CheckpointInfo {
    std::uint64_t count = 0;  // checkpoints written to this store, this one included
    std::string stamp;        // the writer's words, e.g. the time
  };
  // A companion layer's records (the 2D laser layer's tiles: map_checkpoints.h) written with it,
  // in a table of their own: all of them again (replace_all), or those changed since.
  struct LayerRecord {
    std::uint64_t key = 0;
    std::vector<unsigned char> bytes;
  };
  struct LayerRecords {
    std::vector<LayerRecord> records;
    bool replace_all = false;
  };
  void checkpoint(const std::vector<std::uint64_t>& keys, const BlockSource& block_at,
                  const std::vector<std::uint64_t>& removed, const CheckpointInfo& info,
                  const LayerRecords* layer = nullptr);
  // The companion layer's records that leave its memory (GridLayer2D's bound), in one
  // transaction; like spilled blocks, they join the layer's checkpoint at the next checkpoint, and
  // clearSpilled forgets them.
  void putLayer(const std::vector<LayerRecord>& records);
  // A layer record: spilled since the last checkpoint, else the checkpoint's; false when neither.
  bool getLayer(std::uint64_t key, std::vector<unsigned char>* bytes) const;
  // The layer's records of the last checkpoint, in key order.
  void forEachLayerRecord(
      const std::function<void(std::uint64_t, const unsigned char*, std::size_t)>& fn) const;
  std::optional<CheckpointInfo> lastCheckpoint() const;
  // Flushes what was committed to the disk (commits are not flushed one by one, see above). May
  // run alongside reads and writes.
  void sync();

  std::size_t size() const;       // blocks held
  std::size_t sizeLimit() const;  // the current map size, bytes

 private:
  void lockFolder();
  void open();
  void close();
  void checkOrWriteMetadata();
  void grow(std::size_t current);
  void drop(bool checkpoint_too);
  using EntryFn = std::function<void(std::uint64_t, const MDB_val&)>;
  void walk(MDB_txn* txn, const EntryFn& fn) const;  // the merged view, in key order
  int writeCheckpoint(MDB_txn* txn, const std::vector<std::uint64_t>& keys,
                      const BlockSource& block_at, const std::vector<std::uint64_t>& removed,
                      const CheckpointInfo& info, const LayerRecords* layer);
  [[noreturn]] void fail(const std::string& what, int code) const;

  BlockStoreConfig config_;
  int lock_fd_ = -1;  // holds the folder's flock while the store is open
  MDB_env* env_ = nullptr;
  unsigned int blocks_dbi_ = 0;            // spilled since the last checkpoint
  unsigned int checkpoint_dbi_ = 0;        // the last checkpoint
  unsigned int layer_dbi_ = 0;             // the companion layer's records of the last checkpoint
  unsigned int layer_spilled_dbi_ = 0;     // its records spilled since
  mutable std::shared_mutex remap_mutex_;  // growing the map (exclusive) vs sync() and get()
  unsigned int meta_dbi_ = 0;
};

}  // namespace occupancy_fusion
