// Frames for the mapping session made from the simulator's renderings (shared by the
// evaluations that drive a MappingSession with rendered sensors).
#pragma once

#include "occupancy_fusion/mapping/frames.h"
#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/stereo_camera.h"

namespace occupancy_fusion {

// A rendered disparity image of a camera with `baseline` (m) as a session frame.
DisparityFrame disparityFrameOf(const sim::DisparityImage& image, const sim::PinholeCamera& camera,
                                double baseline, const FrameHeader& header);

}  // namespace occupancy_fusion
