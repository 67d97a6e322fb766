#include "occupancy_fusion/ros/saved_map.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <stdexcept>

#include "occupancy_fusion/map/layer_files.h"
#include "occupancy_fusion/map/octomap_conversion.h"

namespace occupancy_fusion {
namespace {

bool hasExtension(const std::string& path, const std::string& extension) {
  return std::filesystem::path(path).extension() == extension;
}

// liboctomap reads a truncated file (an interrupted copy) without complaint, returning part of the
// tree. Its header states the node count ("size N" before the "data" line): compare.
void requireCompleteTree(const std::string& path, const octomap::OcTree& tree) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  long long declared = -1;
  while (std::getline(in, line) && line != "data") {
    if (line.rfind("size ", 0) == 0) declared = std::stoll(line.substr(5));
  }
  if (declared >= 0 && static_cast<std::size_t>(declared) != tree.size()) {
    throw std::runtime_error("the file is incomplete: its header declares " +
                             std::to_string(declared) + " tree nodes, " +
                             std::to_string(tree.size()) + " could be read");
  }
}

}  // namespace

std::string layerYamlBeside(const std::string& octomap_path) {
  std::filesystem::path prefix(octomap_path);
  if (hasExtension(octomap_path, ".ot") || hasExtension(octomap_path, ".bt")) {
    prefix.replace_extension();
  }
  return layerFilePaths(prefix.string()).yaml;
}

ResumedMap resumeSavedMap(const std::string& path, SharedMap* map) {
  ResumedMap resumed;
  const std::unique_ptr<octomap::OcTree> tree = readOcTreeFile(path, map->voxels().model());
  try {
    requireCompleteTree(path, *tree);
  } catch (const std::exception& error) {
    throw std::runtime_error(path + ": " + error.what());
  }
  resumed.layer_yaml = layerYamlBeside(path);
  std::optional<LogOddsRaster> layer;
  if (std::filesystem::exists(resumed.layer_yaml)) {
    layer = readLayerFiles(resumed.layer_yaml);
    if (std::abs(layer->resolution - map->layer().resolution()) >
        1e-9 * map->layer().resolution()) {
      throw std::runtime_error(resumed.layer_yaml + ": resolution " +
                               std::to_string(layer->resolution) + " m, the map's is " +
                               std::to_string(map->layer().resolution()) + " m");
    }
  }
  resumed.known_voxels_before = map->voxels().knownVoxelCount();
  fromOcTree(*tree, &map->voxels());  // one write: the change log reports every loaded block
  resumed.known_voxels = map->voxels().knownVoxelCount();
  resumed.labels_only = hasExtension(path, ".bt");
  if (layer) {
    map->layer().importRaster(*layer);  // one write, as the voxels
    resumed.layer_found = true;
  }
  resumed.layer_cells = map->layer().knownCellCount();
  return resumed;
}

}  // namespace occupancy_fusion
