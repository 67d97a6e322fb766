// The one map saver (the MapServer's ~save_map and offline_mapper): which files, when the 2D files
// are left out, and that an empty map overwrites nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "../../common/test_folder.h"
#include "occupancy_fusion/map/layer_files.h"
#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/mapping/map_saving.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

VoxelMapConfig mapConfig() {
  VoxelMapConfig config;
  config.resolution = 0.1;
  return config;
}

GridLayer2DConfig layerConfig() {
  GridLayer2DConfig config;
  config.resolution = 0.1;
  return config;
}

class MapSaving : public TestFolder {
 protected:
  std::vector<std::string> names(const std::vector<std::string>& written) const {
    std::vector<std::string> result;
    for (const std::string& file : written) result.push_back(fs::path(file).filename().string());
    return result;
  }
};

TEST_F(MapSaving, WritesTheMapFilesAndTheInspectionFilesWhenAsked) {
  VoxelMap voxels(mapConfig());
  GridLayer2D layer(layerConfig());
  voxels.setLogOdds({1, 2, 5}, 2.0f);   // z = 0.55 m: in the default band
  voxels.setLogOdds({1, 3, 40}, 1.0f);  // z = 4.05 m: above it
  layer.setLogOdds({-3, 4}, -1.5f);
  std::vector<std::string> written;
  MapSaveOptions options;
  options.band.min_z = 0.1;
  options.band.max_z = 2.0;
  const SavedMapFiles saved = saveMap(voxels, layer, path("site"), options, &written);
  EXPECT_EQ(names(written), (std::vector<std::string>{"site.ot", "site.bt", "site.pgm", "site.yaml",
                                                      "site.laser.npy", "site.laser.yaml"}));
  // The 2D view spans the voxel column and the layer cell: x from -3 to 1, y from 2 to 4.
  EXPECT_EQ(saved.grid_width, 5);
  EXPECT_EQ(saved.grid_height, 3);
  const std::unique_ptr<VoxelMap> back = readOctomapFile(path("site.ot"), mapConfig());
  EXPECT_EQ(back->knownVoxelCount(), 2u);
  EXPECT_FLOAT_EQ(*back->logOdds({1, 3, 40}), 1.0f);
  EXPECT_FLOAT_EQ(readLayerFiles(path("site.laser.yaml")).data.front(), -1.5f);

  options.inspection_files = true;
  std::vector<std::string> all;
  saveMap(voxels, layer, path("all"), options, &all);
  EXPECT_EQ(names(all),
            (std::vector<std::string>{"all.ot", "all.bt", "all.pgm", "all.yaml", "all.laser.npy",
                                      "all.laser.yaml", "all.pcd", "all.npy", "all.png"}));
}

TEST_F(MapSaving, WithoutA2DViewThe2DFilesAreLeftOut) {
  VoxelMap voxels(mapConfig());
  GridLayer2D layer(layerConfig());
  voxels.setLogOdds({1, 3, 40}, 1.0f);  // above the band only
  std::vector<std::string> written;
  MapSaveOptions options;
  options.band.min_z = 0.1;
  options.band.max_z = 2.0;
  options.inspection_files = true;
  const SavedMapFiles saved = saveMap(voxels, layer, path("tall"), options, &written);
  EXPECT_EQ(saved.grid_width, 0);
  EXPECT_EQ(names(written), (std::vector<std::string>{"tall.ot", "tall.bt", "tall.laser.npy",
                                                      "tall.laser.yaml", "tall.pcd"}));
}

TEST_F(MapSaving, AnEmptyMapOverwritesNothing) {
  { std::ofstream(path("kept.ot")) << "previous"; }
  VoxelMap voxels(mapConfig());
  GridLayer2D layer(layerConfig());
  std::vector<std::string> written;
  EXPECT_THROW(saveMap(voxels, layer, path("kept"), MapSaveOptions(), &written),
               std::runtime_error);
  EXPECT_TRUE(written.empty());
  std::ifstream in(path("kept.ot"));
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "previous");
  EXPECT_FALSE(fs::exists(path("kept.bt")));
}

}  // namespace
}  // namespace occupancy_fusion
