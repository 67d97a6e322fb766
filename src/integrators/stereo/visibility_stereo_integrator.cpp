#include "occupancy_fusion/integrators/stereo/visibility_stereo_integrator.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <stdexcept>

#include "frame_rays.h"
#include "occupancy_fusion/integrators/ray_traversal.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "ray_bundles.h"
#include "span_schedule.h"

namespace occupancy_fusion {

// ---------------------------------------------------------------------------------------------
// The equations (Eq. 3-8)

NormalCdfTable::NormalCdfTable() : values_(kSize + 1) {
  for (int i = 0; i < kSize; ++i) {
    const double x = -kRange + i / kScale;
    values_[i] = 0.5 * std::erfc(-x / std::sqrt(2.0));
  }
  values_[kSize] = values_[kSize - 1];  // read by operator() only with fraction 0
}

namespace {
// Wall time between laps.
class Stopwatch {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return seconds;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// Eq. 3, here so that the ray caster's every step inlines it (an exported function of a shared
// library is called through the PLT).
inline double visibilityAfter(double previous, double p_occluded,
                              const VisibilityStereoConfig& config) {
  // P(V_i | not V_i-1) = 0 leaves only the terms conditioned on a visible predecessor.
  const double visibility = previous * (config.prob_visible_if_occluded * p_occluded +
                                        config.prob_visible_if_not_occluded * (1.0 - p_occluded));
  return visibility >= config.visibility_max ? 1.0 : visibility;
}
}  // namespace

double nextVisibility(double previous, double p_occluded, const VisibilityStereoConfig& config) {
  return visibilityAfter(previous, p_occluded, config);
}

double occupancyAfterMeasurement(double p_occupied, bool hit, double visibility,
                                 const VisibilityStereoConfig& config) {
  // Likelihoods of the measurement M (a hit or a miss) under each state of Fig.
  // 2b.
  auto likelihood = [hit](double p_hit) { return hit ? p_hit : 1.0 - p_hit; };
  const double m_invisible = likelihood(config.prob_hit_invisible);
  const double m_occupied = likelihood(config.prob_hit_visible_occupied);
  const double m_free = likelihood(config.prob_hit_visible_free);
  const double m_given_occupied = m_invisible * (1.0 - visibility) + m_occupied * visibility;  // 5
  const double m_total = m_invisible * (1.0 - visibility) +
                         visibility * (m_occupied * p_occupied + m_free * (1.0 - p_occupied));  // 6
  return m_given_occupied * p_occupied / m_total;  // Eq. 4
}

double occupancyAfterInterpolatedMeasurement(double p_occupied, double p_inside, double visibility,
                                             const VisibilityStereoConfig& config) {
  const double after_hit = occupancyAfterMeasurement(p_occupied, true, visibility, config);
  const double after_miss = occupancyAfterMeasurement(p_occupied, false, visibility, config);
  return p_inside * after_hit + (1.0 - p_inside) * after_miss;  // Eq. 8
}

// ---------------------------------------------------------------------------------------------
// Ray casting

namespace {

// 512 values a block (one per voxel) for the blocks a frame reaches, each block's array found by
// hash once for a run of look-ups inside it. Blocks are keyed relative to the frame's origin
// block: rays reach less than half packKey's exact range from the sensor (rayTargetOf), so every
// key of a frame is distinct however far the sensor is from the map's origin.
template <typename Value>
class FrameBlockTable {
 public:
  explicit FrameBlockTable(Value initial) : initial_(initial) {}
  // The voxel's value, `initial` until written.
  Value& at(const VoxelIndex& voxel, const BlockIndex& origin_block) {
    return values(VoxelMap::blockOf(voxel), origin_block)[VoxelMap::linearIndexInBlock(voxel)];
  }
  // The blocks in the order they were first written, and by that number their 512 values (by
  // VoxelMap::linearIndexInBlock); numberOf: kNone where the block has none.
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  const std::vector<BlockIndex>& blocks() const { return block_indices_; }
  const Value* valuesOf(std::uint32_t number) const { return blocks_[number].data(); }
  std::uint32_t numberOf(const BlockIndex& block, const BlockIndex& origin_block) const {
    const BlockIndex offset = block - origin_block;
    if ((offset.array().abs() < kNearReach).all()) return near_numbers_[nearSlot(offset)];
    const auto it = block_numbers_.find(packKey(offset));
    return it == block_numbers_.end() ? kNone : it->second;
  }

 private:
  Value* values(const BlockIndex& block, const BlockIndex& origin_block) {
    if (last_ != nullptr && block == last_block_) return last_;
    const BlockIndex offset = block - origin_block;
    std::uint32_t* number = nullptr;
    if ((offset.array().abs() < kNearReach).all()) {
      number = &near_numbers_[nearSlot(offset)];
      if (*number == kNone) *number = newBlock(block);
    } else {
      const auto [it, inserted] = block_numbers_.try_emplace(packKey(offset), 0u);
      if (inserted) it.value() = newBlock(block);
      number = &it.value();
    }
    last_block_ = block;
    last_ = blocks_[*number].data();
    return last_;
  }
  std::uint32_t newBlock(const BlockIndex& block) {
    blocks_.emplace_back().fill(initial_);
    block_indices_.push_back(block);
    return static_cast<std::uint32_t>(blocks_.size() - 1);
  }
  // Blocks within kNearReach - 1 of the origin's block, along every axis, are numbered in a dense
  // cube: most of a frame's block look-ups without a hash.
  static constexpr int kNearReach = 8, kNearEdge = 2 * kNearReach - 1;
  static std::size_t nearSlot(const BlockIndex& offset) {
    return (static_cast<std::size_t>(offset.z() + kNearReach - 1) * kNearEdge +
            (offset.y() + kNearReach - 1)) *
               kNearEdge +
           (offset.x() + kNearReach - 1);
  }

  Value initial_;
  std::vector<std::uint32_t> near_numbers_ =
      std::vector<std::uint32_t>(kNearEdge * kNearEdge * kNearEdge, kNone);
  SpatialKeyMap<std::uint32_t> block_numbers_;                 // block key -> position in blocks_
  std::deque<std::array<Value, VoxelBlock::kVolume>> blocks_;  // growing it moves no array
  std::vector<BlockIndex> block_indices_;                      // per position in blocks_
  BlockIndex last_block_ = BlockIndex::Zero();
  Value* last_ = nullptr;
};

// The frame's updates, one entry per voxel, reduced on insertion. Entries live
// in a vector so that the previous-ray cache can keep their positions. A voxel finds its entry
// through its block: a table of the block's 512 entry numbers, found by hash once for the run
// of steps a ray takes inside the block (a hash look-up per voxel, with its probes, was a fifth
// of a frame's time at 0.05 m).
class alignas(64) FrameUpdates {  // per thread, side by side: no shared cache line
 public:
  void reserve(std::size_t voxels) {
    entries_.reserve(voxels);
    readings_.reserve(voxels);
  }
  std::uint32_t findOrInsert(const VoxelIndex& index, const VoxelIndex& origin) {
    std::uint32_t& slot = slots_.at(index, VoxelMap::blockOf(origin));
    if (slot == kNoEntry) {
      slot = static_cast<std::uint32_t>(entries_.size());
      entries_.push_back({index, 0.0f, 0.0f});
      readings_.push_back({kNotComputed, kNotComputed, kNotComputed});
    }
    return slot;
  }
  // What a walk reads of the entry's voxel besides the map: each depends only on the voxel, the
  // sensor's voxel, the map before the frame and the frame's measurement, and rays that are not
  // neighbours (bundle_rays) reach the same voxel many times past the previous-ray cache.
  struct Reading {
    float occlusion;            // Eq. 1's local occlusion
    float measured_visibility;  // the frame's own visibility of the voxel (1: none)
    float inside_cap;           // the bound on its P(I_v), applied by capInside() (NaN: none)
  };
  // The entry's reading, made by read(&update, &reading) on its first request, which also sets
  // the update's prior where the measurement gives one (Eq. 4-6 of a never-observed voxel).
  template <typename Read>
  const Reading& readOnce(std::uint32_t entry, Read&& read) {
    Reading& reading = readings_[entry];
    if (std::isnan(reading.occlusion)) read(&entries_[entry], &reading);
    return reading;
  }
  // P(I_v) of every entry at most its measured bound: min(max over rays, bound) as the bound
  // applied after the reduction.
  void capInside() {
    for (std::uint32_t i = 0; i < entries_.size(); ++i) entries_[i] = cappedEntry(i);
  }
  // Reduction to one update per voxel: the largest P(I_v) (a hit wins over a
  // miss, as in OctoMap) and the largest visibility (see reduce()).
  void reduce(std::uint32_t entry, float p_inside, float visibility, bool passed = false) {
    reduceInto(&entries_[entry], p_inside, visibility, passed);
  }
  static void reduceInto(StereoVoxelUpdate* update, float p_inside, float visibility,
                         bool passed = false) {
    update->p_inside = std::max(update->p_inside, p_inside);
    update->visibility = std::max(update->visibility, visibility);
    update->passed = update->passed || passed;
  }
  void merge(const FrameUpdates& other, const VoxelIndex& origin) {
    for (std::size_t i = 0; i < other.entries_.size(); ++i) {
      const StereoVoxelUpdate& theirs = other.entries_[i];
      const std::size_t known = entries_.size();
      const std::uint32_t entry = findOrInsert(theirs.index, origin);
      if (entry >= known) {  // new here: the other thread's measurement of it (the same voxel's)
        entries_[entry].prior = theirs.prior;
        readings_[entry].inside_cap = other.readings_[i].inside_cap;
      }
      reduce(entry, theirs.p_inside, theirs.visibility, theirs.passed);
    }
  }
  std::vector<StereoVoxelUpdate>& entries() { return entries_; }

  // By block, for writing the map straight from the threads' tables (writeThreadUpdates).
  static constexpr std::uint32_t kNoEntry = std::numeric_limits<std::uint32_t>::max();
  using Slots = FrameBlockTable<std::uint32_t>;
  const Slots& slots() const { return slots_; }
  // The entry's update with the bound on its P(I_v) applied (as capInside()).
  StereoVoxelUpdate cappedEntry(std::uint32_t entry) const {
    StereoVoxelUpdate update = entries_[entry];
    const float cap = readings_[entry].inside_cap;
    if (cap < update.p_inside) update.p_inside = cap;
    return update;
  }
  // Per block number of slots(): whether an entry there was updated (visibility > 0).
  std::vector<char> updatedBlocks(const BlockIndex& origin_block) const {
    std::vector<char> updated(slots_.blocks().size(), 0);
    for (const StereoVoxelUpdate& update : entries_) {
      if (update.visibility > 0)
        updated[slots_.numberOf(VoxelMap::blockOf(update.index), origin_block)] = 1;
    }
    return updated;
  }

 private:
  static constexpr float kNotComputed = std::numeric_limits<float>::quiet_NaN();

  FrameBlockTable<std::uint32_t> slots_{kNoEntry};  // voxel -> its entry
  std::vector<StereoVoxelUpdate> entries_;
  std::vector<Reading> readings_;  // per entry; occlusion kNotComputed until read
};

// Read access to the map for one thread and frame: blocks are copied once
// (under the map's shared lock) and then read without locking; the map is not
// written during ray casting.
class MapSnapshot {
 public:
  explicit MapSnapshot(const VoxelMap& map) : map_(map) {}

  // The voxel's log-odds, or NaN when it was never observed.
  float logOdds(const VoxelIndex& index) {
    constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();
    const VoxelBlock* copy = find(VoxelMap::blockOf(index));
    if (copy == nullptr) return kUnknown;
    const float value = copy->log_odds[VoxelMap::linearIndexInBlock(index)];
    return VoxelBlock::isKnown(value) ? value : kUnknown;
  }

 private:
  const VoxelBlock* find(const BlockIndex& block) {
    const std::uint64_t key = packKey(block);
    if (last_valid_ && key == last_key_) return last_;
    auto it = blocks_.find(key);
    if (it == blocks_.end()) {
      auto copy = std::make_unique<VoxelBlock>();
      if (!map_.copyBlock(block, copy.get())) copy.reset();
      it = blocks_.emplace(key, std::move(copy)).first;
    }
    last_valid_ = true;
    last_key_ = key;
    last_ = it->second.get();
    return last_;
  }

  const VoxelMap& map_;
  SpatialKeyMap<std::unique_ptr<VoxelBlock>> blocks_;
  bool last_valid_ = false;
  std::uint64_t last_key_ = 0;
  const VoxelBlock* last_ = nullptr;
};

// unknown_neighbours: measured: the frame's measured surface read at voxels. A voxel's depth z
// (its centre's, along the optical axis) against the surface depth z_s on its line of sight, with
// Eq. 7's sigma_z of z_s kept within [sigma_min, sigma_max].
struct FrameMeasurement {
  const MeasuredSurface* surface;  // null: no measurement (every read is false)
  double lambda;                   // Eq. 7: sigma_z = lambda z^2
  const NormalCdfTable* phi;
  double resolution;
  double sigma_min, sigma_max;  // m
  double face_offset;           // m, from a voxel's centre to its front and back along the depth
  double border_reach;          // m, half a voxel's diagonal: centres this far outside the image
                                // belong to voxels that rays through its border pixels cross

  struct Depth {
    double z, z_surface, sigma;
    // P(the measured surface lies in front of depth z + offset).
    double surfaceInFront(double offset, const NormalCdfTable& cdf) const {
      return cdf((z + offset - z_surface) / sigma);
    }
  };
  // False where the image does not say (outside it, behind the camera, no surface near).
  bool depthOf(const VoxelIndex& voxel, Depth* depth) const {
    if (surface == nullptr) return false;
    const Eigen::Vector3d center = (voxel.cast<double>().array() + 0.5) * resolution;
    if (!surface->depthAt(center, &depth->z, &depth->z_surface, border_reach)) return false;
    depth->sigma = std::clamp(lambda * depth->z_surface * depth->z_surface, sigma_min, sigma_max);
    return true;
  }
};

// One thread's reads of the frame's measurement, each voxel's made once: a voxel is read as the
// neighbour of up to three others (Eq. 1), for its own visibility and for its own update's prior
// and P(I_v) bound, each read a projection into the image and a read of the surface grid.
class MeasurementMemo {
 public:
  MeasurementMemo(const FrameMeasurement& measurement, const VoxelIndex& origin)
      : measurement_(measurement), origin_block_(VoxelMap::blockOf(origin)) {}

  struct Reading {
    float log_odds;  // logit of P(O), unclamped (+inf where P(O) = 1); NaN: the image does not say
    float visibility;   // 1 - P(the surface lies in front of the voxel's front); NaN: not read yet
    float in_front;     // P(the surface lies in front of the voxel's centre), that is P(O)
    float behind_back;  // P(the surface lies in front of the voxel's back)
    bool says() const { return !std::isnan(log_odds); }
  };

  // logit of P(O) by the measurement (the surface lies in front of the voxel's centre),
  // unclamped (+inf where P(O) = 1); NaN where the image does not say.
  float occupancyLogOdds(const VoxelIndex& voxel) { return readingOf(voxel).log_odds; }
  // Visible while the surface lies behind the voxel's front; 1 where the image does not say.
  float visibility(const VoxelIndex& voxel) { return readingOf(voxel).visibility; }

  const Reading& readingOf(const VoxelIndex& voxel) {
    Reading& reading = readings_.at(voxel, origin_block_);
    if (std::isnan(reading.visibility)) {
      FrameMeasurement::Depth depth;
      if (measurement_.depthOf(voxel, &depth)) {
        const NormalCdfTable& phi = *measurement_.phi;
        const double in_front = depth.surfaceInFront(0.0, phi);
        reading.log_odds = logit(in_front);
        reading.visibility =
            static_cast<float>(1.0 - depth.surfaceInFront(-measurement_.face_offset, phi));
        reading.in_front = static_cast<float>(in_front);
        reading.behind_back =
            static_cast<float>(depth.surfaceInFront(measurement_.face_offset, phi));
      } else {
        reading = {kNotRead, 1.0f, kNotRead, kNotRead};
      }
    }
    return reading;
  }

 private:
  static constexpr float kNotRead = std::numeric_limits<float>::quiet_NaN();

  const FrameMeasurement& measurement_;
  BlockIndex origin_block_;
  FrameBlockTable<Reading> readings_{{kNotRead, kNotRead, kNotRead, kNotRead}};
};

// How Eq. 1 reads a neighbour (the paper's OctoMap has no node for a never-observed one; see
// UnknownNeighbours in the header).
struct NeighbourReading {
  bool ignore_unknown;                  // kKnownOnly: left out of the minimum
  float unknown_log_odds;               // kPrior: logit(unknown_neighbour_occupancy)
  const FrameMeasurement* measurement;  // kMeasured
  bool fuse_known;  // the measurement's evidence added to known neighbours' log-odds too
  float min_log_odds, max_log_odds;  // the map's clamping bounds

  // The neighbour's log-odds: the map's (NaN: never observed) with the measurement's.
  float read(const VoxelIndex& neighbour, float map_log_odds, MeasurementMemo* memo) const {
    const bool known = !std::isnan(map_log_odds);
    const float measured_log_odds = (known && !fuse_known) || measurement->surface == nullptr
                                        ? std::numeric_limits<float>::quiet_NaN()
                                        : memo->occupancyLogOdds(neighbour);
    if (std::isnan(measured_log_odds)) return known ? map_log_odds : unknown_log_odds;
    // Not clamped below: space the frame measures free, P(O) = 0, passes the visibility on
    // unchanged, as Eq. 3 does for q_max and above.
    const float measured = std::min(measured_log_odds, max_log_odds);
    if (!known) return measured;
    // The measurement's free-space evidence weighs at most as one clamped free voxel, so that a
    // surface the map knows well still occludes where the frame's median misses it (an object
    // smaller than the window, seen through a patch shifted away from the camera).
    return std::min(map_log_odds + std::max(measured, min_log_odds), max_log_odds);
  }
};

// Eq. 1: P(C_v) = min P(O) over the (up to three) neighbours behind the faces
// of v that face the sensor. A face is visible when the sensor lies beyond its
// plane: along an axis where the sensor shares v's slab, no face is visible and
// that neighbour is left out (the sensor's own voxel has none: P(C) = 0). With
// no neighbour left, nothing occludes v. min P(O) = sigmoid(min log-odds), one
// exp instead of three.
double localOcclusion(const VoxelIndex& voxel, const VoxelIndex& origin,
                      const NeighbourReading& reading, MapSnapshot* snapshot,
                      MeasurementMemo* memo) {
  float min_log_odds = std::numeric_limits<float>::infinity();
  bool any = false;
  for (int axis = 0; axis < 3; ++axis) {
    if (voxel[axis] == origin[axis]) continue;
    VoxelIndex neighbour = voxel;
    neighbour[axis] += voxel[axis] > origin[axis] ? -1 : 1;
    float value = snapshot->logOdds(neighbour);
    if (std::isnan(value) && reading.ignore_unknown) continue;
    value = reading.read(neighbour, value, memo);
    min_log_odds = std::min(min_log_odds, value);
    any = true;
  }
  return any ? probabilityFromLogOdds(min_log_odds) : 0.0;
}

// Sec. III-D: the voxels of the previous ray, by position on the ray, with
// their update entries and local occlusions. Neighbouring pixels' rays mostly
// cross the same voxels at the same positions, and those skip the hash table
// and the neighbour look-ups.
struct CachedVoxel {
  VoxelIndex index;
  std::uint32_t entry;
  float occlusion;
  float measured_visibility;  // 1 without a measurement
};

struct RayCounters {
  std::size_t voxel_visits = 0;
  std::size_t cache_hits = 0;
  std::size_t rays_invisible = 0;
};

struct FrameContext {
  const VisibilityStereoConfig& config;
  const NormalCdfTable& phi;
  Eigen::Vector3d origin;
  VoxelIndex origin_voxel;
  double resolution;
  NeighbourReading neighbours;
  const FrameMeasurement& measurement;
  bool measured_visibility;  // a voxel's visibility is at most the measurement's
  bool measured_updates;     // measured_prior or measured_inside, with a measurement
};

class RayCaster {
 public:
  RayCaster(const FrameContext& frame, MapSnapshot* snapshot, MeasurementMemo* memo,
            FrameUpdates* updates)
      : frame_(frame), snapshot_(snapshot), memo_(memo), updates_(updates) {}

  // The walk to `point`. bundle_rays (the visibility mode) passes the nearest point of the same
  // end voxel too: the rays to both cross the same voxels up to it, but for one at a corner now
  // and then, and the same voxels have the same visibility, so one walk carries both points'
  // P(I_v) (the reduction keeps the larger). Where `point` lies beyond max_range, the cut walk
  // carries no hit: the nearest point gets a walk of its own.
  void cast(const Eigen::Vector3d& point, double range_sigma,
            const Eigen::Vector3d* nearest = nullptr, double nearest_sigma = 0.0) {
    const Eigen::Vector3d offset = point - frame_.origin;
    const double range = offset.norm();
    const double max_range = frame_.config.max_range;
    const bool clipped = max_range >= 0 && range > max_range;
    if (clipped && nearest != nullptr) cast(*nearest, nearest_sigma);
    current_.clear();
    if (clipped) {
      castClipped(frame_.origin + offset * (max_range / range), range, range_sigma);
    } else if (frame_.config.method == StereoIntegrationMethod::kOctomap) {
      castOctomap(point);
    } else {
      const InsideOfPoint near =
          nearest != nullptr ? InsideOfPoint(*nearest, nearest_sigma, frame_) : InsideOfPoint();
      castVisibility(point, range_sigma, near);
    }
    std::swap(previous_, current_);
  }
  const RayCounters& counters() const { return counters_; }

 private:
  // The voxel at position j of the current ray, through the cache when the
  // previous ray had the same voxel there.
  const CachedVoxel& lookUp(const VoxelIndex& index, std::size_t j, bool need_occlusion) {
    ++counters_.voxel_visits;
    if (j < previous_.size() && previous_[j].index == index) {
      ++counters_.cache_hits;
      current_.push_back(previous_[j]);
    } else {
      const std::uint32_t entry = updates_->findOrInsert(index, frame_.origin_voxel);
      if (!need_occlusion) {
        current_.push_back({index, entry, 0.0f, 1.0f});
        return current_.back();
      }
      const FrameUpdates::Reading& reading =
          updates_->readOnce(entry, [&](StereoVoxelUpdate* update, FrameUpdates::Reading* read) {
            read->occlusion = static_cast<float>(
                localOcclusion(index, frame_.origin_voxel, frame_.neighbours, snapshot_, memo_));
            read->measured_visibility =
                frame_.measured_visibility ? memo_->visibility(index) : 1.0f;
            if (frame_.measured_updates) measureUpdate(index, update, &read->inside_cap);
          });
      current_.push_back({index, entry, reading.occlusion, reading.measured_visibility});
    }
    return current_.back();
  }

  // measured_prior: a never-observed voxel's prior of Eq. 4-6 from the frame's measurement, where
  // it says less than unknown_occupancy. measured_inside: P(I_v) of Eq. 8 at most P(the measured
  // surface lies in front of the voxel's back).
  void measureUpdate(const VoxelIndex& index, StereoVoxelUpdate* update, float* inside_cap) {
    *inside_cap = std::numeric_limits<float>::infinity();
    const MeasurementMemo::Reading& reading = memo_->readingOf(index);
    if (!reading.says()) return;
    const VisibilityStereoConfig& config = frame_.config;
    if (config.measured_inside) *inside_cap = reading.behind_back;
    if (config.measured_prior && std::isnan(snapshot_->logOdds(index))) {
      update->prior = std::min(static_cast<float>(config.unknown_occupancy), reading.in_front);
    }
  }

  // measured_visibility: at most the frame's own visibility of the voxel (q_max counts as 1).
  double limitByMeasurement(double visibility, const CachedVoxel& voxel) const {
    const double measured =
        voxel.measured_visibility >= frame_.config.visibility_max ? 1.0 : voxel.measured_visibility;
    return std::min(visibility, measured);
  }

  // OctoMap's rays: misses up to the end voxel, a hit in it (as
  // PointCloudIntegrator).
  void castOctomap(const Eigen::Vector3d& point) {
    RayTraversal ray(frame_.origin, point, frame_.resolution);
    for (std::size_t j = 0;; ++j) {
      const bool at_end = ray.atEnd();
      updates_->reduce(lookUp(ray.current(), j, false).entry, at_end ? 1.0f : 0.0f, 1.0f);
      if (at_end) return;
      ray.stepTowardsEnd();
    }
  }

  // The voxel's centre, from the sensor.
  Eigen::Vector3d centreFromOrigin(const VoxelIndex& index) const {
    const Eigen::Vector3d center = (index.cast<double>().array() + 0.5) * frame_.resolution;
    return center - frame_.origin;
  }

  // P(I_v) of Sec. III-C: the voxel reduced to its centre (centre_from_origin), at distance s
  // along the ray from the sensor, against a point at distance range with standard deviation
  // range_sigma.
  static double insideProbability(const Eigen::Vector3d& centre_from_origin,
                                  const Eigen::Vector3d& direction, double range,
                                  double range_sigma, const NormalCdfTable& phi) {
    const double s = centre_from_origin.dot(direction);
    if (range_sigma > 0) return phi((s - range) / range_sigma);
    return s >= range ? 1.0 : 0.0;
  }

  // A point beyond max_range, as OctoMap's insertPointCloud treats it: the ray up to max_range
  // (the voxel holding the cut left out) is updated as a miss and nothing as a hit. In the
  // visibility mode the voxels keep Eq. 3's visibility and Eq. 8's P(I_v) from the measured
  // range (about 0 unless the point lies within a few sigma of the cut); no full hit.
  void castClipped(const Eigen::Vector3d& cut, double range, double range_sigma) {
    const bool octomap = frame_.config.method == StereoIntegrationMethod::kOctomap;
    const Eigen::Vector3d direction = (cut - frame_.origin).normalized();
    RayTraversal ray(frame_.origin, cut, frame_.resolution);
    double visibility = 1.0;
    for (std::size_t j = 0; ray.beforeEnd(); ++j, ray.stepTowardsEnd()) {
      const CachedVoxel& voxel = lookUp(ray.current(), j, !octomap);
      if (octomap) {
        updates_->reduce(voxel.entry, 0.0f, 1.0f);
        continue;
      }
      visibility = visibilityAfter(visibility, voxel.occlusion, frame_.config);  // Eq. 3
      visibility = limitByMeasurement(visibility, voxel);
      if (visibility < frame_.config.visibility_min) {
        ++counters_.rays_invisible;
        return;
      }
      const double p_inside = insideProbability(centreFromOrigin(voxel.index), direction, range,
                                                range_sigma, frame_.phi);
      updates_->reduce(voxel.entry, static_cast<float>(p_inside), static_cast<float>(visibility));
    }
  }

  // A point's Eq. 8 along a walk: P(I_v) until the voxel where it reaches the stop value (Sec.
  // III-C), which gets a full hit, and none after it.
  class InsideOfPoint {
   public:
    InsideOfPoint() = default;  // no point: adds nothing
    InsideOfPoint(const Eigen::Vector3d& point, double range_sigma, const FrameContext& frame)
        : range_sigma_(range_sigma), stop_(frame.config.inside_stop_probability), open_(true) {
      const Eigen::Vector3d offset = point - frame.origin;
      range_ = offset.norm();
      direction_ = offset / range_;
      // phi's argument (s - range) / sigma lies below -kRange, where phi is 0, for s below this
      // (the margins outweigh the rounding of the subtraction and the division).
      zero_before_ = range_ - (NormalCdfTable::kRange + 1e-3) * range_sigma_ - 1e-9 * range_;
    }
    bool open() const { return open_; }
    // Whether a voxel (its centre, its half diagonal) lies wholly more than `sigmas` range sigmas
    // in front of the point.
    bool clearlyBefore(const Eigen::Vector3d& centre_from_origin, double half_diagonal,
                       double sigmas) const {
      return open_ &&
             centre_from_origin.dot(direction_) + half_diagonal < range_ - sigmas * range_sigma_;
    }
    double farthestReach() const { return open_ ? range_ + 6.0 * range_sigma_ : 0.0; }  // m
    double next(const Eigen::Vector3d& centre_from_origin, const NormalCdfTable& phi) {
      if (!open_) return 0.0;
      // Most of a walk lies far in front of its point: P(I_v) = 0 there without the division.
      if (centre_from_origin.dot(direction_) < zero_before_) return 0.0;
      const double p_inside =
          insideProbability(centre_from_origin, direction_, range_, range_sigma_, phi);
      if (p_inside < stop_) return p_inside;
      open_ = false;
      return 1.0;  // the one further voxel with a full hit
    }

   private:
    Eigen::Vector3d direction_ = Eigen::Vector3d::Zero();
    double range_ = 0, range_sigma_ = 0, stop_ = 1, zero_before_ = 0;
    bool open_ = false;
  };

  // Eq. 1-3 and 8 along one ray, with the P(I_v) of `near`, a second point on (nearly) the same
  // ray, where it has one (cast).
  void castVisibility(const Eigen::Vector3d& point, double range_sigma, InsideOfPoint near) {
    const FrameContext& f = frame_;
    InsideOfPoint far(point, range_sigma, f);
    RayTraversal ray(f.origin, point, f.resolution);
    // The walk ends where P(I_v) reaches the stop value, at the latest ~2.4
    // sigma past the point; the bound only guards against rounding.
    const double reach = std::max(far.farthestReach(), near.farthestReach());
    const std::size_t max_steps = static_cast<std::size_t>(3 * reach / f.resolution + 8);
    double visibility = 1.0;
    const double half_diagonal = 0.5 * std::sqrt(3.0) * f.resolution;
    for (std::size_t j = 0; j < max_steps; ++j) {
      const CachedVoxel& voxel = lookUp(ray.current(), j, true);
      const Eigen::Vector3d centre = centreFromOrigin(voxel.index);
      // clear_passed: the frame saw through a voxel well in front of the nearer point.
      const bool passed =
          f.config.clear_passed &&
          (near.open() ? near : far).clearlyBefore(centre, half_diagonal, f.config.passed_sigmas);
      if (!passed) visibility = visibilityAfter(visibility, voxel.occlusion, f.config);  // Eq. 3
      visibility = limitByMeasurement(visibility, voxel);
      if (visibility < f.config.visibility_min) {
        ++counters_.rays_invisible;
        return;
      }
      const double p_inside = std::max(far.next(centre, f.phi), near.next(centre, f.phi));
      updates_->reduce(voxel.entry, static_cast<float>(p_inside), static_cast<float>(visibility),
                       passed);
      if (!far.open() && !near.open()) return;
      ray.next();
    }
  }

  const FrameContext& frame_;
  MapSnapshot* snapshot_;
  MeasurementMemo* memo_;
  FrameUpdates* updates_;
  std::vector<CachedVoxel> previous_;
  std::vector<CachedVoxel> current_;
  RayCounters counters_;
};

// One voxel's reduced update written to its block: Eq. 4-8 from the block's value (or the
// update's prior where the voxel is unknown), or OctoMap's hit or miss.
class UpdateWriter {
 public:
  UpdateWriter(const VisibilityStereoConfig& config, const VoxelMap& map)
      : config_(config),
        octomap_(config.method == StereoIntegrationMethod::kOctomap),
        min_log_odds_(map.minLogOdds()),
        max_log_odds_(map.maxLogOdds()),
        hit_(map.model().hitLogOdds()),
        miss_(map.model().missLogOdds()),
        passed_miss_(static_cast<float>(logit(config.passed_miss_probability))) {}

  void write(const StereoVoxelUpdate& update, int linear, VoxelBlock* block) const {
    if (octomap_) {
      block->update(linear, update.p_inside >= 1.0f ? hit_ : miss_, min_log_odds_, max_log_odds_);
      return;
    }
    const float old_value = block->log_odds[linear];
    if (config_.clear_passed && update.passed && update.p_inside < 0.01f) {
      block->update(linear, passed_miss_, min_log_odds_, max_log_odds_);
      return;
    }
    const double p_unknown = update.prior >= 0 ? update.prior : config_.unknown_occupancy;
    const double p_old =
        VoxelBlock::isKnown(old_value) ? probabilityFromLogOdds(old_value) : p_unknown;
    const double p_new =
        occupancyAfterInterpolatedMeasurement(p_old, update.p_inside, update.visibility, config_);
    // Clamped like OctoMap, to the map's [clamp_min, clamp_max].
    block->set(linear, std::clamp(logit(p_new), min_log_odds_, max_log_odds_));
  }

 private:
  const VisibilityStereoConfig& config_;
  bool octomap_;
  float min_log_odds_, max_log_odds_, hit_, miss_, passed_miss_;
};

// The threads' updates written to the map block by block, each block on one thread, without
// merging the threads' tables first (a serial pass over every entry) or grouping the merged
// updates by block (a hash per update): a voxel's updates on several threads are reduced as
// merge() and capInside() would (the largest P(I_v) and visibility, the bound and the prior the
// same on every thread: they depend only on the voxel and the frame). Returns the voxels updated.
std::size_t writeThreadUpdates(const std::vector<FrameUpdates>& threads, const VoxelIndex& origin,
                               const Eigen::Vector3d& focus, const UpdateWriter& writer,
                               VoxelMap* map) {
  const BlockIndex origin_block = VoxelMap::blockOf(origin);
  const std::size_t count = threads.size();
  const int thread_count = static_cast<int>(count);
  std::vector<std::vector<char>> updated(count);
#pragma omp parallel for schedule(static, 1) num_threads(thread_count)
  for (int t = 0; t < thread_count; ++t) updated[t] = threads[t].updatedBlocks(origin_block);
  // Every block with an updated voxel, once (the first thread that has it lists it).
  std::vector<BlockIndex> blocks;
  for (std::size_t t = 0; t < count; ++t) {
    const std::vector<BlockIndex>& own = threads[t].slots().blocks();
    for (std::size_t n = 0; n < own.size(); ++n) {
      if (!updated[t][n]) continue;
      bool listed = false;
      for (std::size_t e = 0; e < t && !listed; ++e) {
        const std::uint32_t number = threads[e].slots().numberOf(own[n], origin_block);
        listed = number != FrameUpdates::Slots::kNone && updated[e][number];
      }
      if (!listed) blocks.push_back(own[n]);
    }
  }
  if (blocks.empty()) return 0;
  map->setFocus(focus);
  std::atomic<std::size_t> written{0};
  map->updateBlocks(blocks, [&](const BlockIndex& block_index, VoxelBlock& block) {
    std::vector<const std::uint32_t*> slots(count, nullptr);
    for (std::size_t t = 0; t < count; ++t) {
      const std::uint32_t number = threads[t].slots().numberOf(block_index, origin_block);
      if (number != FrameUpdates::Slots::kNone) slots[t] = threads[t].slots().valuesOf(number);
    }
    std::size_t here = 0;
    for (int linear = 0; linear < VoxelBlock::kVolume; ++linear) {
      StereoVoxelUpdate update;
      bool found = false;
      for (std::size_t t = 0; t < count; ++t) {
        if (slots[t] == nullptr || slots[t][linear] == FrameUpdates::kNoEntry) continue;
        const StereoVoxelUpdate theirs = threads[t].cappedEntry(slots[t][linear]);
        if (!found) {
          update = theirs;
          found = true;
          continue;
        }
        FrameUpdates::reduceInto(&update, theirs.p_inside, theirs.visibility, theirs.passed);
      }
      // A voxel looked up where the visibility fell below q_min was entered but never updated.
      if (!found || !(update.visibility > 0)) continue;
      writer.write(update, linear, &block);
      ++here;
    }
    written += here;
  });
  return written;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// VisibilityStereoIntegrator

VisibilityStereoIntegrator::VisibilityStereoIntegrator(const VisibilityStereoConfig& config)
    : config_(config), frame_rays_(std::make_unique<FrameRays>()) {
  config_.validate();
}

VisibilityStereoIntegrator::~VisibilityStereoIntegrator() = default;

StereoIntegrationStats VisibilityStereoIntegrator::computeUpdates(
    const std::vector<Eigen::Vector3f>& points_in_map, const std::vector<float>& range_sigmas,
    const Eigen::Vector3d& sensor_origin, const VoxelMap& map,
    std::vector<StereoVoxelUpdate>* updates, const MeasuredSurface* surface) const {
  if (range_sigmas.size() != points_in_map.size()) {
    throw std::invalid_argument("range_sigmas must have one entry per point");
  }
  return computeUpdates(points_in_map, range_sigmas, nullptr, 0, points_in_map.size(),
                        sensor_origin, map, updates, surface);
}

StereoIntegrationStats VisibilityStereoIntegrator::computeUpdates(
    const std::vector<Eigen::Vector3f>& points_in_map, const std::vector<float>& range_sigmas,
    const std::vector<RayTarget>* given_ends, int ray_columns, std::size_t point_count,
    const Eigen::Vector3d& sensor_origin, const VoxelMap& map,
    std::vector<StereoVoxelUpdate>* updates, const MeasuredSurface* surface,
    VoxelMap* write_to) const {
  updates->clear();
  StereoIntegrationStats stats;
  stats.points = point_count;
  if (!map.isInRange(sensor_origin)) {
    stats.skipped_points = stats.points;
    return stats;
  }
  const double resolution = map.resolution();
  // logit(0) = -inf and logit(1) = +inf order correctly in Eq. 1's minimum.
  const bool measured = config_.unknown_neighbours == UnknownNeighbours::kMeasured &&
                        surface != nullptr && !surface->empty();
  const FrameMeasurement measurement{
      measured ? surface : nullptr,
      measured ? config_.disparity.disparity_sigma_px / surface->focalBaseline() : 0.0,
      &phi_,
      resolution,
      config_.measured_sigma_min_voxels * resolution,
      config_.measured_sigma_max_voxels * resolution,
      0.5 * resolution,
      0.5 * std::sqrt(3.0) * resolution};
  const NeighbourReading neighbours{config_.unknown_neighbours == UnknownNeighbours::kKnownOnly,
                                    logit(config_.unknown_neighbour_occupancy),
                                    &measurement,
                                    config_.measured_fuse_known,
                                    map.minLogOdds(),
                                    map.maxLogOdds()};
  const FrameContext frame{config_,
                           phi_,
                           sensor_origin,
                           map.indexOf(sensor_origin),
                           resolution,
                           neighbours,
                           measurement,
                           measured && config_.measured_visibility,
                           measured && (config_.measured_prior || config_.measured_inside)};
  const bool visibility_mode = config_.method == StereoIntegrationMethod::kVisibility;
  std::size_t skipped = 0;
  std::vector<BundledRay> bundles;
  Stopwatch stopwatch;
  if (config_.bundle_rays) {
    if (given_ends != nullptr) {
      bundles = bundleRaysByEndVoxel(*given_ends, visibility_mode, &skipped);
      orderByImageTiles(ray_columns, &bundles);
    } else {
      const std::vector<RayTarget> ends =
          rayTargetsOf(points_in_map, range_sigmas, sensor_origin, resolution, visibility_mode);
      bundles = bundleRaysByEndVoxel(ends, visibility_mode, &skipped);
    }
  }
  stats.bundling_seconds = stopwatch.lap();
  // Without bundling every slot is a ray; its usability is checked in the parallel loop.
  const int count = static_cast<int>(config_.bundle_rays ? bundles.size() : points_in_map.size());
  // A thread for every 64 rays: a second thread's own tables and memo cost less than the walks
  // of 128 rays (Middlebury's quarter input, 0.1-0.2 m: 46-961 bundled rays a frame).
  const int threads = std::max(1, std::min(omp_get_max_threads(), count / 64));
  SpanSchedule schedule(count, threads, std::clamp(count / (16 * threads), 32, 256));
  std::vector<FrameUpdates> per_thread(threads);
  // Room for the frame's voxels up front: growing the table rehashes every entry several times.
  // On the Middlebury benchmark a bundled ray adds 5 to 8 voxels of its own.
  constexpr std::size_t kVoxelsPerRay = 8, kMaxReserved = std::size_t{1} << 16;
  for (FrameUpdates& updates : per_thread) {
    updates.reserve(std::min(kVoxelsPerRay * count / threads, kMaxReserved));
  }
  std::size_t visits = 0, hits = 0, invisible = 0;
#pragma omp parallel num_threads(threads) reduction(+ : skipped, visits, hits, invisible)
  {
    MapSnapshot snapshot(map);
    const int thread = omp_get_thread_num();
    MeasurementMemo memo(measurement, frame.origin_voxel);
    RayCaster caster(frame, &snapshot, &memo, &per_thread[thread]);
    int first = 0, last = 0;
    while (schedule.next(thread, &first, &last)) {
      for (int ray = first; ray < last; ++ray) {
        const std::uint32_t i =
            config_.bundle_rays ? bundles[ray].farthest : static_cast<std::uint32_t>(ray);
        Eigen::Vector3d point = points_in_map[i].cast<double>();
        const float sigma = range_sigmas[i];
        if (!config_.bundle_rays) {
          const RayTarget end = given_ends != nullptr
                                    ? (*given_ends)[i]
                                    : rayTargetOf(points_in_map[i], sigma, sensor_origin,
                                                  resolution, visibility_mode);
          if (!end.isPoint()) continue;
          if (!end.isUsable()) {
            ++skipped;
            continue;
          }
        }
        // discretize = true: OctoMap's bundled ray ends at the end voxel's centre.
        if (config_.bundle_rays && !visibility_mode) {
          point = (voxelIndexOf(point, resolution).cast<double>().array() + 0.5) * resolution;
        }
        if (config_.bundle_rays && bundles[ray].nearest != i) {
          const std::uint32_t n = bundles[ray].nearest;
          const Eigen::Vector3d nearest = points_in_map[n].cast<double>();
          caster.cast(point, sigma, &nearest, range_sigmas[n]);
        } else {
          caster.cast(point, sigma);
        }
      }
    }
    visits += caster.counters().voxel_visits;
    hits += caster.counters().cache_hits;
    invisible += caster.counters().rays_invisible;
  }
  stats.walk_seconds = stopwatch.lap();
  stats.skipped_points = skipped;
  stats.rays = config_.bundle_rays ? bundles.size() : point_count - skipped;
  stats.merged_points = stats.points - skipped - stats.rays;
  stats.voxel_visits = visits;
  stats.cache_hits = hits;
  stats.rays_invisible = invisible;
  if (write_to != nullptr) {
    stats.updated_voxels = writeThreadUpdates(per_thread, frame.origin_voxel, sensor_origin,
                                              UpdateWriter(config_, *write_to), write_to);
    stats.write_seconds = stopwatch.lap();
    return stats;
  }
  for (int t = 1; t < threads; ++t) per_thread[0].merge(per_thread[t], frame.origin_voxel);
  per_thread[0].capInside();
  *updates = std::move(per_thread[0].entries());
  // A voxel looked up where the visibility fell below q_min was entered but never updated.
  updates->erase(std::remove_if(updates->begin(), updates->end(),
                                [](const StereoVoxelUpdate& u) { return !(u.visibility > 0); }),
                 updates->end());
  stats.updated_voxels = updates->size();
  return stats;
}

void VisibilityStereoIntegrator::apply(const std::vector<StereoVoxelUpdate>& updates,
                                       VoxelMap* map) const {
  // Group the updates by block so that each block is written by one thread.
  SpatialKeyMap<std::vector<std::uint32_t>> by_block;
  std::vector<BlockIndex> blocks;
  for (std::uint32_t i = 0; i < updates.size(); ++i) {
    const BlockIndex block = VoxelMap::blockOf(updates[i].index);
    auto [it, inserted] = by_block.try_emplace(packKey(block));
    if (inserted) blocks.push_back(block);
    it.value().push_back(i);
  }
  const UpdateWriter writer(config_, *map);
  map->updateBlocks(blocks, [&](const BlockIndex& block_index, VoxelBlock& block) {
    for (std::uint32_t i : by_block.find(packKey(block_index))->second) {
      writer.write(updates[i], VoxelMap::linearIndexInBlock(updates[i].index), &block);
    }
  });
}

StereoIntegrationStats VisibilityStereoIntegrator::integrate(
    const std::vector<Eigen::Vector3f>& points_in_map, const std::vector<float>& range_sigmas,
    const Eigen::Vector3d& sensor_origin, VoxelMap* map, const MeasuredSurface* surface) const {
  const auto start = std::chrono::steady_clock::now();
  if (range_sigmas.size() != points_in_map.size()) {
    throw std::invalid_argument("range_sigmas must have one entry per point");
  }
  StereoIntegrationStats stats = integrateRays(points_in_map, range_sigmas, nullptr, 0,
                                               points_in_map.size(), sensor_origin, map, surface);
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

StereoIntegrationStats VisibilityStereoIntegrator::integrateRays(
    const std::vector<Eigen::Vector3f>& points_in_map, const std::vector<float>& range_sigmas,
    const std::vector<RayTarget>* ends, int ray_columns, std::size_t point_count,
    const Eigen::Vector3d& sensor_origin, VoxelMap* map, const MeasuredSurface* surface) const {
  std::vector<StereoVoxelUpdate> unused;
  return computeUpdates(points_in_map, range_sigmas, ends, ray_columns, point_count, sensor_origin,
                        *map, &unused, surface, map);
}

void VisibilityStereoIntegrator::disparityToMapPoints(const DisparityImageView& disparity,
                                                      const StereoCamera& camera,
                                                      const Eigen::Isometry3d& T_map_camera,
                                                      std::vector<Eigen::Vector3f>* points_in_map,
                                                      std::vector<float>* range_sigmas,
                                                      std::size_t* pixels_read,
                                                      std::size_t* dropped_uncertain) const {
  const StereoPoints camera_points = disparityToPoints(disparity, camera, config_.disparity);
  const Eigen::Isometry3f transform = T_map_camera.cast<float>();
  points_in_map->resize(camera_points.size());
  range_sigmas->resize(camera_points.size());
  for (std::size_t i = 0; i < camera_points.size(); ++i) {
    const Eigen::Vector3f& p = camera_points.points[i];
    (*points_in_map)[i] = transformPoint(transform, p);
    (*range_sigmas)[i] = rangeSigmaOf(p, camera_points.depth_sigmas[i]);
  }
  if (pixels_read != nullptr) *pixels_read = camera_points.pixels_read;
  if (dropped_uncertain != nullptr) *dropped_uncertain = camera_points.dropped_uncertain;
}

MeasuredSurface VisibilityStereoIntegrator::measuredSurface(const DisparityImageView& disparity,
                                                            const StereoCamera& camera,
                                                            const Eigen::Isometry3d& T_map_camera,
                                                            double voxel_size_m) const {
  if (config_.unknown_neighbours != UnknownNeighbours::kMeasured ||
      config_.method != StereoIntegrationMethod::kVisibility) {
    return {};
  }
  // The grid stays at grid_step_px when the rays are cast from every 2nd or 4th pixel: on an
  // 8 px grid at half input the corridor matrix's 0.05 m cells lost 0.05 of coverage and had 1.2x
  // the false-occupied voxels (docs/disparity_method.md, "Moving camera").
  const DisparityConversionConfig& conversion = config_.disparity;
  SurfaceGridScale scale;
  scale.voxel_size_m = voxel_size_m;
  // disparityToPoints drops d < sigma_d / max_depth_sigma_ratio (sigma_z / z = sigma_d / d).
  scale.min_disparity_px = conversion.min_disparity_px;
  if (conversion.max_depth_sigma_ratio > 0) {
    scale.min_disparity_px = std::max(
        scale.min_disparity_px, conversion.disparity_sigma_px / conversion.max_depth_sigma_ratio);
  }
  scale.max_range_m = config_.max_range;
  return MeasuredSurface(disparity, camera, T_map_camera, config_.measured_surface, scale);
}

StereoIntegrationStats VisibilityStereoIntegrator::integrate(const DisparityImageView& disparity,
                                                             const StereoCamera& camera,
                                                             const Eigen::Isometry3d& T_map_camera,
                                                             VoxelMap* map) const {
  const auto start = std::chrono::steady_clock::now();
  const std::unique_lock<std::mutex> kept(frame_rays_mutex_, std::try_to_lock);
  FrameRays own_rays;
  FrameRays& rays = kept.owns_lock() ? *frame_rays_ : own_rays;
  MeasuredSurface surface;
  // Bad input throws here: an exception must not leave an OpenMP region.
  disparity.validate();
  camera.validate();
  const bool visibility_mode = config_.method == StereoIntegrationMethod::kVisibility;
  // The pixels' rows and the measured surface's rows as tasks of one team: both threads work on
  // both, with one region's start-up, and the surface's serial parts (its grid step, its sample
  // lattice) run while the other thread converts rows. (The conversion as one task beside the
  // surface's rows would leave its own row tasks to one thread: a thread waiting for its children
  // does not take their children.)
  Stopwatch stopwatch;
#pragma omp parallel
#pragma omp single
  {
    convertFrameRays(
        disparity, camera, config_.disparity, T_map_camera, map->resolution(), visibility_mode,
        &rays,
        [&] { surface = measuredSurface(disparity, camera, T_map_camera, map->resolution()); });
  }
  const double conversion_seconds = stopwatch.lap();
  StereoIntegrationStats stats =
      integrateRays(rays.points, rays.range_sigmas, &rays.ends, rays.columns, rays.points_count,
                    T_map_camera.translation(), map, &surface);
  stats.conversion_seconds = conversion_seconds;
  stats.dropped_uncertain = rays.dropped_uncertain;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

}  // namespace occupancy_fusion
