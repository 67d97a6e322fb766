// Submaps of a VoxelMap and its laser layer that can be moved after they were written: what lets
// the map follow a SLAM system's loop closures.
//
// The mappers write the fused map (the VoxelMap and GridLayer2D every topic, file and checkpoint
// reads) as they always have, with frames placed in the map by T_map_odom * T_odom_sensor, where
// T_map_odom is the placement of the submap being written (the active one; fixed while it is
// written, so its frames are placed by odometry alone, smooth and locally consistent). The fusion
// watches those writes (setWriteWatcher): when a submap is closed, what its frames changed in each
// block (and laser tile), log-odds cell by cell (log_odds_deltas.h), becomes the submap. Adding
// every submap's changes in turn, clamped, gives the fused map again; so when a correction moves a
// submap, the blocks it covered before and covers now are rebuilt from the submaps that cover them,
// each resampled at its own placement (nearest cell; the layer's tiles by the placement's planar
// part), in the order they were written. Nothing else
// in the map is touched: without corrections the map is the one the mappers wrote, bit for bit.
//
// Thread safety: every public member function may be called from any thread. Frames hold a
// FrameLease while they are placed and written, so that no submap is closed in between.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <istream>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <shared_mutex>
#include <string>
#include <utility>
#include <vector>

#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/map/voxel_map.h"

namespace occupancy_fusion {

struct SubmapFusionConfig {
  // m. A new placement that moves no corner of a submap's blocks by more than this leaves the
  // submap where it is (SLAM's small adjustments of old keyframes cost nothing). 0: a quarter
  // voxel (a laser wall drawn a third of a cell off already lands in other cells: measured on the
  // CARMEN logs, docs/loop_closures.md).
  double min_shift = 0.0;
  // Bytes of the submaps in memory (0: no bound): their indexes (which submaps reach each
  // block; where spilled blocks lie, 16 bytes a block), the active submap's first sights, and as
  // much of the closed submaps' changes as those leave; beyond, the oldest submaps' changes go to a
  // temporary file in spill_folder (empty: the system's temporary folder) and are read back from it
  // when a correction moves them or what they overlap. The indexes alone may exceed it on a large
  // map.
  std::size_t max_memory_bytes = 0;
  std::string spill_folder;

  void validate() const;  // throws std::invalid_argument naming the bad field
};

struct SubmapPlacement;  // where a submap was written and is shown (store_submaps.h)
class SubmapSpillFile;

// One submap as diagnostics and the trajectory corrections see it.
struct SubmapInfo {
  int id = 0;
  bool active = false;     // being written
  bool fixed = false;      // the map's contents from before the fusion began: never moved
  double start_stamp = 0;  // s, first frame written into it (0: none yet)
  double end_stamp = 0;    // s, last frame
  Eigen::Isometry3d written = Eigen::Isometry3d::Identity();  // T_map_odom it was written with
  Eigen::Isometry3d placed = Eigen::Isometry3d::Identity();   // T_map_odom it is shown with
  std::size_t blocks = 0;  // blocks it changed (the active one: written so far)
  std::size_t tiles = 0;   // laser layer tiles it changed
  std::size_t bytes = 0;   // memory of its changes
  // m, the map-frame box of its blocks and tiles where it was written (empty: none).
  Eigen::AlignedBox3d bounds;
};

// How far moving the points of `box` from placement `from` to `to` carries any of them (m): at
// one of its corners, for a rigid motion. Placements are T_map_odom; `written` the one the box's
// coordinates were taken at. 0 for an empty box.
double largestShift(const Eigen::AlignedBox3d& box, const Eigen::Isometry3d& written,
                    const Eigen::Isometry3d& from, const Eigen::Isometry3d& to);

// What one move of submaps did.
struct SubmapMoveResult {
  std::size_t moved = 0;             // submaps re-placed
  std::size_t blocks_rewritten = 0;  // blocks of the fused map rebuilt
  // s, wall time until the moved submaps were in the map re-sampled at their new places, and
  // until their laser cells were drawn again from their scans as well (all of it)
  double moved_seconds = 0.0;
  double seconds = 0.0;
};

// What draws a submap's part of the laser layer anew at another placement, from what its scans
// measured (MapReanchoring keeps them): a moved submap's thin walls then land where a map made
// at that placement has them, instead of being re-sampled from a grid that moved.
class LayerDrawer {
 public:
  virtual ~LayerDrawer() = default;
  // Integrates submap `id`'s scans into `layer` (empty) with the submap placed at T_map_odom.
  // false: nothing kept for it (its cells are re-sampled instead). Called from place(), one
  // submap at a time, without the fusion's lock: frames may start a submap meanwhile.
  virtual bool draw(int id, const Eigen::Isometry3d& T_map_odom, GridLayer2D* layer) = 0;
};

class SubmapFusion {
 public:
  // Starts watching `map` and `layer` (may be null; both must outlive the fusion) with an active
  // submap written at `T_map_odom`. What they hold already becomes a fixed submap, never moved.
  SubmapFusion(VoxelMap* map, GridLayer2D* layer, const SubmapFusionConfig& config,
               const Eigen::Isometry3d& T_map_odom = Eigen::Isometry3d::Identity());
  ~SubmapFusion();
  SubmapFusion(const SubmapFusion&) = delete;
  SubmapFusion& operator=(const SubmapFusion&) = delete;

  // Held by a frame from its placement until its write is done: the active submap stays the
  // same meanwhile.
  class FrameLease {
   public:
    int submap() const { return submap_; }
    // Where the frame's odometry pose is to be placed: T_map_sensor = T_map_odom() * T_odom_sensor.
    const Eigen::Isometry3d& T_map_odom() const { return T_map_odom_; }

   private:
    friend class SubmapFusion;
    std::shared_lock<std::shared_mutex> lock_;
    int submap_ = 0;
    Eigen::Isometry3d T_map_odom_;
  };
  // stamp (s, 0: unstamped) widens the active submap's time span.
  FrameLease beginFrame(double stamp);

  // Closes the active submap (it keeps its placement) and starts the next one, written with
  // T_map_odom (without: the active one's). Returns the new submap's id. A submap that changed
  // nothing is reused.
  int startSubmap(const Eigen::Isometry3d& T_map_odom);
  int startSubmap();
  // startSubmap(), unless a correction is re-sampling the map (place(); while it draws the laser
  // layer anew, a submap may start): then nothing and false, at once. Waiting would hold every
  // mapper's frames for the rebuild's time.
  bool tryStartSubmap();
  bool tryStartSubmap(const Eigen::Isometry3d& T_map_odom);
  // What the map holds so far (e.g. a saved map just loaded) becomes a fixed submap, never moved.
  void fixWrittenSoFar();

  // New placements (T_map_odom) by submap id; unknown ids are ignored. The active submap, when it
  // moves, is closed first and the next one is written with its new placement (with nothing
  // written yet, it is only placed anew).
  // `next`: where the frames from now on are written (the newest correction), when given; the
  // active submap is closed first if that moves it.
  SubmapMoveResult place(const std::vector<std::pair<int, Eigen::Isometry3d>>& placements,
                         const std::optional<Eigen::Isometry3d>& next = std::nullopt);

  std::vector<SubmapInfo> submaps() const;
  // The map-frame box (where written) of the newest blocks: the active submap's, else those of
  // the last submap that has any; empty when there are none. While a correction rebuilds the map,
  // the box measured last.
  Eigen::AlignedBox3d newestBounds() const;
  int activeSubmap() const;
  // The laser layer's moved submaps are drawn by `drawer` from now on (nullptr: re-sampled); it
  // must outlive the fusion or be unset. Called from place(), not under the map's locks.
  void setLayerDrawer(LayerDrawer* drawer);

  const SubmapFusionConfig& config() const { return config_; }
  double minShift() const { return min_shift_; }  // m, config().min_shift or a quarter voxel
  std::size_t memoryBytes() const;   // the submaps' changes and the active one's first sights
  std::size_t spilledBytes() const;  // written to the spill file (max_memory_bytes) so far
  // Corrections that moved submaps so far, counted once the map holds them re-sampled (before
  // the laser layer is drawn again): what a publisher watches to send a correction at once.
  std::uint64_t movesResampled() const { return moves_.load(std::memory_order_acquire); }

  // The submaps as bytes, to be saved beside the map (submap_files.h): the active submap is closed
  // first. restore() takes them back once the map and layer hold what was saved with them (their
  // sum): the submaps then move again with later corrections. Throws std::runtime_error when
  // the bytes are not a save of this map's kind (resolution, laser layer); the fusion then holds
  // the map's contents as one fixed submap.
  void save(std::ostream& out);
  void restore(std::istream& in);
  // save, then `then` before any frame is written into the next submap (a checkpoint of the map
  // in the same state as the bytes).
  void saveThen(std::ostream& out, const std::function<void()>& then);

  // Empties the map and layer and forgets every submap (the map server's reset).
  void reset();

 private:
  struct Stores;
  struct Meta {
    int id = 0;
    bool fixed = false;
    double start = 0.0, end = 0.0;
    Eigen::Isometry3d written = Eigen::Isometry3d::Identity();
    Eigen::Isometry3d placed = Eigen::Isometry3d::Identity();
  };
  using Placements = std::vector<std::pair<int, Eigen::Isometry3d>>;

  // By value: callers pass the active submap's own placement, which closing it replaces.
  void closeActiveLocked(Eigen::Isometry3d next_T_map_odom);
  void startSubmapLocked(const Eigen::Isometry3d& T_map_odom);  // startSubmap's, under its locks
  void restoreLocked(std::istream& in);
  // The moved submaps' laser tiles drawn anew by drawer_ where it can (they are re-sampled
  // already). `placed`: every closed submap's placement, by id. `lock` (on mutex_) is let go
  // while a submap's scans are drawn.
  void drawTiles(std::vector<int> moved, const std::vector<SubmapPlacement>& placed,
                 SpatialKeySet* touched, std::unique_lock<std::mutex>* lock);
  void fixContentsLocked();         // the map's contents become one fixed submap, nothing else
  void enforceMemoryBoundLocked();  // the oldest submaps' changes to the spill file
  void adoptContentsLocked();       // what the map holds, if anything, as fixed submap 0
  // The active submap shown at `placed`; frames from now on written at `next`.
  void placeActiveLocked(const Eigen::Isometry3d& placed, const Eigen::Isometry3d& next);
  Eigen::AlignedBox3d boundsOf(int id) const;
  Eigen::AlignedBox3d activeBounds() const;
  std::size_t activeBlocks() const;

  VoxelMap* map_;
  GridLayer2D* layer_;
  SubmapFusionConfig config_;
  double min_shift_;  // m, config_'s or a quarter voxel

  // Held for a whole correction (place()) and by what must not come in while it lets go of
  // mutex_ (saves, restores, resets): corrections one at a time.
  std::mutex correction_mutex_;
  std::shared_mutex frames_mutex_;  // shared: frames in flight; unique: a submap closes
  mutable std::mutex mutex_;        // the submaps
  std::unique_ptr<Stores> stores_;
  LayerDrawer* drawer_ = nullptr;
  std::unique_ptr<SubmapSpillFile> spill_;  // with max_memory_bytes, made at the first spill
  std::vector<Meta> closed_;                // by id
  Meta active_;  // id closed_.size(); its stamps also change under stamp_mutex_
  mutable std::mutex stamp_mutex_;
  std::atomic<std::uint64_t> moves_{0};  // movesResampled()
  mutable std::mutex newest_mutex_;
  mutable Eigen::AlignedBox3d newest_bounds_;  // newestBounds()' last
};

}  // namespace occupancy_fusion
