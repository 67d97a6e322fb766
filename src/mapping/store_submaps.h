// The submaps of one store of cells (the VoxelMap's blocks, the laser layer's tiles): what each
// submap changed there, where its changes reach at its placement, and the rebuild of the store's
// blocks from them. SubmapFusion keeps one per store and the submaps' ids, stamps and placements;
// this part is the same for both stores, up to StoreTraits (below).
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <istream>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/log_odds_deltas.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/stored_block.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "submap_spill_file.h"

namespace occupancy_fusion {

// What both stores keep of a block's (tile's) changes, and how.
template <class StoreType, class CellsType, int kCount>
struct PackedChangesTraits {
  using Store = StoreType;
  using Cells = CellsType;
  static constexpr int kCellCount = kCount;
  using Stored = PackedLogOddsChanges<kCount>;

  static Stored store(const Store& store, const Cells& before, const Cells& after) {
    return Stored(before, after, store.thresholdLogOdds());
  }
  static const Cells& view(const Stored& stored, Cells* scratch) {
    stored.expandInto(scratch);
    return *scratch;
  }
  static std::size_t bytes(const Stored& stored) { return stored.bytes(); }
};

// The VoxelMap's blocks.
struct VoxelStoreTraits : PackedChangesTraits<VoxelMap, VoxelBlock, VoxelBlock::kVolume> {
  using Index = Eigen::Vector3i;

  static std::uint64_t key(const Index& index) { return packKey(index); }
  static Index unkey(std::uint64_t key) { return unpackKey3(key); }
  static Index containerOf(const Index& cell) { return VoxelMap::blockOf(cell); }
  static int linearOf(const Index& cell) { return VoxelMap::linearIndexInBlock(cell); }
  static Index cellOf(const Index& container, int linear) {
    return VoxelMap::voxelIndex(container, linear);
  }
  // A cell's index as a point of the map frame (m, its corner) and back.
  static Eigen::Vector3d point(const Eigen::Vector3d& cell) { return cell; }
  static Eigen::Vector3d scaled(const Eigen::Vector3d& point) { return point; }
  static Index floorIndex(const Eigen::Vector3d& scaled) {
    return scaled.array().floor().cast<int>();
  }
  static int side() { return VoxelBlock::kSide; }

  static void setWriteWatcher(Store* store, CellsWriteWatcher<Index, Cells>* watcher,
                              const std::function<void(const VoxelMap::BlockReader&)>& on_switch) {
    store->setWriteWatcher(watcher, on_switch);
  }
  static void rewrite(Store* store, const std::vector<Index>& blocks,
                      const std::function<void(const Index&, Cells&)>& fn) {
    store->rewriteBlocks(blocks, fn);
  }
  static std::vector<std::pair<Index, Cells>> copyAll(const Store& store) {
    return store.copyBlocks();
  }
  static std::size_t count(const Store& store) { return store.blockCount(); }
};

// The laser layer's tiles, in the map's x-y plane: a placement's planar part moves them.
struct TileStoreTraits : PackedChangesTraits<GridLayer2D, GridTile, GridTile::kArea> {
  using Index = Eigen::Vector2i;

  static std::uint64_t key(const Index& index) { return packKey(index); }
  static Index unkey(std::uint64_t key) { return unpackKey2(key); }
  static Index containerOf(const Index& cell) { return GridLayer2D::tileOf(cell); }
  static int linearOf(const Index& cell) { return GridLayer2D::linearIndexInTile(cell); }
  static Index cellOf(const Index& container, int linear) {
    return GridLayer2D::cellIndex(container, linear);
  }
  static Eigen::Vector3d point(const Eigen::Vector2d& cell) { return {cell.x(), cell.y(), 0.0}; }
  static Eigen::Vector2d scaled(const Eigen::Vector3d& point) { return point.head<2>(); }
  static Index floorIndex(const Eigen::Vector3d& scaled) {
    return scaled.head<2>().array().floor().cast<int>();
  }
  static int side() { return GridTile::kSide; }

  static void setWriteWatcher(
      Store* store, CellsWriteWatcher<Index, Cells>* watcher,
      const std::function<void(const GridLayer2D::TileReader&)>& on_switch) {
    store->setWriteWatcher(watcher, on_switch);
  }
  static void rewrite(Store* store, const std::vector<Index>& tiles,
                      const std::function<void(const Index&, Cells&)>& fn) {
    store->rewriteTiles(tiles, fn);
  }
  static std::vector<std::pair<Index, Cells>> copyAll(const Store& store) {
    std::vector<std::pair<Index, Cells>> tiles;
    store.forEachTile([&](const Index& index, const Cells& tile) {
      if (tile.known_count > 0) tiles.emplace_back(index, tile);
    });
    return tiles;
  }
  static std::size_t count(const Store& store) { return store.knownCellCount(); }
};

// Where a submap was written and is shown (T_map_odom each).
struct SubmapPlacement {
  Eigen::Isometry3d written = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d placed = Eigen::Isometry3d::Identity();
  bool atWrittenPlace() const { return placed.matrix() == written.matrix(); }
};

template <class Traits>
class StoreSubmaps {
 public:
  using Store = typename Traits::Store;
  using Cells = typename Traits::Cells;
  using Index = typename Traits::Index;
  using Vector = Eigen::Matrix<double, Index::RowsAtCompileTime, 1>;
  static constexpr int kDimensions = Index::RowsAtCompileTime;

  explicit StoreSubmaps(Store* store)
      : store_(store), active_(std::make_unique<ActiveWrites>(store->resolution())) {}
  ~StoreSubmaps() { Traits::setWriteWatcher(store_, nullptr, {}); }

  // What the store holds now as the next submap's changes (the map's contents before submaps).
  void adoptExistingContents() {
    Record record;
    for (const auto& entry : Traits::copyAll(*store_)) {
      record.add(entry.first, Traits::store(*store_, Cells(), entry.second), cellSide());
    }
    records_.push_back(std::move(record));
  }
  void startWatching() { Traits::setWriteWatcher(store_, active_.get(), {}); }

  // Closes the active submap into the next record and starts the next one, under the store's
  // lock, so that no write comes between.
  void closeActive() {
    Record record;
    auto next = std::make_unique<ActiveWrites>(cellSide());
    Traits::setWriteWatcher(store_, next.get(), [&](const auto& read) {
      Cells after;
      for (const auto& entry : active_->before) {
        if (!read(Traits::unkey(entry.first), &after)) after = Cells();
        typename Traits::Stored stored = Traits::store(*store_, before(entry.second), after);
        if (stored.changed() == 0) continue;
        record.add(Traits::unkey(entry.first), std::move(stored), cellSide());
      }
    });
    active_ = std::move(next);
    records_.push_back(std::move(record));
  }

  // The map-frame box of the active submap's blocks so far, and of a closed one's (written).
  Eigen::AlignedBox3d activeBounds() const {
    std::lock_guard<std::mutex> lock(active_->info_mutex);
    return active_->bounds;
  }
  std::size_t activeBlocks() const {
    std::lock_guard<std::mutex> lock(active_->info_mutex);
    return active_->count;
  }
  // Memory of the active submap's record: the blocks' contents kept and a table slot each.
  std::size_t activeBytes() const {
    std::lock_guard<std::mutex> lock(active_->info_mutex);
    return active_->kept * sizeof(Cells) + active_->count * kTableSlotBytes;
  }
  bool holdsContents() const { return Traits::count(*store_) > 0; }
  const Eigen::AlignedBox3d& bounds(int id) const { return records_[id].bounds; }
  std::size_t blocks(int id) const { return records_[id].blockCount(); }
  bool spilled(int id) const { return records_[id].spilled; }
  std::size_t bytes(int id) const { return records_[id].bytes; }
  std::size_t records() const { return records_.size(); }

  std::size_t inMemoryBytes() const {
    std::size_t bytes = 0;
    for (const Record& record : records_) bytes += record.spilled ? 0 : record.bytes;
    return bytes;
  }
  // Where the spilled records' blocks lie: what stays in memory of them.
  std::size_t spilledIndexBytes() const {
    std::size_t bytes = 0;
    for (const Record& record : records_) bytes += record.spilled ? record.bytes : 0;
    return bytes;
  }

  // The oldest in-memory records written to `spill` until the records in memory take at most
  // `budget` bytes (the newest stays). Returns the bytes written to it.
  std::size_t spillOldest(std::size_t budget, SubmapSpillFile* spill) {
    spill_ = spill;
    std::size_t in_memory = inMemoryBytes();
    std::size_t written = 0;
    for (std::size_t id = 0; id + 1 < records_.size() && in_memory > budget; ++id) {
      Record& record = records_[id];
      if (record.spilled || record.changes.empty()) continue;
      // One append a record, its blocks in key order: the index is their keys and ends.
      std::vector<std::uint64_t> keys;
      keys.reserve(record.changes.size());
      for (const auto& entry : record.changes) keys.push_back(entry.first);
      std::sort(keys.begin(), keys.end());
      std::string bytes;
      SpilledIndex index;
      index.ends.reserve(keys.size());
      for (std::uint64_t key : keys) {
        record.changes.at(key).appendPackedTo(&bytes);
        if (bytes.size() > std::numeric_limits<std::uint32_t>::max()) {
          throw std::runtime_error("submaps: a submap's changes exceed 4 GiB");
        }
        index.ends.push_back(static_cast<std::uint32_t>(bytes.size()));
      }
      index.keys = std::move(keys);
      index.base = spill->append(bytes);
      written += bytes.size();
      in_memory -= record.bytes;
      record.changes = SpatialKeyMap<typename Traits::Stored>();
      record.spilled = true;
      record.spilled_index = std::move(index);
      record.bytes = record.spilled_index.bytes();
    }
    return written;
  }

  // Submap `id` re-placed: its coverage follows; the store's blocks it covered and covers are
  // added to `touched`.
  void move(int id, const SubmapPlacement& placement, SpatialKeySet* touched) {
    Record& record = records_[id];
    touched->insert(record.footprint.begin(), record.footprint.end());
    removeCoverage(id);
    addCoverage(id, placement);
    touched->insert(record.footprint.begin(), record.footprint.end());
  }
  void cover(int id, const SubmapPlacement& placement) { addCoverage(id, placement); }

  // Submap `id` re-placed with its changes drawn anew at placement.placed (its measurements
  // integrated there: no re-sampling), each block from before[i] to after[i], replacing those it
  // had; `touched` as move().
  void redraw(int id, const std::vector<Index>& indices, const std::vector<Cells>& before,
              const std::vector<Cells>& after, const SubmapPlacement& placement,
              SpatialKeySet* touched) {
    touched->insert(records_[id].footprint.begin(), records_[id].footprint.end());
    removeCoverage(id);
    Record record;
    for (std::size_t i = 0; i < indices.size(); ++i) {
      typename Traits::Stored stored = Traits::store(*store_, before[i], after[i]);
      if (stored.changed() > 0) record.add(indices[i], std::move(stored), cellSide());
    }
    // The bounds stay those of where the submap was written, as for the other records.
    Eigen::AlignedBox3d written;
    if (!record.bounds.isEmpty()) {
      const Eigen::Isometry3d back = placement.written * placement.placed.inverse();
      for (int i = 0; i < 8; ++i) {
        written.extend(back *
                       record.bounds.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i)));
      }
    }
    record.bounds = written;
    record.drawn_at = placement.placed;
    records_[id] = std::move(record);
    addCoverage(id, placement);
    touched->insert(records_[id].footprint.begin(), records_[id].footprint.end());
  }

  // Where submap `id`'s measurements land when drawn at `placement`: its placed footprint grown
  // by one block each way (a scan drawn at its own correction may reach a block further).
  std::vector<Index> reach(int id, const SubmapPlacement& placement) const {
    SpatialKeySet reached;
    const Index one = Index::Ones();
    for (std::uint64_t key : footprint(records_[id], placement)) {
      const Index index = Traits::unkey(key);
      forEachIndexIn(Index(index - one), Index(index + one),
                     [&](const Index& near) { reached.insert(Traits::key(near)); });
    }
    std::vector<Index> indices;
    for (std::uint64_t key : reached) indices.push_back(Traits::unkey(key));
    return indices;
  }

  // The closed submaps written before `id` added up over `indices` at their placements: what the
  // store held there, as those submaps are placed now, when submap `id` began.
  std::vector<Cells> foldBefore(int id, const std::vector<Index>& indices,
                                const std::vector<SubmapPlacement>& placements) const {
    std::vector<Cells> sums(indices.size());
    const long count = static_cast<long>(indices.size());
#pragma omp parallel for schedule(dynamic, 8)
    for (long i = 0; i < count; ++i) {
      auto it = coverage_.find(Traits::key(indices[i]));
      if (it == coverage_.end()) continue;
      for (int earlier : it->second) {
        if (earlier >= id) break;  // in the order written
        foldInto(earlier, placements[earlier], indices[i], &sums[i]);
      }
    }
    return sums;
  }

  // The blocks rebuilt from the closed submaps at their placements (by id), with the active
  // submap's writes so far on top.
  void rebuild(const SpatialKeySet& touched, const std::vector<SubmapPlacement>& placements) {
    if (touched.empty()) return;
    const std::vector<std::uint64_t> keys(touched.begin(), touched.end());
    std::vector<Cells> sums(keys.size());
    const long count = static_cast<long>(keys.size());
#pragma omp parallel for schedule(dynamic, 8)
    for (long i = 0; i < count; ++i) {
      auto it = coverage_.find(keys[i]);
      if (it == coverage_.end()) continue;
      for (int id : it->second) foldInto(id, placements[id], Traits::unkey(keys[i]), &sums[i]);
    }
    SpatialKeyMap<std::size_t> position;
    std::vector<Index> indices;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      position.emplace(keys[i], i);
      indices.push_back(Traits::unkey(keys[i]));
    }
    const float min = store_->minLogOdds(), max = store_->maxLogOdds();
    // Under the store's lock: the active submap's changes so far stay on top of the new sum.
    Traits::rewrite(store_, indices, [&](const Index& index, Cells& contents) {
      const Cells& sum = sums[position.at(Traits::key(index))];
      auto it = active_->before.find(Traits::key(index));
      if (it == active_->before.end()) {
        contents = sum;
        return;
      }
      Cells active_changes;
      logOddsChanges(before(it->second), contents, &active_changes);
      it.value() = sum.known_count > 0 ? std::make_unique<Cells>(sum) : nullptr;
      contents = sum;
      addLogOddsChanges(active_changes, min, max, &contents);
    });
  }

  // The records as bytes (host order), and back: readRecords replaces every record and the active
  // submap's sights (the store holds what the records add up to, e.g. a map just loaded); cover()
  // then places each. false: the bytes are not what writeRecords writes.
  void writeRecords(std::ostream& out) const {
    writeValue(out, static_cast<std::uint64_t>(records_.size()));
    for (const Record& record : records_) {
      writeValue(out, static_cast<std::uint8_t>(record.drawn_at ? 1 : 0));
      if (record.drawn_at) {
        out.write(reinterpret_cast<const char*>(record.drawn_at->matrix().data()),
                  16 * sizeof(double));
      }
      writeValue(out, static_cast<std::uint64_t>(record.blockCount()));
      forEachStored(record, [&](std::uint64_t key, const typename Traits::Stored& stored) {
        writeValue(out, key);
        stored.writeTo(out);
      });
    }
  }
  bool readRecords(std::istream& in, std::size_t expected) {
    std::uint64_t count = 0;
    if (!readValue(in, &count) || count != expected) return false;
    std::deque<Record> records(count);
    for (Record& record : records) {
      std::uint8_t drawn = 0;
      if (!readValue(in, &drawn)) return false;
      if (drawn != 0) {
        Eigen::Isometry3d at = Eigen::Isometry3d::Identity();
        in.read(reinterpret_cast<char*>(at.matrix().data()), 16 * sizeof(double));
        if (!in || !at.matrix().allFinite()) return false;
        record.drawn_at = at;
      }
      std::uint64_t blocks = 0;
      if (!readValue(in, &blocks)) return false;
      for (std::uint64_t i = 0; i < blocks; ++i) {
        std::uint64_t key = 0;
        typename Traits::Stored stored;
        if (!readValue(in, &key) || !stored.readFrom(in)) return false;
        record.add(Traits::unkey(key), std::move(stored), cellSide());
      }
    }
    reset();
    records_ = std::move(records);
    return true;
  }

  // Forgets every submap and the active one's sights (the store itself is reset by the caller).
  void reset() {
    auto next = std::make_unique<ActiveWrites>(cellSide());
    Traits::setWriteWatcher(store_, next.get(), {});
    active_ = std::move(next);
    records_.clear();
    coverage_.clear();
  }

  std::size_t coverageBytes() const {
    std::size_t bytes = 0;
    for (const auto& entry : coverage_) {
      bytes += sizeof(entry) + entry.second.capacity() * sizeof(int);
    }
    return bytes;
  }

 private:
  // The active submap: each block's contents before its first write since it began. Touched
  // under the store's exclusive lock only, apart from info_mutex's fields.
  struct ActiveWrites : CellsWriteWatcher<Index, Cells> {
    explicit ActiveWrites(double side) : cell_side(side) {}
    void beforeFirstWrite(const Index& index, const Cells* contents) override {
      auto inserted = before.try_emplace(Traits::key(index));
      if (!inserted.second) return;
      // Nothing kept for a block that was all unknown (most of a new submap's): nullptr.
      const bool keep = contents != nullptr && contents->known_count > 0;
      if (keep) inserted.first.value() = std::make_unique<Cells>(*contents);
      std::lock_guard<std::mutex> lock(info_mutex);
      ++count;
      kept += keep ? 1 : 0;
      bounds.extend(containerBox(index, cell_side));
    }
    SpatialKeyMap<std::unique_ptr<Cells>> before;
    mutable std::mutex info_mutex;
    std::size_t count = 0;
    std::size_t kept = 0;  // blocks' contents kept (the others were all unknown)
    Eigen::AlignedBox3d bounds;
    const double cell_side;
  };

  // Where a spilled record's blocks lie in the spill file: one stretch from `base`, the blocks
  // in key order, each ending at ends[i] (16 bytes a block, against about 40 in a hash table).
  struct SpilledIndex {
    std::uint64_t base = 0;
    std::vector<std::uint64_t> keys;  // ascending
    std::vector<std::uint32_t> ends;  // bytes from base
    std::size_t size() const { return keys.size(); }
    std::size_t bytes() const {
      return keys.capacity() * sizeof(std::uint64_t) + ends.capacity() * sizeof(std::uint32_t);
    }
    // Block `key`'s offset and size in the file; false: not in the record.
    bool find(std::uint64_t key, std::uint64_t* offset, std::uint32_t* size) const {
      const auto it = std::lower_bound(keys.begin(), keys.end(), key);
      if (it == keys.end() || *it != key) return false;
      const std::size_t i = static_cast<std::size_t>(it - keys.begin());
      const std::uint32_t begin = i == 0 ? 0 : ends[i - 1];
      *offset = base + begin;
      *size = ends[i] - begin;
      return true;
    }
  };

  struct Record {
    // In memory, or (spilled) in the spill file with only where each block's changes lie here.
    SpatialKeyMap<typename Traits::Stored> changes;
    SpilledIndex spilled_index;
    bool spilled = false;
    std::size_t bytes = 0;                 // of memory
    Eigen::AlignedBox3d bounds;            // of its blocks, where written
    std::vector<std::uint64_t> footprint;  // the store's blocks its placed changes reach
    // Set when the changes were drawn anew from the submap's measurements at this placement
    // (redraw) instead of being those it wrote: they are in the map's grid there.
    std::optional<Eigen::Isometry3d> drawn_at;

    void add(const Index& index, typename Traits::Stored stored, double cell_side) {
      bytes += Traits::bytes(stored);
      bounds.extend(containerBox(index, cell_side));
      changes.emplace(Traits::key(index), std::move(stored));
    }
    std::size_t blockCount() const { return spilled ? spilled_index.size() : changes.size(); }
  };

  template <class Fn>
  static void forEachKey(const Record& record, Fn fn) {
    if (record.spilled) {
      for (std::uint64_t key : record.spilled_index.keys) fn(key);
    } else {
      for (const auto& entry : record.changes) fn(entry.first);
    }
  }
  // The changes of block `key` of a record, read back from the spill file if it is there; false
  // when the record changed no such block.
  bool storedOf(const Record& record, std::uint64_t key, typename Traits::Stored* out) const {
    if (!record.spilled) return false;
    std::uint64_t offset = 0;
    std::uint32_t size = 0;
    if (!record.spilled_index.find(key, &offset, &size)) return false;
    thread_local std::string bytes;
    spill_->read(offset, size, &bytes);
    if (!out->readPacked(bytes)) throw std::runtime_error("submaps: a damaged spill file");
    return true;
  }
  // Block `key`'s changes expanded into *scratch; nullptr when the record changed no such block.
  const Cells* changesOf(const Record& record, std::uint64_t key, Cells* scratch) const {
    if (record.spilled) {
      typename Traits::Stored stored;
      if (!storedOf(record, key, &stored)) return nullptr;
      return &Traits::view(stored, scratch);
    }
    auto it = record.changes.find(key);
    return it == record.changes.end() ? nullptr : &Traits::view(it->second, scratch);
  }
  template <class Fn>
  void forEachStored(const Record& record, Fn fn) const {
    if (!record.spilled) {
      for (const auto& entry : record.changes) fn(entry.first, entry.second);
      return;
    }
    for (std::uint64_t key : record.spilled_index.keys) {
      typename Traits::Stored stored;
      storedOf(record, key, &stored);
      fn(key, stored);
    }
  }

  static constexpr std::size_t kTableSlotBytes = 24;  // a hash table entry, about

  template <class T>
  static void writeValue(std::ostream& out, const T& value) {
    out.write(reinterpret_cast<const char*>(&value), sizeof(value));
  }
  template <class T>
  static bool readValue(std::istream& in, T* value) {
    in.read(reinterpret_cast<char*>(value), sizeof(*value));
    return static_cast<bool>(in);
  }

  double cellSide() const { return store_->resolution(); }

  // An active submap's record of a block before its first write; nullptr: all unknown.
  static const Cells& before(const std::unique_ptr<Cells>& kept) {
    static const Cells unknown;
    return kept ? *kept : unknown;
  }

  // The map-frame box (m) of a block or tile (a tile's is flat, at z = 0).
  static Eigen::AlignedBox3d containerBox(const Index& index, double cell_side) {
    const double side = cell_side * Traits::side();
    const Vector lo = index.template cast<double>() * side;
    const Vector hi = lo + Vector::Constant(side);
    return Eigen::AlignedBox3d(Traits::point(lo), Traits::point(hi));
  }

  // Where a record's changes were taken: where written, or where they were drawn anew.
  static SubmapPlacement effective(const Record& record, const SubmapPlacement& placement) {
    return record.drawn_at ? SubmapPlacement{*record.drawn_at, placement.placed} : placement;
  }

  std::vector<std::uint64_t> footprint(const Record& record,
                                       const SubmapPlacement& submap_placement) const {
    const SubmapPlacement placement = effective(record, submap_placement);
    std::vector<std::uint64_t> keys;
    if (placement.atWrittenPlace()) {
      forEachKey(record, [&](std::uint64_t key) { keys.push_back(key); });
      return keys;
    }
    // Each changed block's corners moved: the blocks of their bounding box.
    const Eigen::Isometry3d moved = placement.placed * placement.written.inverse();
    const double side = cellSide() * Traits::side();
    SpatialKeySet reached;
    forEachKey(record, [&](std::uint64_t key) {
      const Eigen::AlignedBox3d box = containerBox(Traits::unkey(key), cellSide());
      Eigen::AlignedBox3d to;
      for (int i = 0; i < 8; ++i) {
        to.extend(moved * box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i)));
      }
      const Index from = Traits::floorIndex(to.min() / side);
      const Index last = Traits::floorIndex(to.max() / side);
      forEachIndexIn(from, last, [&](const Index& index) { reached.insert(Traits::key(index)); });
    });
    keys.assign(reached.begin(), reached.end());
    return keys;
  }

  template <class Fn>
  static void forEachIndexIn(const Index& from, const Index& last, Fn fn) {
    Index index = from;
    while (true) {
      fn(index);
      int axis = 0;
      while (axis < Index::RowsAtCompileTime && index[axis] == last[axis]) {
        index[axis] = from[axis];
        ++axis;
      }
      if (axis == Index::RowsAtCompileTime) return;
      ++index[axis];
    }
  }

  void addCoverage(int id, const SubmapPlacement& placement) {
    Record& record = records_[id];
    record.footprint = footprint(record, placement);
    for (std::uint64_t key : record.footprint) {
      std::vector<int>& covering = coverage_[key];
      covering.insert(std::upper_bound(covering.begin(), covering.end(), id), id);
    }
  }

  void removeCoverage(int id) {
    for (std::uint64_t key : records_[id].footprint) {
      auto it = coverage_.find(key);
      if (it == coverage_.end()) continue;
      std::vector<int>& covering = it.value();
      covering.erase(std::remove(covering.begin(), covering.end(), id), covering.end());
      if (covering.empty()) coverage_.erase(it);
    }
  }

  // The changes of a record's blocks (tiles) that one destination block reads, each expanded once:
  // a moved block of the map's grid covers parts of up to 2^D of the written grid's.
  class SourceCache {
   public:
    SourceCache(const StoreSubmaps& owner, const Record& record) : owner_(owner), record_(record) {}
    // The change of one cell of the written grid (NaN: none, or no such block).
    float change(const Index& cell) {
      const std::uint64_t key = Traits::key(Traits::containerOf(cell));
      const Cells* source = nullptr;
      int slot = 0;
      while (slot < used_ && keys_[slot] != key) ++slot;
      if (slot < used_) {
        source = sources_[slot];
      } else {
        slot = next_;
        next_ = (next_ + 1) % kSlots;
        used_ = std::max(used_, slot + 1);
        keys_[slot] = key;
        source = owner_.changesOf(record_, key, &scratch_[slot]);
        sources_[slot] = source;
      }
      return source == nullptr ? kNoChange : source->log_odds[Traits::linearOf(cell)];
    }

   private:
    static constexpr int kSlots = 8;
    static constexpr float kNoChange = std::numeric_limits<float>::quiet_NaN();
    const StoreSubmaps& owner_;
    const Record& record_;
    std::array<std::uint64_t, kSlots> keys_{};
    std::array<const Cells*, kSlots> sources_{};
    std::array<Cells, kSlots> scratch_;
    int used_ = 0, next_ = 0;
  };

  // Submap `id`'s changes added to block `index`'s cells at the submap's placement. A moved
  // submap's grid no longer lines up with the map's: each cell takes the change of the written
  // cell under its centre (nearest cell), and where that change is occupied evidence (> 0), its
  // mix with the known neighbours' by distance (sampledChange).
  void foldInto(int id, const SubmapPlacement& submap_placement, const Index& index,
                Cells* cells) const {
    const Record& record = records_[id];
    const SubmapPlacement placement = effective(record, submap_placement);
    const float min = store_->minLogOdds(), max = store_->maxLogOdds();
    if (placement.atWrittenPlace()) {
      Cells scratch;
      if (const Cells* changes = changesOf(record, Traits::key(index), &scratch)) {
        addLogOddsChanges(*changes, min, max, cells);
      }
      return;
    }
    const Eigen::Isometry3d to_written = placement.written * placement.placed.inverse();
    const double resolution = cellSide();
    auto cache = std::make_unique<SourceCache>(*this, record);
    for (int linear = 0; linear < Traits::kCellCount; ++linear) {
      const Vector center =
          (Traits::cellOf(index, linear).template cast<double>() + Vector::Constant(0.5)) *
          resolution;
      const float change = sampledChange(
          cache.get(), Traits::scaled(to_written * Traits::point(center) / resolution));
      cells->set(linear, addLogOddsChange(cells->log_odds[linear], change, min, max));
    }
  }

  // The written grid's change at `at` (in cells: cell c spans [c, c + 1)). Free evidence fills
  // wide regions, and the nearest cell's is taken. Occupied evidence lies in shells a cell or two
  // thick, and the nearest cell moves it up to 0.87 cells outwards (a wall thickened where a
  // rotated grid rounds away from it): there the change is mixed (bi-, trilinearly) with its known
  // neighbours', so a cell whose centre lies far from the written surface cell takes in their
  // free evidence. Building loop at twice the drift: false-occupied 1.28 -> 0.93 x the true-pose
  // map's, moves 1.25 x as long (docs/loop_closures.md).
  static float sampledChange(SourceCache* cache, const Vector& at) {
    const float nearest = cache->change(floorOf(at));
    if (!(nearest > 0.0f)) return nearest;  // free, or no change (NaN)
    const Vector below = (at - Vector::Constant(0.5)).array().floor();
    const Vector fraction = at - Vector::Constant(0.5) - below;
    double sum = 0.0, weights = 0.0;
    for (int corner = 0; corner < (1 << kDimensions); ++corner) {
      Index cell = below.template cast<int>();
      double weight = 1.0;
      for (int axis = 0; axis < kDimensions; ++axis) {
        const bool above = (corner >> axis) & 1;
        cell[axis] += above ? 1 : 0;
        weight *= above ? fraction[axis] : 1.0 - fraction[axis];
      }
      const float change = cache->change(cell);
      if (weight <= 0.0 || std::isnan(change)) continue;  // unknown neighbours add nothing
      sum += weight * change;
      weights += weight;
    }
    return weights > 0.0 ? static_cast<float>(sum / weights) : nearest;
  }
  static Index floorOf(const Vector& at) { return at.array().floor().template cast<int>(); }

  Store* store_;
  SubmapSpillFile* spill_ = nullptr;  // the fusion's, when the submaps have a memory bound
  std::unique_ptr<ActiveWrites> active_;
  std::deque<Record> records_;  // by submap id (a deque: records move, never copy)
  // For every block of the store, the closed submaps whose placed changes reach it, in the order
  // they were written.
  SpatialKeyMap<std::vector<int>> coverage_;
};

}  // namespace occupancy_fusion
