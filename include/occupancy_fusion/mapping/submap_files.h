// The submaps of a map that follows its localisation (map_reanchoring.h), in a file beside the
// map's: <prefix>.submaps next to <prefix>.ot. Saved with the map, they are read back when the
// map is resumed, so that what was mapped before a restart still moves with later corrections.
// Host byte order: a file of this machine's kind.
#pragma once

#include <string>

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

}  // namespace occupancy_fusion
