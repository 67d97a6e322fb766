// The open CPU mappers a user would pick instead of this package, run on the same clouds as
// liboctomap in the benchmarks: Bonxai's ProbabilisticMap and UFOMap's OccupancyMap. Neither is
// a dependency: each is compiled in when its install folder is given to CMake
// (-DBONXAI_ROOT=..., -DUFOMAP_ROOT=...; docs/benchmarks.md says how to build them), and left out
// otherwise.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace occupancy_fusion {
namespace bench {

struct PeerRun {
  std::string name;        // e.g. "bonxai", "ufomap_discrete"
  double median_ms = 0.0;  // per cloud, wall
  double cpu_ms = 0.0;  // per cloud, mean CPU of the inserting thread (every peer inserts on one)
  double memory_mb = 0.0;  // the map's own figure after the last cloud
  // The median over the clouds of ours' time over the peer's, each pair timed back to back
  // (see PairedInsert); NaN without one.
  double paired_ratio = std::numeric_limits<double>::quiet_NaN();
};

// This package's insertion of cloud i (or of the frame it came from) into a map of its own (a
// new one when i is 0), returning its wall milliseconds. runPeers calls it just before each
// peer inserts the same cloud, so that a ratio is taken from two runs milliseconds apart: on a
// shared machine whose speed drifts by tens of percent within a run, the ratio of two medians
// taken seconds apart does not hold still.
using PairedInsert = std::function<double(std::size_t cloud)>;

// The peers compiled in, in a fixed order; empty when none is.
std::vector<std::string> compiledPeers();

// Each compiled peer inserting every cloud (world frame, sensor at origins[i]) into one map of
// the given voxel size, with the hit / miss / clamping probabilities of OccupancyModel and no
// range limit, in the peer's recommended fast mode.
std::vector<PeerRun> runPeers(const std::vector<std::vector<Eigen::Vector3f>>& clouds,
                              const std::vector<Eigen::Vector3d>& origins, double resolution,
                              const PairedInsert& ours = {});

}  // namespace bench
}  // namespace occupancy_fusion
