// The paper's claim (Sec. IV-A) on the simulator's corridor (eval/stereo_corridor.h): with
// correlated stereo errors (patches of wrong disparity that persist over frames), the visibility
// method maps far fewer false-occupied voxels than OctoMap's update on the same rays, while
// covering the true surface about as well.
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "occupancy_fusion/eval/stereo_corridor.h"
#include "occupancy_fusion/sim/scenes.h"

namespace occupancy_fusion {
namespace {

constexpr double kResolution = 0.2;  // the paper's voxel size (Sec. IV)

struct Measured {
  StereoMapQuality quality;
  double cache_hit_rate = 0.0;
};

Measured mapCorridor(const VisibilityStereoConfig& config, const sim::Scene& scene,
                     const std::vector<StereoFrame>& frames,
                     const std::vector<SeenSurfaceSample>& surface) {
  const StereoCorridorRun run = mapStereoCorridor(config, frames, kResolution);
  Measured measured;
  measured.quality = evaluateStereoMap(scene, run.occupied, kResolution, surface);
  measured.cache_hit_rate = static_cast<double>(run.cache_hits) / run.voxel_visits;
  return measured;
}

void print(const char* name, const Measured& m) {
  std::printf("  %s: false_occupied=%zu occupied=%zu coverage=%.3f cache_hit_rate=%.3f\n", name,
              m.quality.false_occupied, m.quality.occupied, m.quality.coverage, m.cache_hit_rate);
}

// The frames, the seen surface and the OctoMap mode's map are shared by the tests (rendered
// once).
class CorridorArtifactsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const StereoCorridorSetup setup;  // 80 frames, 3 cm apart
    frames_ = new std::vector<StereoFrame>(
        renderStereoCorridor(scene(), setup, VisibilityStereoIntegrator()));
    surface_ = new std::vector<SeenSurfaceSample>(seenSurface(scene(), setup, kResolution));
    VisibilityStereoConfig octomap_config;
    octomap_config.method = StereoIntegrationMethod::kOctomap;
    octomap_ = new Measured(mapCorridor(octomap_config, scene(), *frames_, *surface_));
    std::printf("corridor, %d frames, %zu visible surface samples\n", setup.frames,
                surface_->size());
    print("octomap mode", *octomap_);
  }
  static void TearDownTestSuite() {
    delete frames_;
    delete surface_;
    delete octomap_;
  }
  static const sim::Scene& scene() {
    static const sim::Scene corridor = sim::makeCorridorScene();
    return corridor;
  }
  static Measured mapWith(const VisibilityStereoConfig& config) {
    return mapCorridor(config, scene(), *frames_, *surface_);
  }

  static std::vector<StereoFrame>* frames_;
  static std::vector<SeenSurfaceSample>* surface_;
  static Measured* octomap_;
};

std::vector<StereoFrame>* CorridorArtifactsTest::frames_ = nullptr;
std::vector<SeenSurfaceSample>* CorridorArtifactsTest::surface_ = nullptr;
Measured* CorridorArtifactsTest::octomap_ = nullptr;

TEST_F(CorridorArtifactsTest, TableIMapsFewerFalseOccupiedVoxelsThanOctomap) {
  const Measured table_i = mapWith(VisibilityStereoConfig());
  print("visibility (Table I)", table_i);
  // Measured (Release): 167 false-occupied voxels against OctoMap's 2240 (1/13.4; the goal is
  // <= 1/5), at 0.646 of its coverage: Table I's values map unknown space gradually (Fig. 5a),
  // so surfaces first seen late in the run are not reached yet (docs/disparity_method.md).
  EXPECT_LE(5 * table_i.quality.false_occupied, octomap_->quality.false_occupied);
  EXPECT_GT(octomap_->quality.coverage, 0.95);
  EXPECT_GE(table_i.quality.coverage, 0.6 * octomap_->quality.coverage);
  EXPECT_LT(table_i.quality.coverage, 0.8 * octomap_->quality.coverage);
}

// Sec. IV-A's compromise towards faster expansion (StereoParameterSet::kFastExpansion) meets
// both goals of the comparison: at most 1/5 of OctoMap's false-occupied voxels with at least 90 %
// of its surface coverage.
TEST_F(CorridorArtifactsTest, FastExpansionMeetsBothGoals) {
  const Measured fast = mapWith(visibilityStereoConfigFor(StereoParameterSet::kFastExpansion));
  print("visibility (fast_expansion)", fast);
  // Measured (Release): 214 false-occupied voxels against OctoMap's 1951 (0.110), coverage
  // 0.935 against 1.000.
  EXPECT_LE(5 * fast.quality.false_occupied, octomap_->quality.false_occupied);
  EXPECT_GE(fast.quality.coverage, 0.9 * octomap_->quality.coverage);
  // The surface within 4 m of the trajectory is covered as by OctoMap.
  EXPECT_GT(fast.quality.coverage_by_distance[1], 0.97);
}

}  // namespace
}  // namespace occupancy_fusion
