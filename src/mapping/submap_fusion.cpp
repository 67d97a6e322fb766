#include "occupancy_fusion/mapping/submap_fusion.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "occupancy_fusion/map/log_odds_deltas.h"

namespace occupancy_fusion {

// The active submap: each block's contents before its first write since the submap began. Only
// touched under the map's exclusive lock (the watcher's calls, rewriteBlocks, the switch).
struct SubmapFusion::ActiveWrites : BlockWriteWatcher {
  explicit ActiveWrites(const Eigen::Isometry3d& T_map_odom) : written(T_map_odom) {}

  void beforeFirstWrite(const BlockIndex& block, const VoxelBlock* contents) override {
    auto inserted = before.try_emplace(packKey(block));
    if (!inserted.second) return;
    inserted.first.value() = contents != nullptr ? std::make_unique<VoxelBlock>(*contents)
                                                 : std::make_unique<VoxelBlock>();
    std::lock_guard<std::mutex> lock(info_mutex);
    lo = lo.cwiseMin(block);
    hi = hi.cwiseMax(block);
    blocks = before.size();
  }

  void widen(double stamp) {
    if (stamp == 0.0) return;
    std::lock_guard<std::mutex> lock(info_mutex);
    start = start == 0.0 ? stamp : std::min(start, stamp);
    end = std::max(end, stamp);
  }

  Eigen::Isometry3d written;
  SpatialKeyMap<std::unique_ptr<VoxelBlock>> before;
  // For readers without the map's lock: the span of stamps, the blocks' count and bounds.
  mutable std::mutex info_mutex;
  double start = 0.0, end = 0.0;
  std::size_t blocks = 0;
  BlockIndex lo = BlockIndex::Constant(VoxelMap::kMaxBlockCoordinate), hi = -lo;
};

// A closed submap: what its frames changed, by block of the map's grid at `written`.
struct SubmapFusion::Submap {
  int id = 0;
  bool fixed = false;
  double start = 0.0, end = 0.0;
  Eigen::Isometry3d written = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d placed = Eigen::Isometry3d::Identity();
  Eigen::AlignedBox3d bounds;  // of its changed blocks, where written
  SpatialKeyMap<StoredBlock> changes;
  std::size_t bytes = 0;
  std::vector<std::uint64_t> footprint;  // fused-map blocks its placed changes reach

  bool atWrittenPlace() const { return placed.matrix() == written.matrix(); }
};

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The box (m) of the blocks from lo to hi (inclusive); empty when lo > hi.
Eigen::AlignedBox3d blockBox(const BlockIndex& lo, const BlockIndex& hi, double resolution) {
  if ((lo.array() > hi.array()).any()) return Eigen::AlignedBox3d();
  const double side = resolution * VoxelBlock::kSide;
  return Eigen::AlignedBox3d(lo.cast<double>() * side,
                             (hi.cast<double>() + Eigen::Vector3d::Ones()) * side);
}

BlockIndex floorBlock(const Eigen::Vector3d& point, double block_side) {
  return (point / block_side).array().floor().cast<int>();
}

}  // namespace

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
    throw std::invalid_argument("submaps/min_shift must be >= 0 m (0: one voxel), got " +
                                std::to_string(min_shift));
  }
}

SubmapFusion::SubmapFusion(VoxelMap* map, const SubmapFusionConfig& config,
                           const Eigen::Isometry3d& T_map_odom)
    : map_(map), config_(config) {
  config_.validate();
  min_shift_ = config_.min_shift > 0.0 ? config_.min_shift : map_->resolution();
  adoptExistingContents();
  active_ = std::make_unique<ActiveWrites>(T_map_odom);
  map_->setWriteWatcher(active_.get());
}

SubmapFusion::~SubmapFusion() { map_->setWriteWatcher(nullptr); }

void SubmapFusion::adoptExistingContents() {
  std::vector<VoxelMap::BlockCopy> blocks = map_->copyBlocks();
  if (blocks.empty()) return;
  auto fixed = std::make_unique<Submap>();
  fixed->fixed = true;
  BlockIndex lo = BlockIndex::Constant(VoxelMap::kMaxBlockCoordinate), hi = -lo;
  for (const VoxelMap::BlockCopy& copy : blocks) {
    lo = lo.cwiseMin(copy.first);
    hi = hi.cwiseMax(copy.first);
    // From unknown, a cell's change is its value.
    StoredBlock stored = StoredBlock::newDense();
    *stored.dense() = copy.second;
    stored.settle(VoxelMap::kMaxSparseBricks);
    fixed->bytes += stored.bytes();
    fixed->changes.emplace(packKey(copy.first), std::move(stored));
  }
  fixed->bounds = blockBox(lo, hi, map_->resolution());
  submaps_.push_back(std::move(fixed));
  addCoverage(0);
}

SubmapFusion::FrameLease SubmapFusion::beginFrame(double stamp) {
  FrameLease lease;
  lease.lock_ = std::shared_lock<std::shared_mutex>(frames_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  lease.submap_ = static_cast<int>(submaps_.size());
  lease.T_map_odom_ = active_->written;
  active_->widen(stamp);
  return lease;
}

int SubmapFusion::startSubmap(const Eigen::Isometry3d& T_map_odom) {
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  {
    std::lock_guard<std::mutex> info(active_->info_mutex);
    if (active_->blocks == 0) {  // nothing written yet: the same submap, placed anew
      active_->written = T_map_odom;
      return static_cast<int>(submaps_.size());
    }
  }
  return closeActiveLocked(T_map_odom);
}

int SubmapFusion::closeActiveLocked(const Eigen::Isometry3d& next_T_map_odom) {
  auto closed = std::make_unique<Submap>();
  closed->id = static_cast<int>(submaps_.size());
  closed->written = closed->placed = active_->written;
  {
    std::lock_guard<std::mutex> info(active_->info_mutex);
    closed->start = active_->start;
    closed->end = active_->end;
    closed->bounds = blockBox(active_->lo, active_->hi, map_->resolution());
  }
  auto next = std::make_unique<ActiveWrites>(next_T_map_odom);
  map_->setWriteWatcher(next.get(), [&](const VoxelMap::BlockReader& read) {
    VoxelBlock after, changes;
    for (const auto& entry : active_->before) {
      if (!read(unpackKey3(entry.first), &after)) after = VoxelBlock();
      if (logOddsChanges(*entry.second, after, &changes) == 0) continue;
      StoredBlock stored = StoredBlock::newDense();
      *stored.dense() = changes;
      stored.settle(VoxelMap::kMaxSparseBricks);
      closed->bytes += stored.bytes();
      closed->changes.emplace(entry.first, std::move(stored));
    }
  });
  active_ = std::move(next);
  submaps_.push_back(std::move(closed));
  addCoverage(static_cast<int>(submaps_.size()) - 1);
  return static_cast<int>(submaps_.size());
}

std::vector<std::uint64_t> SubmapFusion::footprint(const Submap& submap) const {
  std::vector<std::uint64_t> keys;
  keys.reserve(submap.changes.size());
  if (submap.atWrittenPlace()) {
    for (const auto& entry : submap.changes) keys.push_back(entry.first);
    return keys;
  }
  // Each changed block's corners moved: the blocks of their bounding box.
  const Eigen::Isometry3d moved = submap.placed * submap.written.inverse();
  const double side = map_->resolution() * VoxelBlock::kSide;
  SpatialKeySet reached;
  for (const auto& entry : submap.changes) {
    const BlockIndex block = unpackKey3(entry.first);
    const Eigen::AlignedBox3d box = blockBox(block, block, map_->resolution());
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3d corner =
          moved * box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i));
      lo = lo.cwiseMin(corner);
      hi = hi.cwiseMax(corner);
    }
    const BlockIndex from = floorBlock(lo, side), to = floorBlock(hi, side);
    for (int z = from.z(); z <= to.z(); ++z) {
      for (int y = from.y(); y <= to.y(); ++y) {
        for (int x = from.x(); x <= to.x(); ++x) reached.insert(packKey(BlockIndex(x, y, z)));
      }
    }
  }
  keys.assign(reached.begin(), reached.end());
  return keys;
}

void SubmapFusion::addCoverage(int index) {
  Submap& submap = *submaps_[static_cast<std::size_t>(index)];
  submap.footprint = footprint(submap);
  for (std::uint64_t key : submap.footprint) {
    std::vector<int>& covering = coverage_[key];
    covering.insert(std::upper_bound(covering.begin(), covering.end(), index), index);
  }
}

void SubmapFusion::removeCoverage(int index) {
  for (std::uint64_t key : submaps_[static_cast<std::size_t>(index)]->footprint) {
    auto it = coverage_.find(key);
    if (it == coverage_.end()) continue;
    std::vector<int>& covering = it.value();
    covering.erase(std::remove(covering.begin(), covering.end(), index), covering.end());
    if (covering.empty()) coverage_.erase(it);
  }
}

bool SubmapFusion::movesBeyondThreshold(const Submap& submap,
                                        const Eigen::Isometry3d& placed) const {
  return largestShift(submap.bounds, submap.written, submap.placed, placed) > min_shift_;
}

SubmapMoveResult SubmapFusion::place(const Placements& placements) {
  const auto start = std::chrono::steady_clock::now();
  SubmapMoveResult result;
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  const int active_id = static_cast<int>(submaps_.size());
  for (const auto& placement : placements) {
    // The active submap moves as a closed one: its next frames are written at the new place.
    if (placement.first != active_id) continue;
    std::unique_lock<std::mutex> info(active_->info_mutex);
    if (active_->blocks == 0) {
      active_->written = placement.second;
    } else if (largestShift(blockBox(active_->lo, active_->hi, map_->resolution()),
                            active_->written, active_->written, placement.second) > min_shift_) {
      info.unlock();
      closeActiveLocked(placement.second);
    }
    break;
  }
  frames.unlock();  // frames go on into the new active submap while the map is rebuilt
  SpatialKeySet touched;
  for (const auto& placement : placements) {
    if (placement.first < 0 || placement.first >= static_cast<int>(submaps_.size())) continue;
    Submap& submap = *submaps_[static_cast<std::size_t>(placement.first)];
    if (submap.fixed || !movesBeyondThreshold(submap, placement.second)) continue;
    touched.insert(submap.footprint.begin(), submap.footprint.end());
    removeCoverage(placement.first);
    submap.placed = placement.second;
    addCoverage(placement.first);
    touched.insert(submap.footprint.begin(), submap.footprint.end());
    ++result.moved;
  }
  rebuild(std::vector<std::uint64_t>(touched.begin(), touched.end()));
  result.blocks_rewritten = touched.size();
  result.seconds = secondsSince(start);
  return result;
}

void SubmapFusion::foldInto(const Submap& submap, const BlockIndex& block,
                            VoxelBlock* cells) const {
  const float min = map_->minLogOdds(), max = map_->maxLogOdds();
  VoxelBlock scratch;
  if (submap.atWrittenPlace()) {
    auto it = submap.changes.find(packKey(block));
    if (it != submap.changes.end()) addLogOddsChanges(it->second.view(&scratch), min, max, cells);
    return;
  }
  // Nearest cell: each voxel takes the change of the submap's cell under its centre.
  const Eigen::Isometry3d to_written = submap.written * submap.placed.inverse();
  const double resolution = map_->resolution();
  std::uint64_t cached_key = 0;
  const VoxelBlock* source = nullptr;
  bool cached = false;
  for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
    const Eigen::Vector3d center = map_->centerOf(VoxelMap::voxelIndex(block, linear));
    const VoxelIndex index = (to_written * center / resolution).array().floor().cast<int>();
    const std::uint64_t key = packKey(VoxelMap::blockOf(index));
    if (!cached || key != cached_key) {
      auto it = submap.changes.find(key);
      source = it == submap.changes.end() ? nullptr : &it->second.view(&scratch);
      cached_key = key;
      cached = true;
    }
    if (source == nullptr) continue;
    const float change = source->log_odds[VoxelMap::linearIndexInBlock(index)];
    cells->set(linear, addLogOddsChange(cells->log_odds[linear], change, min, max));
  }
}

void SubmapFusion::rebuild(const std::vector<std::uint64_t>& keys) {
  if (keys.empty()) return;
  // The closed submaps' sum, outside the map's lock: they change only under mutex_, held here.
  std::vector<VoxelBlock> sums(keys.size());
  const long count = static_cast<long>(keys.size());
#pragma omp parallel for schedule(dynamic, 8)
  for (long i = 0; i < count; ++i) {
    auto it = coverage_.find(keys[i]);
    if (it == coverage_.end()) continue;
    for (int index : it->second) {
      foldInto(*submaps_[static_cast<std::size_t>(index)], unpackKey3(keys[i]), &sums[i]);
    }
  }
  SpatialKeyMap<std::size_t> position;
  std::vector<BlockIndex> blocks;
  blocks.reserve(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    position.emplace(keys[i], i);
    blocks.push_back(unpackKey3(keys[i]));
  }
  const float min = map_->minLogOdds(), max = map_->maxLogOdds();
  // Under the map's lock: the active submap's writes so far stay on top of the new sum.
  map_->rewriteBlocks(blocks, [&](const BlockIndex& block, VoxelBlock& contents) {
    const VoxelBlock& sum = sums[position.at(packKey(block))];
    auto it = active_->before.find(packKey(block));
    if (it == active_->before.end()) {
      contents = sum;
      return;
    }
    VoxelBlock active_changes;
    logOddsChanges(*it->second, contents, &active_changes);
    *it.value() = sum;
    contents = sum;
    addLogOddsChanges(active_changes, min, max, &contents);
  });
}

std::vector<SubmapInfo> SubmapFusion::submaps() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<SubmapInfo> result;
  for (const auto& submap : submaps_) {
    SubmapInfo info;
    info.id = submap->id;
    info.fixed = submap->fixed;
    info.start_stamp = submap->start;
    info.end_stamp = submap->end;
    info.written = submap->written;
    info.placed = submap->placed;
    info.blocks = submap->changes.size();
    info.bytes = submap->bytes;
    info.bounds = submap->bounds;
    result.push_back(info);
  }
  SubmapInfo active;
  active.id = static_cast<int>(submaps_.size());
  active.active = true;
  {
    std::lock_guard<std::mutex> info(active_->info_mutex);
    active.start_stamp = active_->start;
    active.end_stamp = active_->end;
    active.blocks = active_->blocks;
    active.bounds = blockBox(active_->lo, active_->hi, map_->resolution());
    active.written = active.placed = active_->written;
  }
  active.bytes = active.blocks * sizeof(VoxelBlock);
  result.push_back(active);
  return result;
}

int SubmapFusion::activeSubmap() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(submaps_.size());
}

std::size_t SubmapFusion::memoryBytes() const {
  std::size_t bytes = 0;
  for (const SubmapInfo& info : submaps()) bytes += info.bytes;
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& entry : coverage_)
    bytes += sizeof(entry) + entry.second.capacity() * sizeof(int);
  return bytes;
}

void SubmapFusion::reset() {
  std::unique_lock<std::shared_mutex> frames(frames_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  auto next = std::make_unique<ActiveWrites>(active_->written);
  map_->setWriteWatcher(next.get());
  map_->reset();
  active_ = std::move(next);
  submaps_.clear();
  coverage_.clear();
}

}  // namespace occupancy_fusion
