// How a nodelet gets its shared map: read the map parameters from its private namespace and
// acquire the map of that name from the process-wide registry, logging what happened.
#pragma once

#include <memory>
#include <string>

#include "occupancy_fusion/params/parameter_source.h"
#include "occupancy_fusion/ros/map_registry.h"

namespace occupancy_fusion {

// Throws std::invalid_argument naming the parameter when the parameters are invalid or
// disagree with an existing map of the same name. Warns when the existing map's sensor model or
// memory bound differ from this nodelet's parameters (the first user's settings stay).
std::shared_ptr<SharedMap> acquireSharedMap(const ParameterSource& parameters,
                                            const std::string& nodelet_name);

}  // namespace occupancy_fusion
