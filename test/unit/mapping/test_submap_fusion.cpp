// Submaps that move (mapping/submap_fusion.h): without a move the map is the one written, bit for
// bit; a move carries a submap's cells to their new place and leaves the others as they were.
#include <gtest/gtest.h>

#include <cmath>
#include <future>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

#include "occupancy_fusion/integrators/point_cloud_integrator.h"
#include "occupancy_fusion/map/log_odds_deltas.h"
#include "occupancy_fusion/mapping/submap_fusion.h"

namespace occupancy_fusion {
namespace {

constexpr double kResolution = 0.1;
// A submap keeps each change rounded to PackedLogOddsChanges' step: a rebuilt cell is within this
// of the exact sum per submap that reaches it.
constexpr float kRounding = PackedLogOddsChanges<VoxelBlock::kVolume>::kStep;

VoxelMapConfig mapConfig() {
  VoxelMapConfig config;
  config.resolution = kResolution;
  return config;
}

using Cells = std::map<std::tuple<int, int, int>, float>;

Cells knownCells(const VoxelMap& map) {
  Cells cells;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float value) {
    cells[{index.x(), index.y(), index.z()}] = value;
  });
  return cells;
}

// The same cells, each value within `tolerance`.
void expectNear(const Cells& actual, const Cells& expected, float tolerance) {
  ASSERT_EQ(actual.size(), expected.size());
  for (const auto& cell : expected) {
    ASSERT_EQ(actual.count(cell.first), 1u);
    EXPECT_NEAR(actual.at(cell.first), cell.second, tolerance);
  }
}

std::vector<Eigen::Vector3i> occupied(const VoxelMap& map) {
  std::vector<Eigen::Vector3i> result;
  map.forEachOccupiedVoxel([&](const VoxelIndex& index, float) { result.push_back(index); });
  return result;
}

// A wall of points at x = wall_x, y in [-1, 1], z in [0, 1], seen from `origin`, both moved by
// `T` (a drifted odometry's view of it).
void seeWall(double wall_x, const Eigen::Vector3d& origin, const Eigen::Isometry3d& T,
             VoxelMap* map) {
  std::vector<Eigen::Vector3f> points;
  for (double y = -1.0; y <= 1.0; y += 0.03) {
    for (double z = 0.0; z <= 1.0; z += 0.03) {
      points.push_back((T * Eigen::Vector3d(wall_x, y, z)).cast<float>());
    }
  }
  PointCloudIntegrator().integrate(points, T * origin, map);
}

TEST(SubmapFusion, WithoutMovesTheMapIsTheOneWrittenBitForBit) {
  VoxelMap watched(mapConfig()), plain(mapConfig());
  SubmapFusion fusion(&watched, nullptr, SubmapFusionConfig());
  for (int frame = 0; frame < 12; ++frame) {
    const Eigen::Vector3d origin(0.1 * frame, 0.05 * frame, 0.5);
    for (VoxelMap* map : {&watched, &plain}) seeWall(2.0 + 0.2 * (frame % 3), origin, {}, map);
    if (frame % 4 == 3) fusion.startSubmap(Eigen::Isometry3d::Identity());
  }
  // Placements at the written place move nothing.
  SubmapMoveResult moved = fusion.place({{0, Eigen::Isometry3d::Identity()},
                                         {1, Eigen::Isometry3d::Identity()},
                                         {3, Eigen::Isometry3d::Identity()}});
  EXPECT_EQ(moved.moved, 0u);
  EXPECT_EQ(moved.blocks_rewritten, 0u);
  EXPECT_EQ(fusion.submaps().size(), 4u);  // three closed, one active
  EXPECT_EQ(knownCells(watched), knownCells(plain));
}

TEST(SubmapFusion, MovedAndMovedBackGivesTheMapAgain) {
  VoxelMap watched(mapConfig()), plain(mapConfig());
  SubmapFusion fusion(&watched, nullptr, SubmapFusionConfig());
  for (int frame = 0; frame < 9; ++frame) {
    const Eigen::Vector3d origin(0.15 * frame, 0.0, 0.5);
    for (VoxelMap* map : {&watched, &plain}) seeWall(2.5 - 0.1 * (frame % 2), origin, {}, map);
    if (frame % 3 == 2) fusion.startSubmap(Eigen::Isometry3d::Identity());
  }
  const Eigen::Isometry3d away(Eigen::Translation3d(0.73, -0.41, 0.0) *
                               Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()));
  EXPECT_EQ(fusion.place({{1, away}}).moved, 1u);
  EXPECT_NE(knownCells(watched), knownCells(plain));
  EXPECT_EQ(fusion.place({{1, Eigen::Isometry3d::Identity()}}).moved, 1u);
  // The changes add up to the written cells again, up to rounding.
  expectNear(knownCells(watched), knownCells(plain), 3 * kRounding);
}

TEST(SubmapFusion, AWholeVoxelShiftCarriesEveryCellOfTheSubmapExactly) {
  VoxelMap map(mapConfig());
  SubmapFusion fusion(&map, nullptr, SubmapFusionConfig());
  seeWall(1.55, Eigen::Vector3d(0, 0, 0.5), {}, &map);
  const Cells written = knownCells(map);
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  const Eigen::Isometry3d shift(Eigen::Translation3d(3 * kResolution, -2 * kResolution, 0.0));
  EXPECT_EQ(fusion.place({{0, shift}}).moved, 1u);
  Cells expected;
  for (const auto& cell : written) {
    const auto& [x, y, z] = cell.first;
    expected[{x + 3, y - 2, z}] = cell.second;
  }
  expectNear(knownCells(map), expected, kRounding);  // the old place is unknown again: no ghost
}

TEST(SubmapFusion, ACorrectedDriftedSubmapLandsWhereTheTruePosesPutIt) {
  // Submap 0 sees a wall from the true pose; submap 1 sees a second wall while its odometry has
  // drifted by `drift`, then the localisation's correction places it at drift^-1.
  const Eigen::Isometry3d drift(Eigen::Translation3d(0.42, -0.27, 0.0) *
                                Eigen::AngleAxisd(0.12, Eigen::Vector3d::UnitZ()));
  VoxelMap map(mapConfig()), truth(mapConfig());
  SubmapFusion fusion(&map, nullptr, SubmapFusionConfig());
  seeWall(2.0, Eigen::Vector3d(0, 0, 0.5), {}, &map);
  seeWall(2.0, Eigen::Vector3d(0, 0, 0.5), {}, &truth);
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  const Eigen::Isometry3d turned(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  seeWall(2.0, Eigen::Vector3d(0, 0, 0.5), drift * turned, &map);
  seeWall(2.0, Eigen::Vector3d(0, 0, 0.5), turned, &truth);
  fusion.startSubmap(Eigen::Isometry3d::Identity());

  // Nearest-cell resampling of a turned wall moves single cells by one voxel: count the occupied
  // voxels of each map with one of the other's within one voxel.
  const auto near = [](const VoxelMap& map, const Eigen::Vector3i& index) {
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (map.occupancy(index + Eigen::Vector3i(dx, dy, dz)) == Occupancy::kOccupied) {
            return true;
          }
        }
      }
    }
    return false;
  };
  const auto matched = [&](const VoxelMap& from, const VoxelMap& to) {
    const std::vector<Eigen::Vector3i> cells = occupied(from);
    std::size_t count = 0;
    for (const Eigen::Vector3i& index : cells) count += near(to, index);
    return static_cast<double>(count) / static_cast<double>(cells.size());
  };
  EXPECT_LT(matched(truth, map), 0.6);
  EXPECT_LT(matched(map, truth), 0.6);
  EXPECT_EQ(fusion.place({{1, drift.inverse()}}).moved, 1u);
  EXPECT_GT(matched(truth, map), 0.98);  // the true walls are mapped
  EXPECT_GT(matched(map, truth), 0.98);  // and no copy of them is left elsewhere
  // Submap 0's wall is untouched.
  EXPECT_EQ(map.occupancyAt({2.05, 0.05, 0.55}), Occupancy::kOccupied);
}

TEST(SubmapFusion, TurnedOccupiedEvidenceIsCarriedOnlyToCellsNearWhereItWasMeasured) {
  // Free space with a weakly occupied cell (one hit more than misses: a noise voxel beside a
  // wall) and a strongly occupied one. Re-sampled by the nearest written cell alone, a cell of
  // the turned grid whose centre lies up to half a voxel off either (per axis) takes its
  // evidence, so noise voxels move outwards by up to 0.87 voxels and walls thicken. Mixed with
  // the free neighbours by distance, a weak change of +0.4 among -1.0 stays occupied only where
  // the cell's weight exceeds 1 / 1.4: within 0.29 voxels per axis of where it was written.
  const VoxelIndex weak(13, 15, 5), strong(17, 15, 5);
  int weak_carried = 0;
  for (int turn = 0; turn < 12; ++turn) {
    VoxelMap map(mapConfig());
    SubmapFusion fusion(&map, nullptr, SubmapFusionConfig());
    for (int z = 1; z <= 9; ++z) {
      for (int y = 11; y <= 19; ++y) {
        for (int x = 9; x <= 21; ++x) map.updateVoxel(VoxelIndex(x, y, z), -1.0f);
      }
    }
    map.updateVoxel(weak, 1.4f);
    map.updateVoxel(strong, 4.0f);
    fusion.startSubmap(Eigen::Isometry3d::Identity());
    const Eigen::Isometry3d placed(
        Eigen::Translation3d(0.013 * turn, -0.029 * turn, 0.007 * turn) *
        Eigen::AngleAxisd(0.05 + 0.047 * turn, Eigen::Vector3d(0.1, 0.2, 1.0).normalized()));
    ASSERT_EQ(fusion.place({{0, placed}}).moved, 1u);
    bool strong_found = false, weak_found = false;
    for (const Eigen::Vector3i& index : occupied(map)) {
      const Eigen::Vector3d written =
          placed.inverse() * ((index.cast<double>().array() + 0.5) * kResolution).matrix() /
          kResolution;
      const VoxelIndex source = written.array().floor().cast<int>();
      ASSERT_TRUE(source == weak || source == strong) << index.transpose();
      strong_found |= source == strong;
      if (source != weak) continue;
      weak_found = true;
      const Eigen::Vector3d off = written - (weak.cast<double>().array() + 0.5).matrix();
      EXPECT_LT(off.cwiseAbs().maxCoeff(), 0.3) << "turn " << turn;
    }
    EXPECT_TRUE(strong_found) << "turn " << turn;  // within 0.78 voxels per axis: always
    weak_carried += weak_found ? 1 : 0;
  }
  // Neither dropped nor always kept: where a cell's centre falls near its own.
  EXPECT_GT(weak_carried, 0);
  EXPECT_LT(weak_carried, 12);
}

TEST(SubmapFusion, TheActiveSubmapsWritesStayOnTopOfARebuild) {
  VoxelMap map(mapConfig());
  SubmapFusion fusion(&map, nullptr, SubmapFusionConfig());
  seeWall(2.0, Eigen::Vector3d(0, 0, 0.5), {}, &map);  // submap 0
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  const VoxelIndex mark(30, 1, 5), shared(20, 1, 5);  // in the active submap; on submap 0's wall
  const float wall = *map.logOdds(shared);
  map.updateVoxel(mark, 1.25f);
  map.updateVoxel(shared, -0.5f);
  fusion.place({{0, Eigen::Isometry3d(Eigen::Translation3d(0.0, 0.0, 1.0))}});
  EXPECT_FLOAT_EQ(*map.logOdds(mark), 1.25f);
  // The wall left; the active submap's own change of that cell stays, from the prior.
  EXPECT_NEAR(*map.logOdds(shared), -0.5f, 1e-6);
  EXPECT_NEAR(*map.logOdds(VoxelIndex(20, 1, 15)), wall, kRounding);
  // Closing it later records only its own changes: moving submap 0 back restores the wall plus
  // the active change.
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  fusion.place({{0, Eigen::Isometry3d::Identity()}});
  EXPECT_NEAR(*map.logOdds(shared), wall - 0.5f, 2 * kRounding);
  EXPECT_FLOAT_EQ(*map.logOdds(mark), 1.25f);
}

TEST(SubmapFusion, AMovedActiveSubmapIsClosedAndTheNextIsWrittenAtTheNewPlace) {
  VoxelMap map(mapConfig());
  SubmapFusion fusion(&map, nullptr, SubmapFusionConfig());
  {
    const SubmapFusion::FrameLease lease = fusion.beginFrame(10.0);
    EXPECT_EQ(lease.submap(), 0);
    seeWall(2.0, Eigen::Vector3d(0, 0, 0.5), lease.T_map_odom(), &map);
  }
  const Eigen::Isometry3d corrected(Eigen::Translation3d(0.0, 0.5, 0.0));
  EXPECT_EQ(fusion.place({{0, corrected}}).moved, 1u);
  const SubmapFusion::FrameLease lease = fusion.beginFrame(11.0);
  EXPECT_EQ(lease.submap(), 1);
  EXPECT_TRUE(lease.T_map_odom().isApprox(corrected));
  const std::vector<SubmapInfo> submaps = fusion.submaps();
  ASSERT_EQ(submaps.size(), 2u);
  EXPECT_DOUBLE_EQ(submaps[0].start_stamp, 10.0);
  EXPECT_TRUE(submaps[0].placed.isApprox(corrected));
  EXPECT_TRUE(submaps[0].written.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_EQ(map.occupancyAt({2.05, 0.55, 0.55}), Occupancy::kOccupied);
}

TEST(SubmapFusion, MovesBelowTheThresholdLeaveTheMapAlone) {
  VoxelMap map(mapConfig());
  SubmapFusion fusion(&map, nullptr, SubmapFusionConfig());  // a quarter voxel
  seeWall(2.0, Eigen::Vector3d(0, 0, 0.5), {}, &map);
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  const Cells before = knownCells(map);
  EXPECT_EQ(fusion.place({{0, Eigen::Isometry3d(Eigen::Translation3d(0.01, 0.02, 0.0))}}).moved,
            0u);
  EXPECT_EQ(knownCells(map), before);
  // A small turn that moves the far corner of the wall's blocks by more than that counts.
  EXPECT_EQ(
      fusion.place({{0, Eigen::Isometry3d(Eigen::AngleAxisd(0.015, Eigen::Vector3d::UnitZ()))}})
          .moved,
      1u);
}

TEST(SubmapFusion, WhatTheMapHeldBeforeStaysWhereItIs) {
  VoxelMap map(mapConfig());
  map.updateVoxel(VoxelIndex(5, 5, 5), 2.0f);  // e.g. a resumed map
  SubmapFusion fusion(&map, nullptr, SubmapFusionConfig());
  map.updateVoxel(VoxelIndex(5, 5, 5), 0.5f);
  map.updateVoxel(VoxelIndex(6, 5, 5), 0.5f);
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  const std::vector<SubmapInfo> submaps = fusion.submaps();
  ASSERT_EQ(submaps.size(), 3u);
  EXPECT_TRUE(submaps[0].fixed);
  fusion.place({{0, Eigen::Isometry3d(Eigen::Translation3d(5.0, 0, 0))},
                {1, Eigen::Isometry3d(Eigen::Translation3d(5.0, 0, 0))}});
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(5, 5, 5)), 2.0f);  // fixed: stays
  EXPECT_FALSE(map.logOdds(VoxelIndex(6, 5, 5)).has_value());
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(55, 5, 5)), 0.5f);  // submap 1's changes moved 5 m
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(56, 5, 5)), 0.5f);
}

TEST(SubmapFusion, WhatWasWrittenBeforeItIsFixedStaysWhereItIs) {
  VoxelMap map(mapConfig());
  SubmapFusion fusion(&map, nullptr, SubmapFusionConfig());
  map.updateVoxel(VoxelIndex(5, 5, 5), 2.0f);  // a saved map loaded after the fusion began
  fusion.fixWrittenSoFar();
  map.updateVoxel(VoxelIndex(6, 5, 5), 0.5f);
  fusion.startSubmap();
  const Eigen::Isometry3d away(Eigen::Translation3d(5.0, 0, 0));
  EXPECT_EQ(fusion.place({{0, away}, {1, away}}).moved, 1u);
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(5, 5, 5)), 2.0f);
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(56, 5, 5)), 0.5f);
  EXPECT_TRUE(fusion.submaps()[0].fixed);
}

TEST(SubmapFusion, ResetForgetsTheSubmaps) {
  VoxelMap map(mapConfig());
  SubmapFusion fusion(&map, nullptr, SubmapFusionConfig());
  seeWall(2.0, Eigen::Vector3d(0, 0, 0.5), {}, &map);
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  fusion.reset();
  EXPECT_EQ(map.blockCount(), 0u);
  EXPECT_EQ(fusion.submaps().size(), 1u);
  map.updateVoxel(VoxelIndex(1, 1, 1), 1.0f);
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  fusion.place({{0, Eigen::Isometry3d(Eigen::Translation3d(1.0, 0, 0))}});
  EXPECT_FLOAT_EQ(*map.logOdds(VoxelIndex(11, 1, 1)), 1.0f);
}

TEST(SubmapFusion, AClearedBoxIsPartOfTheSubmapThatClearedIt) {
  VoxelMap map(mapConfig());
  SubmapFusion fusion(&map, nullptr, SubmapFusionConfig());
  seeWall(2.0, Eigen::Vector3d(0, 0, 0.5), {}, &map);  // submap 0
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  map.clearBox({1.95, -0.05, 0.45}, {2.15, 0.25, 0.75});  // submap 1: a hole in the wall
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  const Cells cleared = knownCells(map);
  // Submap 0 moved away and back: the rebuild adds submap 1's clearing again.
  fusion.place({{0, Eigen::Isometry3d(Eigen::Translation3d(0, 0, 3.0))}});
  fusion.place({{0, Eigen::Isometry3d::Identity()}});
  EXPECT_EQ(map.occupancyAt({2.05, 0.05, 0.55}), Occupancy::kFree);
  const Cells rebuilt = knownCells(map);
  ASSERT_EQ(rebuilt.size(), cleared.size());
  expectNear(rebuilt, cleared, 2 * kRounding);
}

GridLayer2DConfig layerConfig() {
  GridLayer2DConfig config;
  config.resolution = kResolution;
  return config;
}

// A laser's wall: occupied cells along y = wall_y from x = 0 to 3 m, free cells in front of it.
void scanWall(double wall_y, GridLayer2D* layer) {
  const CellIndex origin = layer->indexOf({0.0, 0.0});
  const int width = 30, height = layer->indexOf({0.0, wall_y}).y() - origin.y() + 1;
  std::vector<float> raster(static_cast<std::size_t>(width * height), -0.4f);
  for (int x = 0; x < width; ++x)
    raster[static_cast<std::size_t>(x + width * (height - 1))] = 0.85f;
  layer->addRaster(origin, width, height, raster.data());
}

TEST(SubmapFusion, TheLaserLayerMovesWithTheMapsPlanarPlacement) {
  VoxelMap map(mapConfig());
  GridLayer2D layer(layerConfig());
  SubmapFusion fusion(&map, &layer, SubmapFusionConfig());
  scanWall(1.0,
           &layer);  // submap 0, drifted: the wall is truly 0.3 m farther and 0.5 m to the right
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  scanWall(2.5, &layer);  // submap 1, active
  const float wall = *layer.logOdds(layer.indexOf({1.05, 1.05}));
  const auto moved = fusion.place({{0, Eigen::Isometry3d(Eigen::Translation3d(0.5, 0.3, 0.0))}});
  EXPECT_EQ(moved.moved, 1u);
  // Where the wall was: submap 0's free cell from (0.55, 0.75), then submap 1's miss.
  EXPECT_NEAR(*layer.logOdds(layer.indexOf({1.05, 1.05})), -0.8f, 2 * kRounding);
  EXPECT_NEAR(*layer.logOdds(layer.indexOf({1.55, 1.35})), wall, kRounding);  // 1.05+0.5, +0.3
  EXPECT_EQ(layer.occupancyAt({3.45, 1.35}), Occupancy::kOccupied);           // x 2.95 + 0.5
  // Submap 1's own cells stay, its wall on top of submap 0's moved free space.
  EXPECT_EQ(layer.occupancyAt({0.05, 2.55}), Occupancy::kOccupied);
  EXPECT_EQ(layer.occupancyAt({0.55, 1.05}), Occupancy::kFree);  // submap 1's free cells
  const std::vector<SubmapInfo> submaps = fusion.submaps();
  EXPECT_EQ(submaps[0].blocks, 0u);
  EXPECT_GT(submaps[0].tiles, 0u);
}

// A map saved with its submaps and loaded elsewhere moves with a later correction as the original
// does.
// Measurements of one cell, kept per submap in odometry: submap 0 saw an object there (hits),
// submap 1 saw through where it had been (misses). Drawn again at a new placement in the order
// written, each on what the submaps before it hold, the cell ends as one pass over the
// measurements ends it: free. Drawn from unknown and added up, submap 1's clearing is clamped at
// the minimum first and the object stays (about 3.5 - 2 = 1.5, occupied).
TEST(SubmapFusion, MovedSubmapsAreDrawnAgainInTheOrderWritten) {
  struct CellDrawer : LayerDrawer {
    std::map<int, std::vector<float>> updates;  // by submap, of the cell at (0.25, 0.25) in odom
    bool draw(int id, const Eigen::Isometry3d& T_map_odom, GridLayer2D* layer) override {
      const Eigen::Vector3d at = T_map_odom * Eigen::Vector3d(0.25, 0.25, 0.0);
      for (float update : updates.at(id)) layer->updateCell(layer->indexOf(at.head<2>()), update);
      return true;
    }
    void write(int id, GridLayer2D* layer) {
      for (float update : updates.at(id)) layer->updateCell(layer->indexOf({0.25, 0.25}), update);
    }
  } drawer;
  drawer.updates[0] = std::vector<float>(6, 0.85f);  // clamped at the maximum
  drawer.updates[1] = std::vector<float>(10, -0.4f);
  VoxelMap map(mapConfig());
  GridLayer2D layer(layerConfig());
  SubmapFusion fusion(&map, &layer, SubmapFusionConfig());
  fusion.setLayerDrawer(&drawer);
  drawer.write(0, &layer);
  fusion.startSubmap();
  drawer.write(1, &layer);
  fusion.startSubmap();
  const float cleared = layer.maxLogOdds() - 4.0f;
  EXPECT_LT(cleared, 0.0f);
  EXPECT_NEAR(*layer.logOdds(layer.indexOf({0.25, 0.25})), cleared, 1e-5f);
  const Eigen::Isometry3d moved(Eigen::Translation3d(1.0, 0.0, 0.0));
  EXPECT_EQ(fusion.place({{0, moved}, {1, moved}}).moved, 2u);
  EXPECT_NEAR(*layer.logOdds(layer.indexOf({1.25, 0.25})), cleared, 2 * kRounding);
  EXPECT_EQ(layer.occupancyAt({1.25, 0.25}), Occupancy::kFree);
  EXPECT_FALSE(layer.logOdds(layer.indexOf({0.25, 0.25})));  // nothing left where it was
}

using LayerCells = std::map<std::pair<int, int>, float>;

LayerCells knownCells(const GridLayer2D& layer) {
  LayerCells cells;
  layer.forEachKnownCell([&](const CellIndex& index, float value) {
    cells[{index.x(), index.y()}] = value;
  });
  return cells;
}

// A submap due while a correction re-samples the map is not started then (the frames would wait
// for the whole rebuild): tryStartSubmap() answers at once. While the correction draws the laser
// layer anew it starts, and its writes stay in the map as if it had started after the correction.
TEST(SubmapFusion, ASubmapDueDuringACorrectionStartsWithoutWaitingForIt) {
  struct HeldDrawer : LayerDrawer {
    std::promise<void> drawing, release;
    std::shared_future<void> released = release.get_future().share();
    bool held = false;
    bool draw(int /*id*/, const Eigen::Isometry3d& /*T_map_odom*/,
              GridLayer2D* /*layer*/) override {
      if (held) return false;
      held = true;
      drawing.set_value();
      released.wait();  // the correction holds here, the fusion let go of
      return false;
    }
  } drawer;
  const Eigen::Isometry3d moved(Eigen::Translation3d(0.5, 0.0, 0.0));
  VoxelMap map(mapConfig()), map_after(mapConfig());
  GridLayer2D layer(layerConfig()), layer_after(layerConfig());
  SubmapFusion fusion(&map, &layer, SubmapFusionConfig());
  fusion.setLayerDrawer(&drawer);
  SubmapFusion after(&map_after, &layer_after, SubmapFusionConfig());  // the same, one at a time
  for (GridLayer2D* each : {&layer, &layer_after}) scanWall(1.0, each);
  fusion.startSubmap();
  after.startSubmap();
  for (GridLayer2D* each : {&layer, &layer_after}) scanWall(2.0, each);  // submap 1, active
  std::future<SubmapMoveResult> correction = std::async(std::launch::async, [&] {
    return fusion.place({{0, moved}});
  });
  drawer.drawing.get_future().wait();
  EXPECT_EQ(fusion.beginFrame(12.0).submap(), 1);  // frames go on meanwhile, in submap 1
  EXPECT_TRUE(fusion.tryStartSubmap());            // at once: a blocking start would hang here
  scanWall(2.6, &layer);                           // submap 2, during the correction
  drawer.release.set_value();
  EXPECT_EQ(correction.get().moved, 1u);
  EXPECT_EQ(after.place({{0, moved}}).moved, 1u);
  after.startSubmap();
  scanWall(2.6, &layer_after);
  EXPECT_EQ(fusion.submaps().back().id, 2);
  const LayerCells cells = knownCells(layer), expected = knownCells(layer_after);
  ASSERT_EQ(cells.size(), expected.size());
  for (const auto& cell : expected) EXPECT_NEAR(cells.at(cell.first), cell.second, 4 * kRounding);
  // Moved again, the submap started during the correction goes along.
  const Eigen::Isometry3d again(Eigen::Translation3d(0.0, 1.0, 0.0));
  EXPECT_EQ(fusion.place({{2, again}}).moved, 1u);
  EXPECT_EQ(layer.occupancyAt({1.05, 3.65}), Occupancy::kOccupied);
  EXPECT_NE(layer.occupancyAt({1.05, 2.65}), Occupancy::kOccupied);
}

TEST(SubmapFusion, SavedSubmapsMoveTheLoadedMapAsTheyMovedTheOriginal) {
  VoxelMap original(mapConfig());
  GridLayer2D original_layer(layerConfig());
  SubmapFusion fusion(&original, &original_layer, SubmapFusionConfig());
  seeWall(2.0, Eigen::Vector3d(0, 0, 0.5), {}, &original);
  scanWall(1.0, &original_layer);
  fusion.startSubmap(Eigen::Isometry3d::Identity());
  seeWall(3.0, Eigen::Vector3d(0.5, 0, 0.5), {}, &original);
  std::stringstream saved;
  fusion.save(saved);  // closes submap 1
  EXPECT_EQ(fusion.submaps().size(), 3u);

  // The map as a file holds it (every voxel and cell as it is), then the submaps.
  VoxelMap loaded(mapConfig());
  GridLayer2D loaded_layer(layerConfig());
  original.forEachKnownVoxel(
      [&](const VoxelIndex& index, float value) { loaded.setLogOdds(index, value); });
  loaded_layer.importRaster(original_layer.toLogOddsRaster());
  SubmapFusion resumed(&loaded, &loaded_layer, SubmapFusionConfig());
  EXPECT_TRUE(resumed.submaps()[0].fixed);  // before the submaps are read: all fixed
  resumed.restore(saved);
  ASSERT_EQ(resumed.submaps().size(), 3u);
  EXPECT_FALSE(resumed.submaps()[0].fixed);
  EXPECT_GT(resumed.submaps()[0].tiles, 0u);

  const Eigen::Isometry3d correction(Eigen::Translation3d(0.3, -0.2, 0.0) *
                                     Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ()));
  EXPECT_EQ(fusion.place({{0, correction}}).moved, 1u);
  EXPECT_EQ(resumed.place({{0, correction}}).moved, 1u);
  expectNear(knownCells(loaded), knownCells(original), 2 * kRounding);
  const LogOddsRaster a = original_layer.toLogOddsRaster(), b = loaded_layer.toLogOddsRaster();
  ASSERT_EQ(a.data.size(), b.data.size());
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    if (std::isnan(a.data[i])) {
      EXPECT_TRUE(std::isnan(b.data[i]));
    } else {
      EXPECT_NEAR(a.data[i], b.data[i], 2 * kRounding);
    }
  }
}

TEST(SubmapFusion, DamagedSubmapsLeaveTheLoadedMapInPlace) {
  VoxelMap map(mapConfig());
  SubmapFusion fusion(&map, nullptr, SubmapFusionConfig());
  seeWall(2.0, Eigen::Vector3d(0, 0, 0.5), {}, &map);
  std::stringstream saved;
  fusion.save(saved);
  const std::string bytes = saved.str();
  VoxelMap coarse([] {
    VoxelMapConfig config = mapConfig();
    config.resolution = 0.2;
    return config;
  }());
  coarse.updateVoxel(VoxelIndex(1, 1, 1), 1.0f);
  SubmapFusion coarse_fusion(&coarse, nullptr, SubmapFusionConfig());
  std::stringstream wrong_resolution(bytes);
  EXPECT_THROW(coarse_fusion.restore(wrong_resolution), std::runtime_error);
  std::stringstream cut(bytes.substr(0, bytes.size() / 2));
  EXPECT_THROW(coarse_fusion.restore(cut), std::runtime_error);
  const std::vector<SubmapInfo> submaps = coarse_fusion.submaps();
  ASSERT_EQ(submaps.size(), 2u);  // the map's contents, fixed, and the active submap
  EXPECT_TRUE(submaps[0].fixed);
  coarse_fusion.place({{0, Eigen::Isometry3d(Eigen::Translation3d(1.0, 0, 0))}});
  EXPECT_FLOAT_EQ(*coarse.logOdds(VoxelIndex(1, 1, 1)), 1.0f);
}

TEST(PackedLogOddsChanges, KeepsWhichCellsChangedAndEachChangeToAStep) {
  VoxelBlock before, after;
  after.set(0, 0.8473f);
  before.set(7, 3.5f);
  after.set(7, -1.9931f);  // the whole clamping range of the defaults
  after.set(511, 0.0f);    // a cell that became known at the prior
  before.set(300, 0.4f);
  after.set(300, 0.4f);  // known, unchanged
  const PackedLogOddsChanges<VoxelBlock::kVolume> packed(before, after, 0.0f);
  EXPECT_EQ(packed.changed(), 3u);
  EXPECT_LT(packed.bytes(), 200u);
  VoxelBlock out;
  packed.expandInto(&out);
  EXPECT_EQ(out.known_count, 3);
  EXPECT_NEAR(out.log_odds[0], 0.8473f, kRounding);
  EXPECT_NEAR(out.log_odds[7], -5.4931f, kRounding);
  EXPECT_EQ(out.log_odds[511], 0.0f);
  for (int i : {1, 6, 8, 64, 300, 510}) EXPECT_TRUE(std::isnan(out.log_odds[i])) << i;
  // Every cell changed: about half a dense block.
  VoxelBlock all;
  for (int i = 0; i < VoxelBlock::kVolume; ++i) all.set(i, -0.4f);
  EXPECT_LT(PackedLogOddsChanges<VoxelBlock::kVolume>(VoxelBlock(), all, 0.0f).bytes(),
            sizeof(VoxelBlock) * 6 / 10);
}

// Evidence that cancels to within a step of the threshold: the change, added to the same cell,
// leaves it on the side it ended on (rounded to the nearest step, 0.85 - 0.8499 and 0.85 - 0.8501
// would both come back as 0, free).
TEST(PackedLogOddsChanges, AddedAgainACellEndsOnTheSideOfTheThresholdItEndedOn) {
  VoxelBlock before, after;
  for (int i = 0; i < 200; ++i) {
    before.set(i, 0.85f);
    after.set(i, (i % 2 == 0 ? 1.0f : -1.0f) * 1e-5f * static_cast<float>(i + 1));
  }
  for (const float threshold : {0.0f, 0.3f}) {
    for (int i = 200; i < 400; ++i) {
      before.set(i, -0.7f);
      after.set(i, threshold + (i % 2 == 0 ? 1.0f : -1.0f) * 1e-5f * static_cast<float>(i - 199));
    }
    const PackedLogOddsChanges<VoxelBlock::kVolume> packed(before, after, threshold);
    VoxelBlock changes, again = before;
    packed.expandInto(&changes);
    addLogOddsChanges(changes, -2.0f, 3.5f, &again);
    for (int i = (threshold == 0.0f ? 0 : 200); i < 400; ++i) {
      EXPECT_EQ(again.log_odds[i] > threshold, after.log_odds[i] > threshold) << i;
      EXPECT_NEAR(again.log_odds[i], after.log_odds[i], kRounding) << i;
    }
  }
}

TEST(SubmapFusion, RejectsANegativeThreshold) {
  VoxelMap map(mapConfig());
  SubmapFusionConfig config;
  config.min_shift = -0.1;
  EXPECT_THROW(SubmapFusion(&map, nullptr, config), std::invalid_argument);
}

}  // namespace
}  // namespace occupancy_fusion
