// benchmark dynamic: an object leaves the view of each mapper (eval/dynamic_scenes.h); per case
// the ghost it leaves in the map over the frames after it has gone, and how many frames the map
// takes to clear it (below 5 % of the voxels the object held).
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "occupancy_fusion/eval/dynamic_scenes.h"
#include "occupancy_fusion/tools/command_line.h"
#include "shipped_config.h"

namespace occupancy_fusion {
namespace {

std::vector<double> numbers(const CommandLine& args, const std::string& name,
                            const std::string& fallback) {
  std::vector<double> result;
  for (const std::string& item : args.listValue(name, fallback)) {
    try {
      result.push_back(std::stod(item));
    } catch (const std::exception&) {
      throw UsageError("--" + name + ": not a number: " + item);
    }
  }
  return result;
}

// The ghost (its part seen through) after n frames without the object (the last one mapped if
// fewer).
std::size_t after(const std::vector<std::size_t>& ghost, std::size_t n) {
  if (ghost.empty()) return 0;
  return ghost[std::min(n, ghost.size()) - 1];
}
std::size_t ghostAfter(const DynamicSceneResult& result, std::size_t n) {
  return after(result.ghost, n);
}
std::size_t seenThroughAfter(const DynamicSceneResult& result, std::size_t n) {
  return after(result.ghost_seen_through, n);
}

}  // namespace

int runDynamic(const CommandLine& args) {
  DynamicSceneCase base;
  base.mapping = shippedOrGivenMappingConfig(args);
  base.frames_before = args.intValue("frames_before", base.frames_before);
  base.frames_after = args.intValue("frames_after", base.frames_after);
  base.disparity_noise_px = args.doubleValue("noise_px", base.disparity_noise_px);
  base.rate_hz = args.doubleValue("rate_hz", base.rate_hz);
  std::vector<DynamicEvent> events;
  std::vector<DynamicMapper> mappers;
  try {
    for (const std::string& name : args.listValue("events", "removed_box,person,door,chair")) {
      events.push_back(dynamicEventFromString(name));
    }
    for (const std::string& name : args.listValue(
             "mappers", "depth,stereo,stereo_table_i,stereo_octomap,point_cloud,laser")) {
      mappers.push_back(dynamicMapperFromString(name));
    }
  } catch (const std::invalid_argument& error) {
    throw UsageError(error.what());
  }
  std::ofstream curves;
  if (args.has("curves")) {
    curves.open(args.value("curves"));
    if (!curves) throw UsageError("cannot write " + args.value("curves"));
    curves << "event,mapper,resolution,speed,frames_without_object,ghost,object_voxels,"
              "ghost_seen_through\n";
  }
  for (const DynamicEvent event : events) {
    for (const DynamicMapper mapper : mappers) {
      for (const double resolution : numbers(args, "resolution", "0.05,0.1")) {
        for (const double speed : numbers(args, "speed", "0,0.5")) {
          DynamicSceneCase setup = base;
          setup.event = event;
          setup.mapper = mapper;
          setup.resolution = resolution;
          setup.speed = speed;
          try {
            setup.validate();
          } catch (const std::invalid_argument& error) {
            throw UsageError(error.what());
          }
          const DynamicSceneResult result = evaluateDynamicScene(setup);
          std::printf(
              "dynamic event=%s mapper=%s resolution=%.2f speed=%.2f rate_hz=%.0f "
              "object_voxels=%zu ghost_after_1=%zu ghost_after_3=%zu ghost_after_5=%zu "
              "ghost_last=%zu frames_to_clear=%d seen_through_after_5=%zu "
              "frames_to_clear_seen_through=%d static_coverage=%.3f ms_per_frame=%.2f\n",
              toString(event).c_str(), toString(mapper).c_str(), resolution, speed, setup.rate(),
              result.object_voxels, ghostAfter(result, 1), ghostAfter(result, 3),
              ghostAfter(result, 5), ghostAfter(result, result.ghost.size()),
              result.frames_to_clear, seenThroughAfter(result, 5),
              result.frames_to_clear_seen_through, result.static_coverage, result.ms_per_frame);
          std::fflush(stdout);
          for (std::size_t i = 0; curves && i < result.ghost.size(); ++i) {
            curves << toString(event) << "," << toString(mapper) << "," << resolution << ","
                   << speed << "," << i + 1 << "," << result.ghost[i] << "," << result.object_voxels
                   << "," << result.ghost_seen_through[i] << "\n";
          }
        }
      }
    }
  }
  return 0;
}

}  // namespace occupancy_fusion
