// The dynamic-scene evaluation: an object that leaves the view of a sensor, and how long each
// mapper keeps its ghost. In the simulated corridor (sim::makeCorridorScene, with a room's wall
// 1.6 m behind its doorway) a sensor looks along the corridor, standing or moving along it, while
//  - removed_box: a box 0.8 x 1.0 x 0.5 m (x, y, z) stands 2.5-3.3 m ahead of the sensor's start
//    (x = 1 m) and is taken away after frame 15;
//  - person: a person-sized box 0.4 x 0.3 x 1.7 m walks across the corridor at 1 m/s, 4 m ahead
//    of the sensor's start (x = 13 m, in front of the end wall), and is gone at the far wall;
//  - door: a panel 1.0 x 0.2 x 2.0 m closes the doorway at x in [7, 8] for 15 frames, then opens
//    (is gone), 6 m ahead of the sensor's start (x = 1 m);
//  - chair: a box 0.5 x 0.5 x 0.9 m stands 2.6-3.1 m ahead, left of the axis, for 15 frames and
//    is moved 0.8 m across to the right and left there.
// The frames are rendered from the true poses and mapped by one mapper of the package (depth
// images, the stereo default or Table I, OctoMap's update on the same disparities, point clouds
// of the depth images, or a 2D laser into the laser layer). After each frame: ghost voxels
// (occupied, their centre in the volume the object held, grown by a voxel, farther than a voxel
// diagonal from the static scene, and in the sensor's view at that frame, in sight past the
// static scene; the laser layer's cells in its footprint) and of those the ones a ray of the
// sensor passes to a surface behind them, and at the end
// the coverage of the static surfaces 1-6 m ahead. Shared by `benchmark dynamic` and the tests.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "occupancy_fusion/mapping/mapping_session.h"

namespace occupancy_fusion {

enum class DynamicEvent { kRemovedBox, kPerson, kDoor, kChair };
enum class DynamicMapper {
  kDepth,
  kStereoDefault,
  kStereoTableI,
  kStereoOctomap,
  kPointCloud,
  kLaser
};
std::string toString(DynamicEvent event);
std::string toString(DynamicMapper mapper);
DynamicEvent dynamicEventFromString(const std::string& name);    // throws std::invalid_argument
DynamicMapper dynamicMapperFromString(const std::string& name);  // throws std::invalid_argument

struct DynamicSceneCase {
  // The mappers' settings (the shipped config files', as `benchmark dynamic` reads them); the
  // resolution and, for stereo_table_i and stereo_octomap, the stereo method are set per case.
  MappingSessionConfig mapping;
  DynamicEvent event = DynamicEvent::kRemovedBox;
  DynamicMapper mapper = DynamicMapper::kDepth;
  double resolution = 0.1;  // m
  double speed = 0.0;       // m/s of the sensor along the corridor (0: standing)
  // Frames per second: 15 for the cameras, 10 for the laser unless set (> 0).
  double rate_hz = 0.0;
  int frames_before = 15;           // frames with the object where it starts
  int frames_after = 25;            // frames after it has gone (left the view, for the person)
  double disparity_noise_px = 0.3;  // the stereo mappers' white disparity noise

  double rate() const;    // rate_hz, or the mapper's default
  void validate() const;  // throws std::invalid_argument naming the bad field
};

struct DynamicSceneResult {
  DynamicSceneCase setup;
  // Of the frames: the change's frame (the first without the object where it stood; for the
  // person, the first after it left the view), and per frame the ghost voxels (cells) and the
  // voxels (cells) the object held in the map at its most.
  int change_frame = 0;
  std::vector<std::size_t> ghost;
  std::size_t object_voxels = 0;
  // Of the ghost, per frame, the voxels (cells) the sensor sees through: a ray of it through
  // the voxel returns from a static surface beyond it by more than a voxel diagonal and three
  // of the sensor's range sigmas at that range (stereo: the disparity noise as range), within
  // its range. Only these can be measured free; the rest (behind them only rays without a
  // return, or a surface within the sensor's range error) stays until the sensor moves.
  std::vector<std::size_t> ghost_seen_through;
  // Frames without the object (from the change on) after which the ghost (its part seen
  // through) stays below 5 % of object_voxels; -1: not within the frames mapped.
  int frames_to_clear = -1;
  int frames_to_clear_seen_through = -1;
  double static_coverage = 0.0;  // of the corridor's surfaces in view at the end
  double ms_per_frame = 0.0;
};

DynamicSceneResult evaluateDynamicScene(const DynamicSceneCase& setup);

}  // namespace occupancy_fusion
