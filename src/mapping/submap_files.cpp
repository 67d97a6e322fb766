#include "occupancy_fusion/mapping/submap_files.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace occupancy_fusion {

std::string submapFilePath(const std::string& map_path) {
  const std::filesystem::path path(map_path);
  const std::string extension = path.extension().string();
  const bool map_file = extension == ".ot" || extension == ".bt";
  return (map_file ? path.parent_path() / path.stem() : path).string() + ".submaps";
}

void writeSubmapFile(MapReanchoring* reanchoring, const std::string& path) {
  const std::string temporary = path + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + temporary);
    reanchoring->save(out);
    out.flush();
    if (!out) throw std::runtime_error("cannot write " + temporary);
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::remove(temporary.c_str());
    throw std::runtime_error("cannot write " + path + ": " + error.message());
  }
}

bool readSubmapFile(MapReanchoring* reanchoring, const std::string& path) {
  if (!std::filesystem::exists(path)) return false;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  try {
    reanchoring->restore(in);
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(path + ": " + error.what());
  }
  return true;
}

CheckpointResult checkpointWithSubmaps(MapCheckpoints* checkpoints, MapReanchoring* reanchoring,
                                       const std::string& stamp) {
  std::ostringstream bytes;
  CheckpointResult result;
  reanchoring->saveThen(bytes, [&] {
    const std::string text = bytes.str();
    const std::vector<unsigned char> companion(text.begin(), text.end());
    result = checkpoints->checkpoint(stamp, &companion);
  });
  return result;
}

bool resumeCheckpointedSubmaps(const MapCheckpoints& checkpoints, MapReanchoring* reanchoring) {
  const std::vector<unsigned char>& bytes = checkpoints.resumedCompanion();
  if (bytes.empty()) return false;
  std::istringstream in(std::string(bytes.begin(), bytes.end()));
  try {
    reanchoring->restore(in);
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(std::string("the checkpoint's submaps: ") + error.what());
  }
  return true;
}

}  // namespace occupancy_fusion
