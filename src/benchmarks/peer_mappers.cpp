#include "occupancy_fusion/benchmarks/peer_mappers.h"

#include <limits>

#include "occupancy_fusion/benchmarks/benchmark_harness.h"
#include "occupancy_fusion/map/occupancy_model.h"

#ifdef OCCUPANCY_FUSION_WITH_BONXAI
#include <bonxai_map/probabilistic_map.hpp>
#endif
#ifdef OCCUPANCY_FUSION_WITH_UFOMAP
#include <ufo/map/occupancy_map.h>
#endif

namespace occupancy_fusion {
namespace bench {
namespace {

// The median wall milliseconds of insert(i) over the clouds, and with `ours` the median of
// ours(i) / insert(i), ours(i) run just before.
template <typename Insert>
void timeEach(std::size_t clouds, const PairedInsert& ours, Insert&& insert, PeerRun* run) {
  std::vector<double> ms, ratios;
  double cpu_ms = 0.0;
  for (std::size_t i = 0; i < clouds; ++i) {
    const double ours_ms = ours ? ours(i) : 0.0;
    const double cpu_start = threadCpuMilliseconds();
    const Clock::time_point start = Clock::now();
    insert(i);
    ms.push_back(millisecondsSince(start));
    cpu_ms += threadCpuMilliseconds() - cpu_start;
    if (ours) ratios.push_back(ours_ms / ms.back());
  }
  run->median_ms = median(ms);
  run->cpu_ms = clouds == 0 ? 0.0 : cpu_ms / clouds;
  if (!ratios.empty()) run->paired_ratio = median(ratios);
}

#ifdef OCCUPANCY_FUSION_WITH_BONXAI
PeerRun runBonxai(const std::vector<std::vector<Eigen::Vector3f>>& clouds,
                  const std::vector<Eigen::Vector3d>& origins, double resolution,
                  const PairedInsert& ours) {
  const OccupancyModel model;
  Bonxai::ProbabilisticMap map(resolution);
  Bonxai::ProbabilisticMap::Options options;
  options.prob_hit_log = Bonxai::ProbabilisticMap::logods(static_cast<float>(model.prob_hit));
  options.prob_miss_log = Bonxai::ProbabilisticMap::logods(static_cast<float>(model.prob_miss));
  options.clamp_min_log = Bonxai::ProbabilisticMap::logods(static_cast<float>(model.clamp_min));
  options.clamp_max_log = Bonxai::ProbabilisticMap::logods(static_cast<float>(model.clamp_max));
  map.setOptions(options);
  // Its insertPointCloud takes the points and the origin in one type.
  std::vector<std::vector<Eigen::Vector3d>> points(clouds.size());
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    for (const Eigen::Vector3f& p : clouds[i]) points[i].push_back(p.cast<double>());
  }
  PeerRun run{"bonxai"};
  timeEach(
      clouds.size(), ours,
      [&](std::size_t i) {
        map.insertPointCloud(points[i], origins[i], std::numeric_limits<double>::infinity());
      },
      &run);
  run.memory_mb = map.grid().memUsage() * 1e-6;
  return run;
}
#endif

#ifdef OCCUPANCY_FUSION_WITH_UFOMAP
PeerRun runUfomap(const std::vector<std::vector<Eigen::Vector3f>>& clouds,
                  const std::vector<Eigen::Vector3d>& origins, double resolution,
                  const PairedInsert& ours) {
  const OccupancyModel model;
  ufo::map::OccupancyMap map(resolution);
  map.setProbHit(model.prob_hit);
  map.setProbMiss(model.prob_miss);
  map.setClampingThresMin(model.clamp_min);
  map.setClampingThresMax(model.clamp_max);
  std::vector<ufo::map::PointCloud> points(clouds.size());
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    for (const Eigen::Vector3f& p : clouds[i])
      points[i].push_back(ufo::map::Point3(p.x(), p.y(), p.z()));
  }
  // UFOMap's fast mode: the end points discretised to voxels (as liboctomap's discretize), free
  // space at the finest depth, its own ray casting.
  PeerRun run{"ufomap_discrete"};
  timeEach(
      clouds.size(), ours,
      [&](std::size_t i) {
        const ufo::map::Point3 origin(origins[i].x(), origins[i].y(), origins[i].z());
        map.insertPointCloudDiscrete(origin, points[i], -1, 0);
      },
      &run);
  run.memory_mb = map.memoryUsage() * 1e-6;
  return run;
}
#endif

}  // namespace

std::vector<std::string> compiledPeers() {
  std::vector<std::string> names;
#ifdef OCCUPANCY_FUSION_WITH_BONXAI
  names.push_back("bonxai");
#endif
#ifdef OCCUPANCY_FUSION_WITH_UFOMAP
  names.push_back("ufomap_discrete");
#endif
  return names;
}

std::vector<PeerRun> runPeers(const std::vector<std::vector<Eigen::Vector3f>>& clouds,
                              const std::vector<Eigen::Vector3d>& origins, double resolution,
                              const PairedInsert& ours) {
  std::vector<PeerRun> runs;
#ifdef OCCUPANCY_FUSION_WITH_BONXAI
  runs.push_back(runBonxai(clouds, origins, resolution, ours));
#endif
#ifdef OCCUPANCY_FUSION_WITH_UFOMAP
  runs.push_back(runUfomap(clouds, origins, resolution, ours));
#endif
  static_cast<void>(clouds);
  static_cast<void>(origins);
  static_cast<void>(resolution);
  static_cast<void>(ours);
  return runs;
}

}  // namespace bench
}  // namespace occupancy_fusion
