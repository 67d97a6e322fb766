// Reader of the depth mapper's configuration over any ParameterSource (the ROS parameter server in
// the DepthMapper nodelet, a YAML file in offline_mapper and benchmark), so both configure the
// pyramidal depth integrator the same way. Keys live under "depth/"; absent keys keep
// PyramidDepthConfig's in-class defaults.
#pragma once

#include "occupancy_fusion/integrators/depth/pyramid_depth_config.h"
#include "occupancy_fusion/params/parameter_source.h"

namespace occupancy_fusion {

// depth/method (pyramid | andert | ideal), depth/k, depth/sigma (m), depth/sigma_quadratic
// (1/m), depth/min_range (m), depth/max_range (m), depth/unknown_behind_sigmas,
// depth/max_pyramid_levels, depth/finer_layers, depth/clear_passed, depth/passed_sigmas,
// depth/passed_miss_probability. Validates what it read; throws std::invalid_argument naming the
// offending parameter by its key (e.g. "depth/sigma").
PyramidDepthConfig readPyramidDepthConfig(const ParameterSource& source);

}  // namespace occupancy_fusion
