#include "occupancy_fusion/map/voxel_map.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>

#include "occupancy_fusion/map/block_store.h"

namespace occupancy_fusion {
namespace {

// Approximate heap cost of one hash-table slot (key, pointer, robin-hood bookkeeping) at the
// table's typical load, used for memory accounting.
constexpr std::size_t kTableSlotBytes = 24;

enum Which { kAnyKnown = 0, kOnlyOccupied = 1, kOnlyFree = 2 };

// Where a sparse block is expanded for an updateBlocks callback: one per thread, so that the
// callbacks, running in parallel, neither share one nor allocate.
VoxelBlock& threadScratchBlock() {
  thread_local VoxelBlock scratch;
  return scratch;
}

}  // namespace

// See VoxelMap, "Block storage", and docs/architecture.md for the choice.
const int VoxelMap::kMaxSparseBricks = BrickLayout::kBrickCount - 1;

void VoxelMapConfig::validate() const {
  if (!(resolution > 0.0) || !std::isfinite(resolution)) {
    throw std::invalid_argument("resolution must be a positive number of metres, got " +
                                std::to_string(resolution));
  }
  model.validate();
  if (!(checkpoint_period >= 0.0) || !std::isfinite(checkpoint_period)) {
    throw std::invalid_argument("checkpoint_period must be >= 0 s (0: no checkpoints), got " +
                                std::to_string(checkpoint_period));
  }
}

VoxelMap::VoxelMap(const VoxelMapConfig& config) : config_(config) {
  config_.validate();
  min_log_odds_ = config_.model.minLogOdds();
  max_log_odds_ = config_.model.maxLogOdds();
  threshold_log_odds_ = config_.model.thresholdLogOdds();
  openStore();
}

void VoxelMap::openStore() {
  const bool checkpoints = config_.checkpoint_period > 0;
  const bool bounded = config_.max_memory_bytes > 0 || config_.layer_max_memory_bytes > 0;
  if (config_.spill_folder.empty() || (!bounded && !checkpoints)) return;
  BlockStoreConfig store;
  store.folder = config_.spill_folder;
  store.resolution = config_.resolution;
  store.max_bytes = config_.spill_max_bytes;
  try {
    store_ = std::make_unique<BlockStore>(store);
    if (checkpoints) {
      resumeFromStore();
    } else {
      store_->clear();  // the map starts empty: blocks of an earlier run would read as this map's
    }
  } catch (const std::exception& error) {
    // Mapping goes on in memory (with the bound's eviction); spillStatus() says why.
    store_.reset();
    blocks_.clear();
    spilled_.clear();
    block_bytes_ = 0;
    spilled_known_voxels_ = 0;
    resumed_blocks_ = 0;
    resumed_stamp_.clear();
    checkpoint_count_ = 0;
    recordStoreFailure(error);
  }
}

void VoxelMap::resumeFromStore() {
  // Blocks spilled after the last checkpoint belong to no consistent map.
  store_->clearSpilled();
  if (const auto last = store_->lastCheckpoint()) {
    checkpoint_count_ = last->count;
    resumed_stamp_ = last->stamp;
  }
  const std::size_t room =
      config_.max_memory_bytes == 0 ? SIZE_MAX : config_.max_memory_bytes / 10 * 9;
  store_->forEach([&](std::uint64_t key, const VoxelBlock& block) {
    ++resumed_blocks_;
    StoredBlock stored = StoredBlock::newDense();
    *stored.dense() = block;  // version 0: its first write logs it
    if (hybrid()) stored.settle(kMaxSparseBricks);
    if (storageBytesLocked() + stored.bytes() > room) {
      spilled_.emplace(key, SpilledBlock{block.known_count, 0});
      spilled_known_voxels_ += static_cast<std::size_t>(block.known_count);
      return;
    }
    block_bytes_ += stored.bytes();
    blocks_.emplace(key, std::move(stored));
  });
}

VoxelMap::~VoxelMap() = default;

VoxelIndex VoxelMap::indexOf(const Eigen::Vector3d& point) const {
  return (point / config_.resolution).array().floor().cast<int>();
}

Eigen::Vector3d VoxelMap::centerOf(const VoxelIndex& index) const {
  return (index.cast<double>().array() + 0.5) * config_.resolution;
}

bool VoxelMap::isInRange(const Eigen::Vector3d& point) const {
  const double limit = kMaxCoordinateVoxels * config_.resolution;
  return point.allFinite() && (point.array().abs() < limit).all();
}

VoxelIndex VoxelMap::voxelIndex(const BlockIndex& block, int linear) {
  return block * VoxelBlock::kSide + VoxelBlock::localIndex(linear);
}

const StoredBlock* VoxelMap::findBlock(const BlockIndex& block) const {
  auto it = blocks_.find(packKey(block));
  return it == blocks_.end() ? nullptr : &it->second;
}

const VoxelBlock* VoxelMap::viewBlock(std::uint64_t key, VoxelBlock* scratch) const {
  auto it = blocks_.find(key);
  if (it != blocks_.end()) return &it->second.view(scratch);
  if (spilled_.find(key) != spilled_.end() && readSpilled(key, scratch)) return scratch;
  return nullptr;
}

bool VoxelMap::readSpilled(std::uint64_t key, VoxelBlock* out) const {
  try {
    if (store_->get(key, out)) return true;
    throw std::runtime_error("block store '" + config_.spill_folder + "': block " +
                             std::to_string(key) + " is missing");
  } catch (const std::exception& error) {
    recordStoreFailure(error);
    return false;
  }
}

void VoxelMap::recordStoreFailure(const std::exception& error) const {
  std::lock_guard<std::mutex> lock(failure_mutex_);
  ++store_failures_;
  last_store_error_ = error.what();
}

void VoxelMap::forgetSpilled(std::uint64_t key) {
  auto it = spilled_.find(key);
  spilled_known_voxels_ -= static_cast<std::size_t>(it->second.known);
  spilled_.erase(it);
}

std::optional<StoredBlock> VoxelMap::takeSpilled(std::uint64_t key) {
  if (spilled_.find(key) == spilled_.end()) return std::nullopt;
  VoxelBlock block;
  const bool read = readSpilled(key, &block);
  ++blocks_read_under_lock_;
  return adoptSpilled(key, read ? &block : nullptr);
}

std::optional<StoredBlock> VoxelMap::adoptSpilled(std::uint64_t key, const VoxelBlock* block) {
  forgetSpilled(key);
  if (block == nullptr) {
    // Lost, as an evicted block is: consumers must forget what they derived from it.
    markRemoved(key);
    ++evicted_blocks_;
    return std::nullopt;
  }
  ++blocks_paged_in_;
  StoredBlock stored = StoredBlock::newDense();
  *stored.dense() = *block;  // version 0: its first write in a call logs it
  if (hybrid()) stored.settle(kMaxSparseBricks);
  return stored;
}

VoxelMap::ReadAhead VoxelMap::readSpilledAhead(const std::vector<BlockIndex>& blocks) const {
  ReadAhead ahead;
  if (store_ == nullptr) return ahead;  // set at construction only: no lock for a map without one
  {
    std::shared_lock<std::shared_mutex> lock(mutex_);
    if (spilled_.empty()) return ahead;
    for (const BlockIndex& block : blocks) {
      const std::uint64_t key = packKey(block);
      auto it = spilled_.find(key);
      if (it == spilled_.end()) continue;
      ahead.keys.push_back(key);
      ahead.spills.push_back(it->second.spill);
    }
  }
  // Without the map's lock: the store outlives the map's use of it, and LMDB's readers run beside
  // its writer (the store's remap lock keeps a growth from coming between). A failure here is not
  // counted: the block is read again under the lock, which counts it.
  const long count = static_cast<long>(ahead.keys.size());
  ahead.blocks.resize(ahead.keys.size());
  ahead.found.assign(ahead.keys.size(), 0);
#pragma omp parallel for schedule(dynamic, 4) if (count > 1)
  for (long i = 0; i < count; ++i) {
    try {
      ahead.found[i] = store_->get(ahead.keys[i], &ahead.blocks[i]);
    } catch (const std::exception&) {
      ahead.found[i] = 0;
    }
  }
  return ahead;
}

void VoxelMap::pageInSpilled(const std::vector<BlockIndex>& blocks, ReadAhead* ahead) {
  if (spilled_.empty()) return;
  // Read ahead and not spilled again since (another writer may have paged one in and spilled it
  // again, or reset the map): adopted as read.
  for (std::size_t i = 0; i < ahead->keys.size(); ++i) {
    auto it = spilled_.find(ahead->keys[i]);
    if (it == spilled_.end() || it->second.spill != ahead->spills[i] || !ahead->found[i]) continue;
    std::optional<StoredBlock> stored = adoptSpilled(ahead->keys[i], &ahead->blocks[i]);
    ++blocks_read_ahead_;
    block_bytes_ += stored->bytes();
    blocks_.emplace(ahead->keys[i], std::move(*stored));
  }
  std::vector<std::uint64_t> keys;
  for (const BlockIndex& block : blocks) {
    const std::uint64_t key = packKey(block);
    if (spilled_.find(key) != spilled_.end()) keys.push_back(key);
  }
  if (keys.size() < 2) return;  // storedForWrite reads a single one
  // The store's reads run in parallel (LMDB read transactions); the table is changed serially.
  const long count = static_cast<long>(keys.size());
  std::vector<VoxelBlock> read(keys.size());
  std::vector<char> found(keys.size());
#pragma omp parallel for schedule(dynamic, 4)
  for (long i = 0; i < count; ++i) found[i] = readSpilled(keys[i], &read[i]);
  blocks_read_under_lock_ += keys.size();
  for (long i = 0; i < count; ++i) {
    std::optional<StoredBlock> stored = adoptSpilled(keys[i], found[i] ? &read[i] : nullptr);
    if (!stored) continue;
    block_bytes_ += stored->bytes();
    blocks_.emplace(keys[i], std::move(*stored));
  }
}

void VoxelMap::pageInSpilledInRange(const BlockIndex& lo, const BlockIndex& hi) {
  std::vector<std::uint64_t> keys;
  for (const auto& entry : spilled_) {
    const BlockIndex block = unpackKey3(entry.first);
    if ((block.array() >= lo.array()).all() && (block.array() <= hi.array()).all()) {
      keys.push_back(entry.first);
    }
  }
  for (std::uint64_t key : keys) {
    std::optional<StoredBlock> stored = takeSpilled(key);
    if (!stored) continue;
    block_bytes_ += stored->bytes();
    blocks_.emplace(key, std::move(*stored));
  }
}

StoredBlock& VoxelMap::storedForWrite(std::uint64_t key) {
  auto it = blocks_.find(key);
  if (it == blocks_.end()) {
    std::optional<StoredBlock> spilled = takeSpilled(key);
    if (watcher_ != nullptr && !rewriting_ && !spilled) {
      watcher_->beforeFirstWrite(unpackKey3(key), nullptr);
    }
    it = blocks_.emplace(key, spilled ? std::move(*spilled) : StoredBlock::newDense()).first;
    block_bytes_ += it->second.bytes();
  }
  // A block written since the watcher was set has been seen; a paged-in one (version 0) is seen
  // again, and the watcher keeps its first sight.
  if (watcher_ != nullptr && !rewriting_ && it->second.version() < watch_since_) {
    VoxelBlock before;
    watcher_->beforeFirstWrite(unpackKey3(key), &it->second.view(&before));
  }
  StoredBlock& result = it.value();
  if (result.version() != version_) {
    result.setVersion(version_);
    markChanged(key);
  }
  return result;
}

VoxelBlock& VoxelMap::blockForWrite(const BlockIndex& block) {
  const std::uint64_t key = packKey(block);
  auto it = blocks_.find(key);
  const bool first_in_call = it == blocks_.end() || it->second.version() != version_;
  StoredBlock& stored = storedForWrite(key);
  if (hybrid() && first_in_call) dense_written_.push_back(key);
  if (!stored.isDense()) {
    block_bytes_ -= stored.bytes();
    stored.makeDense();
    block_bytes_ += stored.bytes();
  }
  // The VoxelBlock is on the heap: the reference survives later insertions into the table.
  return *stored.dense();
}

void VoxelMap::settleWrittenBlocks() {
  for (std::uint64_t key : dense_written_) {
    auto it = blocks_.find(key);
    if (it != blocks_.end()) block_bytes_ += it.value().settle(kMaxSparseBricks);
  }
  dense_written_.clear();
}

void VoxelMap::markChanged(std::uint64_t key) {
  change_log_.recordChange(version_, key);
  if (checkpointing()) unsaved_.insert(key);
}

void VoxelMap::markRemoved(std::uint64_t key) {
  change_log_.recordRemoval(version_, key);
  if (checkpointing()) {
    unsaved_.erase(key);
    removed_since_checkpoint_.insert(key);
  }
}

void VoxelMap::finishWrite() {
  settleWrittenBlocks();
  enforceMemoryBound();
  change_log_.finishWrite();
  ++version_;
}

std::optional<float> VoxelMap::logOdds(const VoxelIndex& index) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  const std::uint64_t key = packKey(blockOf(index));
  float value = VoxelBlock::kUnknown;
  auto it = blocks_.find(key);
  if (it != blocks_.end()) {
    value = it->second.at(linearIndexInBlock(index));
  } else if (spilled_.find(key) != spilled_.end()) {
    VoxelBlock block;
    if (readSpilled(key, &block)) value = block.log_odds[linearIndexInBlock(index)];
  }
  if (!VoxelBlock::isKnown(value)) return std::nullopt;
  return value;
}

Occupancy VoxelMap::occupancy(const VoxelIndex& index) const {
  const std::optional<float> value = logOdds(index);
  return value ? classify(*value) : Occupancy::kUnknown;
}

void VoxelMap::updateVoxel(const VoxelIndex& index, float delta) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  blockForWrite(blockOf(index))
      .update(linearIndexInBlock(index), delta, min_log_odds_, max_log_odds_);
  finishWrite();
}

void VoxelMap::applyUpdates(const std::vector<VoxelUpdate>& updates) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  BlockIndex last_block(0, 0, 0);
  VoxelBlock* block = nullptr;
  for (const VoxelUpdate& update : updates) {
    const BlockIndex block_index = blockOf(update.index);
    if (block == nullptr || block_index != last_block) {
      block = &blockForWrite(block_index);
      last_block = block_index;
    }
    block->update(linearIndexInBlock(update.index), update.delta, min_log_odds_, max_log_odds_);
  }
  finishWrite();
}

void VoxelMap::setLogOdds(const VoxelIndex& index, float log_odds) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  blockForWrite(blockOf(index)).set(linearIndexInBlock(index), log_odds);
  finishWrite();
}

void VoxelMap::updateBlocks(const std::vector<BlockIndex>& blocks,
                            const std::function<void(const BlockIndex&, VoxelBlock&)>& fn) {
  ReadAhead ahead = readSpilledAhead(blocks);
  std::unique_lock<std::shared_mutex> lock(mutex_);
  pageInSpilled(blocks, &ahead);
  // Allocation changes the table, so it happens first and serially; the callbacks then only
  // touch their own block.
  const int count = static_cast<int>(blocks.size());
  std::vector<StoredBlock*> targets(blocks.size());
  const std::size_t size_before = blocks_.size();
  for (int i = 0; i < count; ++i) targets[i] = &storedForWrite(packKey(blocks[i]));
  if (blocks_.size() != size_before) {
    // An insertion moves the table's entries (robin hood hashing): find them again.
    for (int i = 0; i < count; ++i) targets[i] = &blocks_.find(packKey(blocks[i])).value();
  }
  const bool hybrid = this->hybrid();
  long long byte_change = 0;
#pragma omp parallel for schedule(dynamic, 4) reduction(+ : byte_change)
  for (int i = 0; i < count; ++i) {
    StoredBlock& stored = *targets[i];
    if (stored.isDense()) {
      VoxelBlock& block = *stored.dense();
      const int known_before = block.known_count;
      fn(blocks[i], block);
      // A dense block of a hybrid map has more bricks than a sparse one may (it was settled so),
      // and a block loses bricks only with known voxels: look again only then, or when new.
      if (hybrid && (known_before == 0 || block.known_count < known_before)) {
        byte_change += stored.settle(kMaxSparseBricks);
      }
    } else {
      VoxelBlock& scratch = threadScratchBlock();
      stored.copyTo(&scratch);
      fn(blocks[i], scratch);
      byte_change += stored.storeFrom(scratch, kMaxSparseBricks);
    }
  }
  block_bytes_ = static_cast<std::size_t>(static_cast<long long>(block_bytes_) + byte_change);
  finishWrite();
}

std::size_t VoxelMap::clearBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  const VoxelIndex lo = indexOf(min);
  const VoxelIndex hi = indexOf(max);
  const BlockIndex block_lo = blockOf(lo);
  const BlockIndex block_hi = blockOf(hi);
  // Spilled blocks in the box are cleared in memory; the bound spills them again afterwards.
  pageInSpilledInRange(block_lo, block_hi);
  std::size_t changed = 0;
  VoxelBlock scratch;
  for (auto it = blocks_.begin(); it != blocks_.end(); ++it) {
    const std::uint64_t key = it->first;
    const BlockIndex block_index = unpackKey3(key);
    if ((block_index.array() < block_lo.array()).any() ||
        (block_index.array() > block_hi.array()).any()) {
      continue;
    }
    StoredBlock& stored = it.value();
    // A sparse block is cleared in its expanded copy; its bricks stay the same (known voxels
    // stay known), so it is repacked in place.
    if (!stored.isDense()) stored.copyTo(&scratch);
    VoxelBlock& block = stored.isDense() ? *stored.dense() : scratch;
    bool touched = false;
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
      if (!VoxelBlock::isKnown(block.log_odds[linear])) continue;
      const Eigen::Vector3d center = centerOf(voxelIndex(block_index, linear));
      if ((center.array() < min.array()).any() || (center.array() > max.array()).any()) continue;
      if (!touched && watcher_ != nullptr && stored.version() < watch_since_) {
        watcher_->beforeFirstWrite(block_index, &block);
      }
      block.log_odds[linear] = min_log_odds_;
      touched = true;
      ++changed;
    }
    if (!touched) continue;
    if (block.version != version_) {
      block.version = version_;
      markChanged(key);
    }
    if (!stored.isDense()) block_bytes_ += stored.storeFrom(scratch, kMaxSparseBricks);
  }
  finishWrite();
  return changed;
}

void VoxelMap::setWriteWatcher(BlockWriteWatcher* watcher,
                               const std::function<void(const BlockReader&)>& on_switch) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  if (on_switch) {
    on_switch([this](const BlockIndex& block, VoxelBlock* out) {
      VoxelBlock scratch;
      const VoxelBlock* found = viewBlock(packKey(block), &scratch);
      if (found == nullptr) return false;
      *out = *found;
      return true;
    });
  }
  watcher_ = watcher;
  // The next write call stamps its blocks with version_, every earlier one with less.
  watch_since_ = version_;
}

void VoxelMap::rewriteBlocks(const std::vector<BlockIndex>& blocks,
                             const std::function<void(const BlockIndex&, VoxelBlock&)>& fn) {
  ReadAhead ahead = readSpilledAhead(blocks);
  std::unique_lock<std::shared_mutex> lock(mutex_);
  pageInSpilled(blocks, &ahead);
  rewriting_ = true;
  VoxelBlock scratch;
  for (const BlockIndex& block_index : blocks) {
    const std::uint64_t key = packKey(block_index);
    const bool present = blocks_.find(key) != blocks_.end();
    if (!present) {
      scratch = VoxelBlock();
    } else {
      blocks_.find(key)->second.copyTo(&scratch);
    }
    fn(block_index, scratch);
    if (scratch.known_count == 0) {
      if (!present) continue;
      auto it = blocks_.find(key);
      block_bytes_ -= it->second.bytes();
      blocks_.erase(it);
      markRemoved(key);
      continue;
    }
    StoredBlock& stored = storedForWrite(key);
    block_bytes_ += stored.storeFrom(scratch, hybrid() ? kMaxSparseBricks : -1);  // -1: dense
    // Unwatched: the watcher's next sight of this block is its first write by a sensor.
    stored.setVersion(0);
  }
  rewriting_ = false;
  finishWrite();
}

void VoxelMap::reset() {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  blocks_.clear();
  block_bytes_ = 0;
  spilled_.clear();
  spilled_known_voxels_ = 0;
  unsaved_.clear();
  removed_since_checkpoint_.clear();
  if (store_ != nullptr) {
    try {
      store_->clear();
    } catch (const std::exception& error) {
      recordStoreFailure(error);  // what it still holds is no longer indexed, so never read
    }
  }
  // Consumers holding older versions must rebuild from scratch.
  change_log_.clear(version_ + 1);
  ++version_;
}

void VoxelMap::setFocus(const Eigen::Vector3d& sensor_origin) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  focus_ = sensor_origin;
}

void VoxelMap::enforceMemoryBound() {
  // The bound covers the voxel storage; the change log holds about one entry per block.
  if (config_.max_memory_bytes == 0 || storageBytesLocked() <= config_.max_memory_bytes) return;
  const std::vector<std::uint64_t> leaving = farthestBlocksOverTarget();
  // With checkpoints, a block unchanged since the last one is in the store already.
  std::vector<std::uint64_t> writing;
  for (std::uint64_t key : leaving) {
    if (!checkpointing() || unsaved_.count(key) != 0) writing.push_back(key);
  }
  const bool spilled = store_ != nullptr && (writing.empty() || spillToStore(writing));
  if (spilled) ++spills_;
  if (spilled && checkpointing()) {
    for (std::uint64_t key : writing) unsaved_.erase(key);  // in the store's spill table now
  }
  for (std::uint64_t key : leaving) {
    auto it = blocks_.find(key);
    if (spilled) {
      const int known = it->second.knownCount();
      spilled_.emplace(key, SpilledBlock{known, spills_});
      spilled_known_voxels_ += static_cast<std::size_t>(known);
    } else {
      markRemoved(key);
      ++evicted_blocks_;
    }
    block_bytes_ -= it->second.bytes();
    blocks_.erase(it);
  }
  if (spilled) blocks_spilled_ += writing.size();
}

void VoxelMap::forEachResumedLayerRecord(
    const std::function<void(std::uint64_t, const unsigned char*, std::size_t)>& fn) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  if (!checkpointing() || resumed_stamp_.empty()) return;
  store_->forEachLayerRecord(fn);
}

bool VoxelMap::hasStore() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return store_ != nullptr;
}

bool VoxelMap::spillLayerRecords(const std::vector<BlockStore::LayerRecord>& records) {
  std::unique_lock<std::shared_mutex> lock(mutex_);  // a store write runs alone
  if (store_ == nullptr) return false;
  try {
    store_->putLayer(records);
    return true;
  } catch (const std::exception& error) {
    recordStoreFailure(error);
    return false;
  }
}

bool VoxelMap::readLayerRecord(std::uint64_t key, std::vector<unsigned char>* bytes) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  if (store_ == nullptr) return false;
  try {
    if (store_->getLayer(key, bytes)) return true;
    throw std::runtime_error("block store '" + config_.spill_folder + "': layer record " +
                             std::to_string(key) + " is missing");
  } catch (const std::exception& error) {
    recordStoreFailure(error);
    return false;
  }
}

CheckpointResult VoxelMap::checkpoint(const std::string& stamp,
                                      const BlockStore::LayerRecords* layer) {
  CheckpointResult result;
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  {
    std::unique_lock<std::shared_mutex> lock(mutex_);
    if (!checkpointing()) return result;
    // In key order: LMDB writes sorted keys fastest.
    std::vector<std::uint64_t> keys(unsaved_.begin(), unsaved_.end());
    std::sort(keys.begin(), keys.end());
    const std::vector<std::uint64_t> removed(removed_since_checkpoint_.begin(),
                                             removed_since_checkpoint_.end());
    VoxelBlock scratch;
    try {
      store_->checkpoint(
          keys,
          [&](std::size_t i) -> const VoxelBlock& {
            return blocks_.find(keys[i])->second.view(&scratch);
          },
          removed, {checkpoint_count_ + 1, stamp}, layer);
    } catch (const std::exception& error) {
      recordStoreFailure(error);  // the blocks stay unsaved: the next checkpoint tries again
      return result;
    }
    ++checkpoint_count_;
    ++checkpoints_written_;
    last_checkpoint_stamp_ = stamp;
    unsaved_.clear();
    removed_since_checkpoint_.clear();
    result.written = true;
    result.blocks_written = keys.size();
    result.blocks_removed = removed.size();
    result.layer_records = layer != nullptr ? layer->records.size() : 0;
  }
  const auto locked = Clock::now();
  result.locked_seconds = std::chrono::duration<double>(locked - start).count();
  try {
    store_->sync();
  } catch (const std::exception& error) {
    recordStoreFailure(error);
  }
  result.sync_seconds = std::chrono::duration<double>(Clock::now() - locked).count();
  return result;
}

std::vector<std::uint64_t> VoxelMap::farthestBlocksOverTarget() const {
  const Eigen::Vector3d focus_in_blocks = focus_ / (config_.resolution * VoxelBlock::kSide);
  std::vector<std::pair<double, std::uint64_t>> by_distance;
  by_distance.reserve(blocks_.size());
  for (const auto& entry : blocks_) {
    const Eigen::Vector3d center = unpackKey3(entry.first).cast<double>().array() + 0.5;
    by_distance.emplace_back((center - focus_in_blocks).squaredNorm(), entry.first);
  }
  std::sort(by_distance.begin(), by_distance.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  const std::size_t target = config_.max_memory_bytes / 10 * 9;
  std::size_t bytes = storageBytesLocked();
  std::vector<std::uint64_t> leaving;
  for (const auto& entry : by_distance) {
    if (bytes <= target) break;
    bytes -= blocks_.find(entry.second)->second.bytes();
    leaving.push_back(entry.second);
  }
  return leaving;
}

bool VoxelMap::spillToStore(const std::vector<std::uint64_t>& keys) {
  VoxelBlock scratch;
  try {
    store_->put(keys, [&](std::size_t i) -> const VoxelBlock& {
      return blocks_.find(keys[i])->second.view(&scratch);
    });
    return true;
  } catch (const std::exception& error) {
    recordStoreFailure(error);  // the blocks are dropped instead
    return false;
  }
}

void VoxelMap::forEachBlockLocked(const BlockFn& fn) const {
  VoxelBlock scratch;
  for (const auto& [key, stored] : blocks_) fn(unpackKey3(key), stored.view(&scratch));
  forEachSpilledBlock(fn);
}

void VoxelMap::forEachSpilledBlock(const BlockFn& fn) const {
  if (spilled_.empty()) return;
  // An exception of fn is the caller's, not a store failure: it ends the walk and is rethrown.
  std::exception_ptr from_fn;
  try {
    store_->forEach([&](std::uint64_t key, const VoxelBlock& block) {
      if (from_fn || spilled_.find(key) == spilled_.end()) return;  // paged in since
      try {
        fn(unpackKey3(key), block);
      } catch (...) {
        from_fn = std::current_exception();
      }
    });
  } catch (const std::exception& error) {
    recordStoreFailure(error);
  }
  if (from_fn) std::rethrow_exception(from_fn);
}

void VoxelMap::forEachVoxelIf(const VoxelFn& fn, int which) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  forEachBlockLocked([&](const BlockIndex& block_index, const VoxelBlock& block) {
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
      const float value = block.log_odds[linear];
      if (!VoxelBlock::isKnown(value)) continue;
      const bool occupied = value > threshold_log_odds_;
      if ((which == kOnlyOccupied && !occupied) || (which == kOnlyFree && occupied)) continue;
      fn(voxelIndex(block_index, linear), value);
    }
  });
}

void VoxelMap::forEachKnownVoxel(const VoxelFn& fn) const { forEachVoxelIf(fn, kAnyKnown); }
void VoxelMap::forEachOccupiedVoxel(const VoxelFn& fn) const { forEachVoxelIf(fn, kOnlyOccupied); }
void VoxelMap::forEachFreeVoxel(const VoxelFn& fn) const { forEachVoxelIf(fn, kOnlyFree); }

void VoxelMap::forEachKnownVoxelInBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                                      const VoxelFn& fn) const {
  // Voxels whose centres lie in [min, max]: index range rounded inwards from the box.
  const VoxelIndex lo = (min / config_.resolution).array().ceil().cast<int>() - 1;
  const VoxelIndex hi = indexOf(max);
  std::shared_lock<std::shared_mutex> lock(mutex_);
  const BlockIndex block_lo = blockOf(lo);
  const BlockIndex block_hi = blockOf(hi);
  auto visit_block = [&](const BlockIndex& block_index, const VoxelBlock& block) {
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
      const float value = block.log_odds[linear];
      if (!VoxelBlock::isKnown(value)) continue;
      const VoxelIndex index = voxelIndex(block_index, linear);
      const Eigen::Vector3d center = centerOf(index);
      if ((center.array() < min.array()).any() || (center.array() > max.array()).any()) continue;
      fn(index, value);
    }
  };
  const Eigen::Array3i extent = (block_hi - block_lo).array() + 1;
  const double box_blocks = extent.cast<double>().prod();
  if (box_blocks <= static_cast<double>(blocks_.size() + spilled_.size())) {
    // A small box: look its blocks up.
    VoxelBlock scratch;
    for (int z = block_lo.z(); z <= block_hi.z(); ++z)
      for (int y = block_lo.y(); y <= block_hi.y(); ++y)
        for (int x = block_lo.x(); x <= block_hi.x(); ++x) {
          const VoxelBlock* block = viewBlock(packKey(BlockIndex(x, y, z)), &scratch);
          if (block != nullptr) visit_block({x, y, z}, *block);
        }
    return;
  }
  // A box larger than the map: walk the map's blocks instead.
  forEachBlockLocked([&](const BlockIndex& block_index, const VoxelBlock& block) {
    if ((block_index.array() < block_lo.array()).any() ||
        (block_index.array() > block_hi.array()).any()) {
      return;
    }
    visit_block(block_index, block);
  });
}

VoxelCounts VoxelMap::countInBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max) const {
  VoxelCounts counts;
  forEachKnownVoxelInBox(min, max, [&](const VoxelIndex&, float value) {
    if (value > threshold_log_odds_) {
      ++counts.occupied;
    } else {
      ++counts.free;
    }
  });
  // Voxels whose centres are inside the box, per axis: indices i with (i + 0.5) r in range.
  Eigen::Vector3d per_axis;
  for (int axis = 0; axis < 3; ++axis) {
    const double first = std::ceil(min[axis] / config_.resolution - 0.5);
    const double last = std::floor(max[axis] / config_.resolution - 0.5);
    per_axis[axis] = std::max(0.0, last - first + 1.0);
  }
  const double total = per_axis.prod();
  counts.unknown = static_cast<std::size_t>(total) - counts.occupied - counts.free;
  return counts;
}

void VoxelMap::forEachBlock(
    const std::function<void(const BlockIndex&, const VoxelBlock&)>& fn) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  forEachBlockLocked(fn);
}

std::vector<VoxelMap::BlockCopy> VoxelMap::copyBlocks() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  std::vector<BlockCopy> copies;
  copies.reserve(blocks_.size() + spilled_.size());
  for (const auto& [key, stored] : blocks_) {
    if (stored.isDense()) {
      copies.emplace_back(unpackKey3(key), *stored.dense());
    } else {
      copies.emplace_back(unpackKey3(key), VoxelBlock());
      stored.copyTo(&copies.back().second);
    }
  }
  forEachSpilledBlock(
      [&](const BlockIndex& index, const VoxelBlock& block) { copies.emplace_back(index, block); });
  return copies;
}

bool VoxelMap::copyBlock(const BlockIndex& block, VoxelBlock* out) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  const StoredBlock* found = findBlock(block);
  if (found != nullptr) {
    found->copyTo(out);
    return true;
  }
  const std::uint64_t key = packKey(block);
  return spilled_.find(key) != spilled_.end() && readSpilled(key, out);
}

std::vector<VoxelMap::VoxelStates> VoxelMap::voxelStates(
    const std::vector<BlockIndex>& blocks) const {
  std::vector<VoxelStates> states(blocks.size());
  const float lower = minLogOdds();
  const float threshold = config_.model.thresholdLogOdds();
  std::shared_lock<std::shared_mutex> lock(mutex_);
  const int count = static_cast<int>(blocks.size());
#pragma omp parallel for schedule(dynamic, 64) if (count >= 256)
  for (int i = 0; i < count; ++i) {
    const StoredBlock* found = findBlock(blocks[static_cast<std::size_t>(i)]);
    if (found == nullptr) continue;
    VoxelBlock expanded;
    const VoxelBlock* block = found->isDense() ? found->dense() : nullptr;
    if (block == nullptr) {
      found->copyTo(&expanded);
      block = &expanded;
    }
    VoxelStates& state = states[static_cast<std::size_t>(i)];
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
      // Eq. 3's clamping leaves a voxel at exactly the bound; unknown (NaN) is neither.
      const float value = block->log_odds[linear];
      if (value == lower) state.at_lower_bound.set(linear);
      if (value > threshold) state.occupied.set(linear);
    }
  }
  return states;
}

MapChanges VoxelMap::changesSince(std::uint64_t version) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  MapChanges changes;
  changes.version = version_;
  std::vector<std::uint64_t> changed, removed;
  if (!change_log_.collectSince(version, &changed, &removed)) {
    changes.full_rebuild = true;
    return changes;
  }
  for (std::uint64_t key : changed) changes.changed.push_back(unpackKey3(key));
  for (std::uint64_t key : removed) changes.removed.push_back(unpackKey3(key));
  return changes;
}

std::uint64_t VoxelMap::version() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return version_;
}

std::size_t VoxelMap::blockCount() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return blocks_.size() + spilled_.size();
}

std::vector<BlockIndex> VoxelMap::blockIndices() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  std::vector<BlockIndex> indices;
  indices.reserve(blocks_.size() + spilled_.size());
  for (const auto& entry : blocks_) indices.push_back(unpackKey3(entry.first));
  for (const auto& entry : spilled_) indices.push_back(unpackKey3(entry.first));
  return indices;
}

std::size_t VoxelMap::knownVoxelCount() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  std::size_t count = 0;
  for (const auto& entry : blocks_) count += static_cast<std::size_t>(entry.second.knownCount());
  return count + spilled_known_voxels_;
}

std::size_t VoxelMap::storageBytesLocked() const {
  return block_bytes_ + blocks_.bucket_count() * kTableSlotBytes;
}

std::size_t VoxelMap::memoryBytesLocked() const {
  return storageBytesLocked() + change_log_.memoryBytes() +
         spilled_.bucket_count() * kTableSlotBytes;
}

std::size_t VoxelMap::memoryBytes() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return memoryBytesLocked();
}

VoxelMap::StorageStats VoxelMap::storageStats() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  StorageStats stats;
  for (const auto& entry : blocks_) {
    const StoredBlock& stored = entry.second;
    if (stored.isDense()) {
      ++stats.dense_blocks;
    } else {
      ++stats.sparse_blocks;
      stats.sparse_bricks += static_cast<std::size_t>(stored.brickCount());
    }
  }
  stats.block_bytes = block_bytes_;
  stats.table_bytes = blocks_.bucket_count() * kTableSlotBytes;
  stats.change_log_bytes = change_log_.memoryBytes();
  stats.spilled_blocks = spilled_.size();
  stats.spill_index_bytes = spilled_.bucket_count() * kTableSlotBytes;
  return stats;
}

std::size_t VoxelMap::evictedBlockCount() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return evicted_blocks_;
}

SpillStatus VoxelMap::spillStatus() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  SpillStatus status;
  status.enabled = store_ != nullptr;
  if (config_.max_memory_bytes > 0) status.folder = config_.spill_folder;
  status.spilled_blocks = spilled_.size();
  status.blocks_written = blocks_spilled_;
  status.blocks_read_ahead = blocks_read_ahead_;
  status.blocks_read_under_lock = blocks_read_under_lock_;
  status.blocks_paged_in = blocks_paged_in_;
  std::lock_guard<std::mutex> failure_lock(failure_mutex_);
  status.failures = store_failures_;
  status.last_error = last_store_error_;
  status.checkpoints = checkpointing();
  status.resumed_blocks = resumed_blocks_;
  status.resumed_stamp = resumed_stamp_;
  status.checkpoints_written = checkpoints_written_;
  status.unsaved_blocks = unsaved_.size();
  status.last_checkpoint_stamp = last_checkpoint_stamp_;
  return status;
}

}  // namespace occupancy_fusion
