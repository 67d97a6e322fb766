// The mappers' settings a benchmark maps with: the `--config FILE ...` given, else the shipped
// config files, as mapping.launch loads them.
#pragma once

#include "occupancy_fusion/mapping/mapping_session.h"
#include "occupancy_fusion/tools/command_line.h"

namespace occupancy_fusion {

// Throws UsageError naming --config when a file cannot be read or holds a bad value.
MappingSessionConfig shippedOrGivenMappingConfig(const CommandLine& args);

}  // namespace occupancy_fusion
