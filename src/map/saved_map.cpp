#include "occupancy_fusion/map/saved_map.h"

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

ResumedMap resumeSavedMap(const std::string& path, VoxelMap* voxels, GridLayer2D* layer) {
  ResumedMap resumed;
  const std::unique_ptr<octomap::OcTree> tree = readOcTreeFile(path, voxels->model());
  try {
    requireCompleteTree(path, *tree);
  } catch (const std::exception& error) {
    throw std::runtime_error(path + ": " + error.what());
  }
  resumed.layer_yaml = layerYamlBeside(path);
  std::optional<LogOddsRaster> saved_layer;
  if (std::filesystem::exists(resumed.layer_yaml)) {
    saved_layer = readLayerFiles(resumed.layer_yaml);
    if (std::abs(saved_layer->resolution - layer->resolution()) > 1e-9 * layer->resolution()) {
      throw std::runtime_error(resumed.layer_yaml + ": resolution " +
                               std::to_string(saved_layer->resolution) + " m, the map's is " +
                               std::to_string(layer->resolution()) + " m");
    }
  }
  resumed.known_voxels_before = voxels->knownVoxelCount();
  try {
    fromOcTree(*tree, voxels);  // one write: the change log reports every loaded block
  } catch (const std::invalid_argument& error) {  // another resolution, too many voxels
    throw std::runtime_error(path + ": " + error.what());
  }
  resumed.known_voxels = voxels->knownVoxelCount();
  resumed.labels_only = hasExtension(path, ".bt");
  if (saved_layer) {
    layer->importRaster(*saved_layer);  // one write, as the voxels
    resumed.layer_found = true;
  }
  resumed.layer_cells = layer->knownCellCount();
  return resumed;
}

}  // namespace occupancy_fusion
