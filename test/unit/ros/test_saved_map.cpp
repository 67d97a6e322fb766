// Nothing lost across a restart: what ~save_map / save_on_shutdown write (saveMapFiles) is what
// load_map resumes (resumeSavedMap), voxels and laser layer alike, bit-exact; a damaged layer file
// stops the resume before the map is touched; a save without layer files (older saves, other
// tools' .ot files) resumes the voxels and says the layer starts empty.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "../../common/test_folder.h"
#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/layer_files.h"
#include "occupancy_fusion/map/saved_map.h"
#include "occupancy_fusion/ros/map_publisher.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

SharedMapConfig mapConfig(double resolution = 0.1) {
  SharedMapConfig config;
  config.voxels.resolution = resolution;
  return config;
}

// Voxels and layer cells with accumulated, partly clamped log-odds, as mappers leave them.
void fill(SharedMap* map, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> coordinate(-50, 50);
  std::uniform_int_distribution<int> count(-5, 5);
  const float hit = static_cast<float>(map->voxels().model().hitLogOdds());
  const float miss = static_cast<float>(map->voxels().model().missLogOdds());
  for (int i = 0; i < 1500; ++i) {
    const int n = count(random);
    const VoxelIndex voxel(coordinate(random), coordinate(random), coordinate(random) / 5);
    const CellIndex cell(coordinate(random) * 3, coordinate(random) - 20);
    for (int k = 0; k <= std::abs(n); ++k) {
      map->voxels().updateVoxel(voxel, n >= 0 ? hit : miss);
      map->layer().updateCell(cell, n >= 0 ? hit : miss);
    }
  }
}

// Entries of `expected` missing from `actual` or with other bits, plus one if the counts differ.
// for_each_known: VoxelMap::forEachKnownVoxel or GridLayer2D::forEachKnownCell.
template <typename Store, typename ForEachKnown>
std::size_t mismatches(const Store& expected, const Store& actual, ForEachKnown for_each_known,
                       std::size_t expected_count, std::size_t actual_count) {
  std::size_t differing = 0;
  (expected.*for_each_known)([&](const auto& index, float log_odds) {
    const std::optional<float> back = actual.logOdds(index);
    if (!back || !sameBits(*back, log_odds)) ++differing;
  });
  return differing + (expected_count != actual_count ? 1 : 0);
}

std::size_t voxelMismatches(const VoxelMap& expected, const VoxelMap& actual) {
  return mismatches(expected, actual, &VoxelMap::forEachKnownVoxel, expected.knownVoxelCount(),
                    actual.knownVoxelCount());
}

std::size_t cellMismatches(const GridLayer2D& expected, const GridLayer2D& actual) {
  return mismatches(expected, actual, &GridLayer2D::forEachKnownCell, expected.knownCellCount(),
                    actual.knownCellCount());
}

class SavedMap : public TestFolder {
 protected:
  void SetUp() override {
    TestFolder::SetUp();
    fill(&saved_, 5);
    saveMapFiles(saved_, FusedGridConfig(), prefix(), &written_);
  }
  std::string prefix() const { return path("site"); }

  SharedMap saved_{mapConfig()};
  std::vector<std::string> written_;
};

TEST_F(SavedMap, ResumesVoxelsAndLaserLayerBitExact) {
  const std::vector<std::string> expected_files = {
      prefix() + ".ot",   prefix() + ".bt",        prefix() + ".pgm",
      prefix() + ".yaml", prefix() + ".laser.npy", prefix() + ".laser.yaml"};
  EXPECT_EQ(written_, expected_files);
  ASSERT_GT(saved_.layer().knownCellCount(), 1000u);

  SharedMap resumed(mapConfig());
  const ResumedMap report = resumeSavedMap(prefix() + ".ot", &resumed.voxels(), &resumed.layer());
  EXPECT_TRUE(report.layer_found);
  EXPECT_FALSE(report.labels_only);
  EXPECT_EQ(report.layer_yaml, prefix() + ".laser.yaml");
  EXPECT_EQ(report.known_voxels, saved_.voxels().knownVoxelCount());
  EXPECT_EQ(report.layer_cells, saved_.layer().knownCellCount());
  EXPECT_EQ(voxelMismatches(saved_.voxels(), resumed.voxels()), 0u);
  EXPECT_EQ(cellMismatches(saved_.layer(), resumed.layer()), 0u);

  // Saving the resumed map gives the same layer files, byte for byte.
  std::vector<std::string> resaved;
  saveMapFiles(resumed, FusedGridConfig(), (folder_ / "again").string(), &resaved);
  for (const char* extension : {".laser.npy", ".ot"}) {
    std::ifstream a(prefix() + extension, std::ios::binary);
    std::ifstream b((folder_ / "again").string() + extension, std::ios::binary);
    EXPECT_TRUE(std::equal(std::istreambuf_iterator<char>(a), std::istreambuf_iterator<char>(),
                           std::istreambuf_iterator<char>(b), std::istreambuf_iterator<char>()))
        << extension;
  }
}

TEST_F(SavedMap, WithoutLayerFilesTheVoxelsResumeAndTheLayerStartsEmpty) {
  fs::remove(prefix() + ".laser.yaml");
  fs::remove(prefix() + ".laser.npy");
  SharedMap resumed(mapConfig());
  const ResumedMap report = resumeSavedMap(prefix() + ".ot", &resumed.voxels(), &resumed.layer());
  EXPECT_FALSE(report.layer_found);
  EXPECT_EQ(report.layer_cells, 0u);
  EXPECT_EQ(voxelMismatches(saved_.voxels(), resumed.voxels()), 0u);
}

TEST_F(SavedMap, BadLayerFilesStopTheResumeBeforeTheMapIsTouched) {
  // A layer of another save (its shape no longer matches the yaml), and a map of another
  // resolution whose .ot would load: neither may leave a half-resumed map.
  SharedMap other(mapConfig());
  other.layer().setLogOdds({0, 0}, 1.0f);
  writeLayerFiles(other.layer().toLogOddsRaster(), (folder_ / "other").string());
  fs::copy_file((folder_ / "other.laser.npy"), prefix() + ".laser.npy",
                fs::copy_options::overwrite_existing);
  SharedMap resumed(mapConfig());
  try {
    resumeSavedMap(prefix() + ".ot", &resumed.voxels(), &resumed.layer());
    ADD_FAILURE() << "a layer array of another save was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(prefix() + ".laser.npy"), std::string::npos)
        << error.what();
  }
  EXPECT_EQ(resumed.voxels().knownVoxelCount(), 0u);
  EXPECT_EQ(resumed.layer().knownCellCount(), 0u);

  SharedMap coarse(mapConfig(0.2));
  coarse.layer().setLogOdds({1, 1}, 1.0f);
  coarse.voxels().setLogOdds({1, 1, 1}, 1.0f);
  std::vector<std::string> files;
  saveMapFiles(coarse, FusedGridConfig(), (folder_ / "coarse").string(), &files);
  fs::copy_file(folder_ / "coarse.laser.yaml", prefix() + ".laser.yaml",
                fs::copy_options::overwrite_existing);
  fs::copy_file(folder_ / "coarse.laser.npy", prefix() + ".laser.npy",
                fs::copy_options::overwrite_existing);
  try {
    resumeSavedMap(prefix() + ".ot", &resumed.voxels(), &resumed.layer());
    ADD_FAILURE() << "a layer of another resolution was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("resolution"), std::string::npos) << error.what();
  }
  EXPECT_EQ(resumed.voxels().knownVoxelCount(), 0u);
  EXPECT_EQ(resumed.layer().knownCellCount(), 0u);
}

TEST(SavedMapPaths, LayerFilesAreFoundBesideEitherOctomapFile) {
  EXPECT_EQ(layerYamlBeside("/maps/site.ot"), "/maps/site.laser.yaml");
  EXPECT_EQ(layerYamlBeside("/maps/site.bt"), "/maps/site.laser.yaml");
  EXPECT_EQ(layerYamlBeside("relative/site.v2.ot"), "relative/site.v2.laser.yaml");
}

}  // namespace
}  // namespace occupancy_fusion
