// Reader of the stereo integrator's configuration over any ParameterSource (the ROS parameter
// server in the DisparityMapper nodelet, a YAML file in offline_mapper and benchmark), so that
// every front end configures VisibilityStereoIntegrator the same way. Kept apart from
// config_readers.h because the map library, which holds those readers, must not depend on the
// integrators library.
#pragma once

#include <string>

#include "occupancy_fusion/integrators/stereo/visibility_stereo_config.h"
#include "occupancy_fusion/params/parameter_source.h"

namespace occupancy_fusion {

// Every parameter lives under this prefix ("stereo/method", ...).
inline const std::string kStereoParameterPrefix = "stereo/";

// Reads, under stereo/ (absent keys keep the values of parameter_set, by default the in-class
// defaults, i.e. the paper's Table I):
//   parameter_set                   table_i | fast_expansion (StereoParameterSet), read first
//   method                          visibility | octomap
//   prob_hit_visible_occupied       P(H | V, O)
//   prob_hit_visible_free           P(H | V, not O)
//   prob_hit_invisible              P(H | not V)
//   prob_visible_if_occluded        P(V_i | C_i, V_i-1)      (Eq. 3)
//   prob_visible_if_not_occluded    P(V_i | not C_i, V_i-1)  (Eq. 3)
//   visibility_min, visibility_max  q_min, q_max
//   unknown_occupancy               prior P(O) of never-observed voxels (Eq. 4-6)
//   unknown_neighbour_occupancy     P(O) of a never-observed neighbour in Eq. 1
//   inside_stop_probability         P(I_v) at which a ray stops (Eq. 8)
//   max_range                       m, negative = unlimited
//   disparity_sigma_px              px, sigma_d of Eq. 7
//   min_disparity_px                px, smaller disparities are dropped
//   max_depth_sigma_ratio           points with a larger sigma_z / z (Eq. 7) are dropped
//   input_resolution                full | half | quarter
// Validates the result; throws std::invalid_argument whose message names the offending
// parameter (e.g. "stereo/visibility_min ...").
VisibilityStereoConfig readVisibilityStereoConfig(const ParameterSource& source);

}  // namespace occupancy_fusion
