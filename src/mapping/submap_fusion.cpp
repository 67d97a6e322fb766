#include "occupancy_fusion/mapping/submap_fusion.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <stdexcept>
#include <string>

#include "store_submaps.h"
#include "submap_spill_file.h"

namespace occupancy_fusion {

// The submaps' changes in each store; the layer's absent without a layer.
struct SubmapFusion::Stores {
  Stores(VoxelMap* map, GridLayer2D* layer)
      : voxels(map),
        tiles(layer != nullptr ? std::make_unique<StoreSubmaps<TileStoreTraits>>(layer) : nullptr) {
  }

  template <class Fn>
  void forEach(Fn fn) {
    fn(voxels);
    if (tiles) fn(*tiles);
  }

  StoreSubmaps<VoxelStoreTraits> voxels;
  std::unique_ptr<StoreSubmaps<TileStoreTraits>> tiles;
};

double largestShift(const Eigen::AlignedBox3d& box, const Eigen::Isometry3d& written,
                    const Eigen::Isometry3d& from, const Eigen::Isometry3d& to) {
  if (box.isEmpty()) return 0.0;
  // A rigid motion moves the points of a box farthest at one of its corners.
  const Eigen::Isometry3d before = from * written.inverse(), after = to * written.inverse();
  double largest = 0.0;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i));
    largest = std::max(largest, (after * corner - before * corner).norm());
  }
  return largest;
}

void SubmapFusionConfig::validate() const {
  if (!(min_shift >= 0.0) || !std::isfinite(min_shift)) {
    throw std::invalid_argument("submaps/min_shift must be >= 0 m (0: a quarter voxel), got " +
                                std::to_string(min_shift));
  }
}

SubmapFusion::SubmapFusion(VoxelMap* map, GridLayer2D* layer, const SubmapFusionConfig& config,
                           const Eigen::Isometry3d& T_map_odom)
    : map_(map), layer_(layer), config_(config) {
  config_.validate();
  min_shift_ = config_.min_shift > 0.0 ? config_.min_shift : 0.25 * map_->resolution();
  stores_ = std::make_unique<Stores>(map_, layer_);
  adoptContentsLocked();
  active_.id = static_cast<int>(closed_.size());
  active_.written = active_.placed = T_map_odom;
  stores_->forEach([](auto& store) { store.startWatching(); });
}

SubmapFusion::~SubmapFusion() = default;

SubmapFusion::FrameLease SubmapFusion::beginFrame(double stamp) {
  FrameLease lease;
  // The active submap's id and placement change only under frames_mutex_'s unique lock: read
  // without mutex_, which a correction holds while it rebuilds the map (frames go on meanwhile).
  lease.lock_ = std::shared_lock<std::shared_mutex>(frames_mutex_);
  lease.submap_ = active_.id;
  lease.T_map_odom_ = active_.written;
  if (stamp != 0.0) {
    std::lock_guard<std::mutex> stamps(stamp_mutex_);
    active_.start = active_.start == 0.0 ? stamp : std::min(active_.start, stamp);
    active_.end = std::max(active_.end, stamp);
  }
  return lease;
}

std::size_t SubmapFusion::activeBlocks() const {
  std::size_t count = stores_->voxels.activeBlocks();
  if (stores_->tiles) count += stores_->tiles->activeBlocks();
  return count;
}

Eigen::AlignedBox3d SubmapFusion::activeBounds() const {
  Eigen::AlignedBox3d box = stores_->voxels.activeBounds();
  if (stores_->tiles) box.extend(stores_->tiles->activeBounds());
  return box;
}

Eigen::AlignedBox3d SubmapFusion::boundsOf(int id) const {
  Eigen::AlignedBox3d box = stores_->voxels.bounds(id);
  if (stores_->tiles) box.extend(stores_->tiles->bounds(id));
  return box;
}

int SubmapFusion::startSubmap(const Eigen::Isometry3d& T_map_odom) {
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  startSubmapLocked(T_map_odom);
  return active_.id;
}

void SubmapFusion::startSubmapLocked(const Eigen::Isometry3d& T_map_odom) {
  if (activeBlocks() == 0) {  // nothing written yet: the same submap, placed anew
    active_.written = active_.placed = T_map_odom;
  } else {
    closeActiveLocked(T_map_odom);
  }
}

int SubmapFusion::startSubmap() {
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  if (activeBlocks() > 0) closeActiveLocked(active_.written);
  return active_.id;
}

bool SubmapFusion::tryStartSubmap() {
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  const std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return false;  // place() holds it for the whole rebuild
  if (activeBlocks() > 0) closeActiveLocked(active_.written);
  return true;
}

bool SubmapFusion::tryStartSubmap(const Eigen::Isometry3d& T_map_odom) {
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  const std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return false;
  startSubmapLocked(T_map_odom);
  return true;
}

void SubmapFusion::fixWrittenSoFar() {
  std::lock_guard<std::mutex> correcting(correction_mutex_);
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  if (activeBlocks() == 0) return;
  closeActiveLocked(active_.written);
  closed_.back().fixed = true;
}

void SubmapFusion::closeActiveLocked(Eigen::Isometry3d next_T_map_odom) {
  stores_->forEach([](auto& store) { store.closeActive(); });
  {
    std::lock_guard<std::mutex> stamps(stamp_mutex_);
    closed_.push_back(active_);
    active_ = Meta();
  }
  const Meta& closed = closed_.back();
  stores_->forEach([&](auto& store) { store.cover(closed.id, {closed.written, closed.placed}); });
  active_.id = static_cast<int>(closed_.size());
  active_.written = active_.placed = next_T_map_odom;
  enforceMemoryBoundLocked();
}

void SubmapFusion::enforceMemoryBoundLocked() {
  if (config_.max_memory_bytes == 0) return;
  // What stays in memory whatever is spilled (which submaps reach each block, where spilled
  // blocks lie, the submap being written) comes first; the closed changes get what it leaves.
  std::size_t fixed = 0;
  stores_->forEach([&](const auto& store) {
    fixed += store.coverageBytes() + store.spilledIndexBytes() + store.activeBytes();
  });
  const std::size_t budget =
      config_.max_memory_bytes > fixed ? config_.max_memory_bytes - fixed : 0;
  const std::size_t tiles = stores_->tiles ? stores_->tiles->inMemoryBytes() : 0;
  if (stores_->voxels.inMemoryBytes() + tiles <= budget) return;
  if (!spill_) spill_ = std::make_unique<SubmapSpillFile>(config_.spill_folder);
  stores_->voxels.spillOldest(budget > tiles ? budget - tiles : 0, spill_.get());
  if (stores_->tiles) {
    const std::size_t voxels = stores_->voxels.inMemoryBytes();
    stores_->tiles->spillOldest(budget > voxels ? budget - voxels : 0, spill_.get());
  }
}

std::size_t SubmapFusion::spilledBytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return spill_ ? spill_->bytes() : 0;
}

void SubmapFusion::placeActiveLocked(const Eigen::Isometry3d& placed,
                                     const Eigen::Isometry3d& next) {
  const Eigen::AlignedBox3d bounds = activeBounds();
  if (activeBlocks() == 0) {
    active_.written = active_.placed = next;
    return;
  }
  const bool moves = largestShift(bounds, active_.written, active_.written, placed) > min_shift_;
  const bool next_moves = largestShift(bounds, active_.written, active_.written, next) > min_shift_;
  // Closed at its written place; the loop over the closed submaps then moves it to `placed`.
  if (moves || next_moves) closeActiveLocked(next);
}

SubmapMoveResult SubmapFusion::place(const Placements& placements,
                                     const std::optional<Eigen::Isometry3d>& next) {
  const auto start = std::chrono::steady_clock::now();
  SubmapMoveResult result;
  std::lock_guard<std::mutex> correcting(correction_mutex_);
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  std::unique_lock<std::mutex> lock(mutex_);
  const int active_id = active_.id;
  const auto active_placement =
      std::find_if(placements.begin(), placements.end(),
                   [&](const auto& placement) { return placement.first == active_id; });
  // The active submap moves as a closed one: its next frames are written at the new place.
  if (active_placement != placements.end() || next) {
    const Eigen::Isometry3d placed =
        active_placement != placements.end() ? active_placement->second : active_.written;
    placeActiveLocked(placed, next ? *next : placed);
  }
  frames.unlock();  // frames go on into the new active submap while the map is rebuilt
  SpatialKeySet touched_blocks, touched_tiles;
  std::vector<int> moved;
  for (const auto& placement : placements) {
    if (placement.first < 0 || placement.first >= static_cast<int>(closed_.size())) continue;
    Meta& submap = closed_[static_cast<std::size_t>(placement.first)];
    if (submap.fixed || largestShift(boundsOf(submap.id), submap.written, submap.placed,
                                     placement.second) <= min_shift_) {
      continue;
    }
    submap.placed = placement.second;
    stores_->voxels.move(submap.id, {submap.written, submap.placed}, &touched_blocks);
    moved.push_back(submap.id);
    ++result.moved;
  }
  std::vector<SubmapPlacement> placed;
  for (const Meta& submap : closed_) placed.push_back({submap.written, submap.placed});
  // First every moved submap re-sampled at its place, the voxels and the laser layer side by side
  // (they share nothing): the map follows the correction at once.
  auto voxels =
      std::async(std::launch::async, [&] { stores_->voxels.rebuild(touched_blocks, placed); });
  if (stores_->tiles) {
    for (int id : moved) stores_->tiles->move(id, placed[id], &touched_tiles);
    stores_->tiles->rebuild(touched_tiles, placed);
  }
  voxels.get();
  const auto seconds_since = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  result.moved_seconds = seconds_since();
  if (result.moved > 0) moves_.fetch_add(1, std::memory_order_release);
  // Then the laser layer's moved submaps drawn again from their scans: its thin walls where a map
  // made at the new placements has them (one submap after another: the slower part).
  if (stores_->tiles && drawer_ != nullptr && !moved.empty()) {
    SpatialKeySet drawn_tiles;
    drawTiles(moved, placed, &drawn_tiles, &lock);
    placed.clear();  // a frame may have closed the active submap meanwhile
    for (const Meta& submap : closed_) placed.push_back({submap.written, submap.placed});
    stores_->tiles->rebuild(drawn_tiles, placed);
    touched_tiles.insert(drawn_tiles.begin(), drawn_tiles.end());
  }
  enforceMemoryBoundLocked();  // the records drawn again are in memory
  result.blocks_rewritten = touched_blocks.size() + touched_tiles.size();
  result.seconds = seconds_since();
  return result;
}

void SubmapFusion::setLayerDrawer(LayerDrawer* drawer) {
  std::lock_guard<std::mutex> lock(mutex_);
  drawer_ = drawer;
}

void SubmapFusion::drawTiles(std::vector<int> moved, const std::vector<SubmapPlacement>& placed,
                             SpatialKeySet* touched, std::unique_lock<std::mutex>* lock) {
  // In the order written, each on what the submaps before it hold there now: a cell's updates
  // are then clamped in the order a single pass over the scans clamps them (drawn from unknown
  // and added, a wall that a later submap's scans cleared stays occupied). Submaps the drawer
  // keeps nothing for stay re-sampled.
  std::sort(moved.begin(), moved.end());
  GridLayer2DConfig config = layer_->config();
  config.max_memory_bytes = 0;
  for (int id : moved) {
    const SubmapPlacement& placement = placed[static_cast<std::size_t>(id)];
    const std::vector<TileIndex> reach = stores_->tiles->reach(id, placement);
    const std::vector<GridTile> before = stores_->tiles->foldBefore(id, reach, placed);
    GridLayer2D layer(config);
    SpatialKeyMap<std::size_t> position;
    for (std::size_t i = 0; i < reach.size(); ++i) {
      position.emplace(packKey(reach[i]), i);
      if (before[i].known_count > 0) layer.restoreTile(reach[i], before[i]);
    }
    // Drawing is most of a correction's time: a frame due to close the active submap may do it
    // meanwhile (it adds a submap after every moved one: no earlier submap's fold changes).
    lock->unlock();
    const bool drawn = drawer_->draw(id, placement.placed, &layer);
    lock->lock();
    if (!drawn) continue;
    std::vector<TileIndex> indices;
    std::vector<GridTile> from, to;
    layer.forEachTile([&](const TileIndex& index, const GridTile& after) {
      const auto found = position.find(packKey(index));
      indices.push_back(index);
      from.push_back(found == position.end() ? GridTile() : before[found->second]);
      to.push_back(after);
    });
    stores_->tiles->redraw(id, indices, from, to, placement, touched);
  }
}

std::vector<SubmapInfo> SubmapFusion::submaps() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<SubmapInfo> result;
  const auto describe = [&](const Meta& meta) {
    SubmapInfo info;
    info.id = meta.id;
    info.fixed = meta.fixed;
    info.start_stamp = meta.start;
    info.end_stamp = meta.end;
    info.written = meta.written;
    info.placed = meta.placed;
    return info;
  };
  for (const Meta& meta : closed_) {
    SubmapInfo info = describe(meta);
    info.blocks = stores_->voxels.blocks(meta.id);
    info.bytes = stores_->voxels.bytes(meta.id);
    if (stores_->tiles) {
      info.tiles = stores_->tiles->blocks(meta.id);
      info.bytes += stores_->tiles->bytes(meta.id);
    }
    info.bounds = boundsOf(meta.id);
    result.push_back(info);
  }
  {
    std::lock_guard<std::mutex> stamps(stamp_mutex_);
    result.push_back(describe(active_));
  }
  SubmapInfo& active = result.back();
  active.active = true;
  active.blocks = stores_->voxels.activeBlocks();
  active.bytes = stores_->voxels.activeBytes();
  if (stores_->tiles) {
    active.tiles = stores_->tiles->activeBlocks();
    active.bytes += stores_->tiles->activeBytes();
  }
  active.bounds = activeBounds();
  return result;
}

Eigen::AlignedBox3d SubmapFusion::newestBounds() const {
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  std::lock_guard<std::mutex> newest(newest_mutex_);
  if (!lock) return newest_bounds_;  // a correction rebuilds the map: as last measured
  Eigen::AlignedBox3d box = activeBounds();
  for (int id = static_cast<int>(closed_.size()) - 1; box.isEmpty() && id >= 0; --id) {
    box = boundsOf(id);
  }
  newest_bounds_ = box;
  return box;
}

int SubmapFusion::activeSubmap() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return active_.id;
}

std::size_t SubmapFusion::memoryBytes() const {
  std::size_t bytes = 0;
  for (const SubmapInfo& info : submaps()) bytes += info.bytes;
  std::lock_guard<std::mutex> lock(mutex_);
  stores_->forEach([&](const auto& store) { bytes += store.coverageBytes(); });
  return bytes;
}

namespace {

constexpr char kSubmapMagic[8] = {'O', 'F', 'S', 'U', 'B', 'M', 'P', '1'};

template <class T>
void writeValue(std::ostream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(value));
}
template <class T>
T readValue(std::istream& in) {
  T value{};
  in.read(reinterpret_cast<char*>(&value), sizeof(value));
  if (!in) throw std::runtime_error("submaps: the file ends early");
  return value;
}
void writePose(std::ostream& out, const Eigen::Isometry3d& pose) {
  out.write(reinterpret_cast<const char*>(pose.matrix().data()), 16 * sizeof(double));
}
Eigen::Isometry3d readPose(std::istream& in) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  in.read(reinterpret_cast<char*>(pose.matrix().data()), 16 * sizeof(double));
  if (!in || !pose.matrix().allFinite()) throw std::runtime_error("submaps: a bad placement");
  return pose;
}

}  // namespace

void SubmapFusion::save(std::ostream& out) { saveThen(out, {}); }

void SubmapFusion::saveThen(std::ostream& out, const std::function<void()>& then) {
  std::lock_guard<std::mutex> correcting(correction_mutex_);
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  if (activeBlocks() > 0) closeActiveLocked(active_.written);
  out.write(kSubmapMagic, sizeof(kSubmapMagic));
  writeValue(out, map_->resolution());
  writeValue(out, static_cast<std::uint8_t>(stores_->tiles ? 1 : 0));
  writeValue(out, static_cast<std::uint64_t>(closed_.size()));
  for (const Meta& meta : closed_) {
    writeValue(out, static_cast<std::uint8_t>(meta.fixed ? 1 : 0));
    writeValue(out, meta.start);
    writeValue(out, meta.end);
    writePose(out, meta.written);
    writePose(out, meta.placed);
  }
  writePose(out, active_.written);
  stores_->forEach([&](const auto& store) { store.writeRecords(out); });
  if (then) then();
}

void SubmapFusion::restore(std::istream& in) {
  std::lock_guard<std::mutex> correcting(correction_mutex_);
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    restoreLocked(in);
  } catch (const std::runtime_error&) {
    fixContentsLocked();
    throw;
  }
}

void SubmapFusion::restoreLocked(std::istream& in) {
  char magic[sizeof(kSubmapMagic)] = {};
  in.read(magic, sizeof(magic));
  if (!in || !std::equal(magic, magic + sizeof(magic), kSubmapMagic)) {
    throw std::runtime_error("submaps: not a submaps file of this version");
  }
  const double resolution = readValue<double>(in);
  if (std::abs(resolution - map_->resolution()) > 1e-9 * map_->resolution()) {
    throw std::runtime_error("submaps: saved at resolution " + std::to_string(resolution) +
                             " m, the map's is " + std::to_string(map_->resolution()) + " m");
  }
  if ((readValue<std::uint8_t>(in) != 0) != static_cast<bool>(stores_->tiles)) {
    throw std::runtime_error("submaps: saved with and restored without a laser layer, or back");
  }
  std::vector<Meta> metas(readValue<std::uint64_t>(in));
  for (std::size_t id = 0; id < metas.size(); ++id) {
    Meta& meta = metas[id];
    meta.id = static_cast<int>(id);
    meta.fixed = readValue<std::uint8_t>(in) != 0;
    meta.start = readValue<double>(in);
    meta.end = readValue<double>(in);
    meta.written = readPose(in);
    meta.placed = readPose(in);
  }
  const Eigen::Isometry3d next = readPose(in);
  bool read = stores_->voxels.readRecords(in, metas.size());
  if (read && stores_->tiles) read = stores_->tiles->readRecords(in, metas.size());
  if (!read) throw std::runtime_error("submaps: damaged changes");
  std::lock_guard<std::mutex> stamps(stamp_mutex_);
  closed_ = std::move(metas);
  for (const Meta& meta : closed_) {
    stores_->forEach([&](auto& store) { store.cover(meta.id, {meta.written, meta.placed}); });
  }
  active_ = Meta();
  active_.id = static_cast<int>(closed_.size());
  active_.written = active_.placed = next;
  enforceMemoryBoundLocked();
}

void SubmapFusion::adoptContentsLocked() {
  bool held = stores_->voxels.holdsContents();
  if (stores_->tiles) held = held || stores_->tiles->holdsContents();
  if (!held) return;
  stores_->forEach([](auto& store) { store.adoptExistingContents(); });
  Meta fixed;
  fixed.fixed = true;
  closed_.push_back(fixed);
  stores_->forEach([](auto& store) { store.cover(0, SubmapPlacement()); });
}

void SubmapFusion::fixContentsLocked() {
  const Eigen::Isometry3d written = active_.written;
  stores_->forEach([](auto& store) { store.reset(); });
  std::lock_guard<std::mutex> stamps(stamp_mutex_);
  closed_.clear();
  adoptContentsLocked();
  active_ = Meta();
  active_.id = static_cast<int>(closed_.size());
  active_.written = active_.placed = written;
}

void SubmapFusion::reset() {
  std::lock_guard<std::mutex> correcting(correction_mutex_);
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  stores_->forEach([](auto& store) { store.reset(); });
  spill_.reset();
  map_->reset();
  if (layer_ != nullptr) layer_->reset();
  const Eigen::Isometry3d written = active_.written;
  std::lock_guard<std::mutex> stamps(stamp_mutex_);
  closed_.clear();
  active_ = Meta();
  active_.written = active_.placed = written;
}

}  // namespace occupancy_fusion
