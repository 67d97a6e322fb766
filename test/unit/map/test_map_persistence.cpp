// Nothing lost (docs/reliability.md): a save that fails part-way leaves the previous file as it
// was, and a map loaded from an .ot file into a live map (what the MapServer's ~load_map does)
// resumes with every log-odds bit-exact, visible to the change log and the fused view, and
// further updates start from the loaded values.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/resource.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>

#include "../../common/test_folder.h"
#include "occupancy_fusion/map/fused_grid.h"
#include "occupancy_fusion/map/map_files.h"
#include "occupancy_fusion/map/octomap_conversion.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

using MapPersistence = TestFolder;

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

VoxelMapConfig mapConfig() {
  VoxelMapConfig config;
  config.resolution = 0.05;
  return config;
}

// Known voxels with varied log-odds (hits and misses accumulated, some clamped) over many blocks.
void fillRandom(VoxelMap* map, unsigned seed, int voxels) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> coordinate(-60, 60);
  std::uniform_int_distribution<int> hits(-6, 6);
  const float hit = static_cast<float>(map->model().hitLogOdds());
  const float miss = static_cast<float>(map->model().missLogOdds());
  for (int i = 0; i < voxels; ++i) {
    const VoxelIndex index(coordinate(random), coordinate(random), coordinate(random) / 4);
    const int count = hits(random);
    for (int k = 0; k < std::abs(count) + 1; ++k) map->updateVoxel(index, count >= 0 ? hit : miss);
  }
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

TEST_F(MapPersistence, FailedWriteKeepsThePreviousFileAndNamesThePath) {
  const std::string target = path("map.ot");
  VoxelMap old_map(mapConfig());
  fillRandom(&old_map, 1, 200);
  writeOt(old_map, target);
  const std::string previous = readBytes(target);
  ASSERT_GT(previous.size(), 1000u);

  // The writer fails after half the bytes are out.
  try {
    writeFileAtomically(target, [&](std::ostream& out) {
      out << std::string(previous.size() / 2, 'x');
      out.flush();
      throw std::runtime_error("simulated failure");
    });
    FAIL() << "the failure was swallowed";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(target), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("simulated failure"), std::string::npos);
  }
  EXPECT_EQ(readBytes(target), previous);

  // A real write error: the operating system refuses to let the file grow past 4 KiB (as a full
  // disk would), in the middle of writing a larger map with the real writer.
  VoxelMap new_map(mapConfig());
  fillRandom(&new_map, 2, 2000);
  rlimit original{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &original), 0);
  rlimit small = original;
  small.rlim_cur = 4096;
  auto* previous_handler = signal(SIGXFSZ, SIG_IGN);  // write() then fails with EFBIG
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  bool threw = false;
  std::string message;
  try {
    writeOt(new_map, target);
  } catch (const std::runtime_error& error) {
    threw = true;
    message = error.what();
  }
  setrlimit(RLIMIT_FSIZE, &original);
  signal(SIGXFSZ, previous_handler);
  ASSERT_TRUE(threw) << "writing past the file size limit succeeded";
  EXPECT_NE(message.find(target), std::string::npos) << message;
  EXPECT_EQ(readBytes(target), previous);

  // Renaming onto something that cannot be replaced (a folder) fails after the whole file was
  // written: the folder stays and no temporary file is left (TearDown).
  fs::create_directories(path("taken.ot/inside"));
  EXPECT_THROW(writeOt(new_map, path("taken.ot")), std::runtime_error);
  EXPECT_TRUE(fs::is_directory(path("taken.ot/inside")));

  // The map server's other formats fail the same way into a missing folder.
  const OccupancyRaster raster = projectToRaster(new_map, nullptr, FusedGridConfig());
  for (const std::string& bad : {path("missing/map.bt"), path("missing/map")}) {
    try {
      if (bad.size() > 3 && bad.compare(bad.size() - 3, 3, ".bt") == 0) {
        writeBt(new_map, bad);
      } else {
        writeMapServerFiles(raster, bad);
      }
      FAIL() << "wrote into a missing folder: " << bad;
    } catch (const std::runtime_error& error) {
      EXPECT_NE(std::string(error.what()).find(bad), std::string::npos) << error.what();
    }
  }
}

TEST_F(MapPersistence, LoadedOtResumesExactlyAndIsSeenByConsumers) {
  VoxelMap saved(mapConfig());
  fillRandom(&saved, 3, 3000);
  writeOt(saved, path("saved.ot"));

  // A live map, as the MapServer's shared map at start, already watched by a publisher.
  VoxelMap live(mapConfig());
  const std::uint64_t watched_from = live.changesSince(0).version;
  FusedGridView view;
  EXPECT_TRUE(view.update(live, nullptr).empty());

  const std::unique_ptr<octomap::OcTree> tree = readOcTreeFile(path("saved.ot"), live.model());
  fromOcTree(*tree, &live);

  // Every log-odds bit-exact, nothing more.
  EXPECT_EQ(live.knownVoxelCount(), saved.knownVoxelCount());
  std::size_t mismatches = 0;
  saved.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    const std::optional<float> back = live.logOdds(index);
    if (!back || !sameBits(*back, log_odds)) ++mismatches;
  });
  EXPECT_EQ(mismatches, 0u);

  // The change log reports every loaded block, so publishers send them on their next cycle.
  const MapChanges changes = live.changesSince(watched_from);
  EXPECT_FALSE(changes.full_rebuild);
  std::set<std::tuple<int, int, int>> reported, expected;
  for (const BlockIndex& b : changes.changed) reported.insert({b.x(), b.y(), b.z()});
  saved.forEachBlock([&](const BlockIndex& b, const VoxelBlock&) {
    expected.insert({b.x(), b.y(), b.z()});
  });
  EXPECT_EQ(reported, expected);
  const OccupancyRaster published = view.update(live, nullptr);
  const OccupancyRaster reference = projectToRaster(saved, nullptr, FusedGridConfig());
  EXPECT_FALSE(published.empty());
  EXPECT_EQ(published.data, reference.data);
  EXPECT_EQ(published.width, reference.width);

  // Mapping goes on from the loaded values: a hit adds to them, clamped as usual.
  const float hit = static_cast<float>(live.model().hitLogOdds());
  std::size_t checked = 0;
  saved.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    if (checked >= 50) return;
    ++checked;
    live.updateVoxel(index, hit);
    const float expected_value = std::min(log_odds + hit, live.maxLogOdds());
    EXPECT_FLOAT_EQ(*live.logOdds(index), expected_value);
  });
  EXPECT_EQ(checked, 50u);
}

TEST_F(MapPersistence, DamagedFilesAreRejectedNamingTheFile) {
  VoxelMap saved(mapConfig());
  fillRandom(&saved, 4, 2000);
  writeOt(saved, path("saved.ot"));
  const std::string bytes = readBytes(path("saved.ot"));
  // Cut in the middle of the tree data, as a copy interrupted or a disk full while copying would.
  { std::ofstream(path("truncated.ot"), std::ios::binary) << bytes.substr(0, bytes.size() / 2); }
  { std::ofstream(path("empty.ot"), std::ios::binary); }
  // liboctomap alone would return part of the tree from the truncated file: readOcTreeFile checks
  // the node data against the header's node count first.
  try {
    readOcTreeFile(path("truncated.ot"), saved.model());
    ADD_FAILURE() << "the truncated file was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("truncated"), std::string::npos) << error.what();
  }
  EXPECT_EQ(readOcTreeFile(path("saved.ot"), saved.model())->size(), toOcTree(saved)->size());
  for (const char* name : {"truncated.ot", "empty.ot", "absent.ot"}) {
    try {
      readOcTreeFile(path(name), saved.model());
      ADD_FAILURE() << name << " was accepted";
    } catch (const std::runtime_error& error) {
      EXPECT_NE(std::string(error.what()).find(path(name)), std::string::npos) << error.what();
    }
  }
  // A header whose node count differs from the data, and one leaf (the root) that would cover
  // 2^48 voxels: both refused, naming the file.
  const std::string header = "# Octomap OcTree file\nid OcTree\nsize 2\nres 0.05\ndata\n";
  const float log_odds = 1.5f;
  const std::string root_leaf =
      std::string(reinterpret_cast<const char*>(&log_odds), sizeof(log_odds)) + '\0';
  { std::ofstream(path("miscounted.ot"), std::ios::binary) << header << root_leaf; }
  std::string one_node = header;
  one_node.replace(one_node.find("size 2"), 6, "size 1");
  { std::ofstream(path("root_leaf.ot"), std::ios::binary) << one_node << root_leaf; }
  for (const char* name : {"miscounted.ot", "root_leaf.ot"}) {
    try {
      readOctomapFile(path(name), mapConfig());
      ADD_FAILURE() << name << " was accepted";
    } catch (const std::runtime_error& error) {
      EXPECT_NE(std::string(error.what()).find(path(name)), std::string::npos) << error.what();
    }
  }
  EXPECT_EQ(readOcTreeFile(path("root_leaf.ot"), saved.model())->size(), 1u);

  // A file of another resolution does not go into a live map of this one.
  VoxelMapConfig coarse = mapConfig();
  coarse.resolution = 0.1;
  VoxelMap live(coarse);
  const std::unique_ptr<octomap::OcTree> tree = readOcTreeFile(path("saved.ot"), live.model());
  EXPECT_THROW(fromOcTree(*tree, &live), std::invalid_argument);
  EXPECT_EQ(live.knownVoxelCount(), 0u);
}

}  // namespace
}  // namespace occupancy_fusion
