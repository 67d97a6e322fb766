#include "shipped_config.h"

#include <exception>
#include <string>
#include <vector>

#include "occupancy_fusion/tools/yaml_parameter_source.h"

namespace occupancy_fusion {

MappingSessionConfig shippedOrGivenMappingConfig(const CommandLine& args) {
  std::vector<std::string> files = args.values("config");
  if (files.empty()) {
    for (const char* name :
         {"depth_mapper", "laser_mapper", "disparity_mapper", "point_cloud_mapper", "map_server"}) {
      files.push_back(std::string(OCCUPANCY_FUSION_SOURCE_DIR) + "/config/" + name + ".yaml");
    }
  }
  try {
    return readMappingSessionConfig(YamlParameterSource::fromFiles(files, ""));
  } catch (const std::exception& error) {
    throw UsageError(std::string("--config: ") + error.what());
  }
}

}  // namespace occupancy_fusion
