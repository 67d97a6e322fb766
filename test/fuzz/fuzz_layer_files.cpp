// Laser layer file loading: the yaml's text and the .npy's bytes -> LogOddsRaster
// (parseLayerFiles, the body of readLayerFiles, src/map/layer_files.cpp) -> GridLayer2D
// (importRaster), as the MapServer's load_map does. Any input must be rejected with
// std::runtime_error or give a raster whose every known value is finite and lands in the layer.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_input.h"
#include "occupancy_fusion/map/layer_files.h"

namespace occupancy_fusion {
namespace fuzz {
namespace {

// The input: the yaml (at most 255 bytes) then the .npy (at most 64 KiB).
template <typename Io>
void describeLayerFiles(Io* io, std::string* yaml, std::vector<char>* npy) {
  io->field(yaml);
  io->bytes(npy);
}

}  // namespace

void writeSeeds() {
  GridLayer2DConfig config;
  config.resolution = 0.05;
  GridLayer2D layer(config);
  for (int i = 0; i < 40; ++i) layer.setLogOdds({i % 9 - 4, i / 9 - 2}, i % 2 ? 1.5f : -0.7f);
  const char* folder = std::getenv("FUZZ_SEED_DIR");
  if (folder == nullptr || *folder == '\0') return;
  const LayerFilePaths paths =
      writeLayerFiles(layer.toLogOddsRaster(), std::string(folder) + "/layer_files_tmp");
  const auto read = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::vector<char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  const std::vector<char> yaml_bytes = read(paths.yaml);
  std::string yaml(yaml_bytes.begin(), yaml_bytes.end());
  std::vector<char> npy = read(paths.npy);
  std::remove(paths.yaml.c_str());
  std::remove(paths.npy.c_str());
  writeSeed("seed_layer", encodeFields(&describeLayerFiles<FuzzWriter>, &yaml, &npy));
}

}  // namespace fuzz
}  // namespace occupancy_fusion

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occupancy_fusion;
  std::string yaml;
  std::vector<char> npy;
  fuzz::decodeFields(&fuzz::describeLayerFiles<fuzz::FuzzReader>, data, size, &yaml, &npy);
  LogOddsRaster raster;
  try {
    raster = parseLayerFiles(yaml, std::string(npy.begin(), npy.end()));
  } catch (const std::runtime_error&) {
    return 0;
  }
  std::size_t known = 0;
  for (const float value : raster.data) {
    if (std::isinf(value)) std::abort();
    if (!std::isnan(value)) ++known;
  }
  GridLayer2DConfig config;
  config.resolution = raster.resolution;
  GridLayer2D layer(config);
  layer.importRaster(raster);
  if (layer.knownCellCount() != known) std::abort();
  return 0;
}
