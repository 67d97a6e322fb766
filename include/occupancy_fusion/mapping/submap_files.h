// The submaps of a map that follows its localisation (map_reanchoring.h), kept with the map: in a
// file beside the map's (<prefix>.submaps next to <prefix>.ot), and in the map's checkpoints.
// Resumed with the map, they make what was mapped before a restart (or a SIGKILL) still move with
// later corrections. Host byte order: files of this machine's kind.
#pragma once

#include <string>

#include "occupancy_fusion/map/map_checkpoints.h"
#include "occupancy_fusion/mapping/map_reanchoring.h"

namespace occupancy_fusion {

// <prefix>.submaps for a map file or prefix ("run.ot", "run.bt" or "run").
std::string submapFilePath(const std::string& map_path);

// Writes the submaps (closing the one being written) to `path`, atomically (a temporary file,
// then a rename). Throws std::runtime_error naming the path when it cannot be written.
void writeSubmapFile(MapReanchoring* reanchoring, const std::string& path);

// Reads them back into a reanchoring whose map holds what was saved with them: false when there
// is no such file. Throws std::runtime_error naming the path for a file that cannot be read or is
// no such save (the map's contents then stay where they are, as one fixed submap).
bool readSubmapFile(MapReanchoring* reanchoring, const std::string& path);

// A checkpoint of the map with its submaps, in one transaction of the map's store, while no
// frame is written.
CheckpointResult checkpointWithSubmaps(MapCheckpoints* checkpoints, MapReanchoring* reanchoring,
                                       const std::string& stamp);

// The submaps of the checkpoint the map resumed, back into `reanchoring`: false when it holds
// none. Throws std::runtime_error when they are damaged (the map's contents then stay where they
// are, as one fixed submap).
bool resumeCheckpointedSubmaps(const MapCheckpoints& checkpoints, MapReanchoring* reanchoring);

}  // namespace occupancy_fusion
