#include "frame_rays.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>

namespace occupancy_fusion {

namespace {

struct RowCounts {
  std::size_t points = 0, dropped_uncertain = 0;
};

// What every pixel of a frame shares.
struct FrameConversion {
  const DisparityPointConverter& converter;
  Eigen::Isometry3f transform;
  Eigen::Vector3d origin;
  double resolution;
  bool needs_direction;
};

// Pixels converted together: enough for the vector loops, few enough for the stack.
constexpr int kRun = 32;

// `count` (at most kRun) pixels of a row, from column `first` on (in converted pixels), into
// `slot` and the slots after it. Every division and square root runs in a loop over all of them
// without branches, which the compiler vectorises; the checks of each pixel follow in one loop
// over the results. The arithmetic of each value is that of convert(), transformPoint(),
// rangeSigmaOf() and rayTargetOf() one pixel at a time, so the bits are the same.
void convertRun(const FrameConversion& frame, const float* row, int first, int count, double ray_y,
                std::size_t slot, FrameRays* rays, RowCounts* counts) {
  const DisparityPointConverter& converter = frame.converter;
  const int step = converter.step();
  float disparity[kRun];
  for (int k = 0; k < count; ++k) disparity[k] = row[(first + k) * step];
  double depth[kRun], x[kRun];  // whatever the disparity: finish() tells which are points
  for (int k = 0; k < count; ++k) {
    depth[k] = converter.depthOf(disparity[k]);
    x[k] = converter.xOf((first + k) * step, depth[k]);
  }
  float map_point[3][kRun], range_sigma[kRun];
  for (int k = 0; k < count; ++k) {
    const Eigen::Vector3f p(static_cast<float>(x[k]), static_cast<float>(depth[k] * ray_y),
                            static_cast<float>(depth[k]));
    const Eigen::Vector3f point = transformPoint(frame.transform, p);
    for (int axis = 0; axis < 3; ++axis) map_point[axis][k] = point[axis];
    range_sigma[k] = rangeSigmaOf(p, static_cast<float>(converter.depthSigmaOf(depth[k])));
  }
  double offset[3][kRun], squared_range[kRun];
  double in_voxels[3][kRun] = {};  // zeros past `count`: packFlooredKeys reads pairs
  for (int k = 0; k < count; ++k) {
    for (int axis = 0; axis < 3; ++axis) {
      offset[axis][k] = map_point[axis][k] - frame.origin[axis];
      in_voxels[axis][k] = map_point[axis][k] / frame.resolution;  // voxelIndexOf's division
    }
    squared_range[k] = squaredLength({offset[0][k], offset[1][k], offset[2][k]});
  }
  std::uint64_t key[kRun];
  packFlooredKeys(in_voxels[0], in_voxels[1], in_voxels[2], (count + 1) / 2 * 2, key);
  for (int k = 0; k < count; ++k) {
    Eigen::Vector3f p;
    float sigma_z;
    const auto converted = converter.finish(disparity[k], depth[k], x[k], ray_y, &p, &sigma_z);
    RayTarget& end = rays->ends[slot + k];
    if (converted != DisparityPointConverter::Result::kPoint) {
      end.key = RayTarget::kNoPoint;
      if (converted == DisparityPointConverter::Result::kUncertain) ++counts->dropped_uncertain;
      continue;
    }
    ++counts->points;
    const Eigen::Vector3f point(map_point[0][k], map_point[1][k], map_point[2][k]);
    rays->points[slot + k] = point;
    rays->range_sigmas[slot + k] = range_sigma[k];
    const double usable =
        usableSquaredRange(point.allFinite(), {offset[0][k], offset[1][k], offset[2][k]},
                           squared_range[k], frame.resolution, frame.needs_direction);
    end = isUsable(usable, range_sigma[k]) ? RayTarget{key[k], usable}
                                           : RayTarget{RayTarget::kUnusable, 0.0};
  }
}

}  // namespace

void convertFrameRays(const DisparityImageView& disparity, const StereoCamera& camera,
                      const DisparityConversionConfig& conversion,
                      const Eigen::Isometry3d& T_map_camera, double resolution,
                      bool needs_direction, FrameRays* rays,
                      const std::function<void()>& alongside) {
  const DisparityPointConverter converter(camera, conversion);
  const int step = converter.step();
  const int columns = (disparity.width + step - 1) / step;
  const int rows = (disparity.height + step - 1) / step;
  const std::size_t slots = static_cast<std::size_t>(columns) * rows;
  rays->points.resize(slots);
  rays->range_sigmas.resize(slots);
  rays->ends.resize(slots);
  rays->columns = columns;
  const FrameConversion frame{converter, T_map_camera.cast<float>(), T_map_camera.translation(),
                              resolution, needs_direction};
  std::vector<RowCounts> counts(rows);
  // Eight rows a task: a few dozen tasks for a whole image, each long against a task's overhead.
  // Without a task group: this thread goes on to `alongside` while the rows wait for a thread.
#pragma omp taskloop grainsize(8) default(shared) nogroup
  for (int j = 0; j < rows; ++j) {
    const int v = j * step;
    const std::size_t first_slot = static_cast<std::size_t>(j) * columns;
    for (int i = 0; i < columns; i += kRun) {
      convertRun(frame, disparity.row(v), i, std::min(kRun, columns - i), converter.rayY(v),
                 first_slot + i, rays, &counts[j]);
    }
  }
  if (alongside) alongside();
#pragma omp taskwait
  rays->points_count = rays->dropped_uncertain = 0;
  for (const RowCounts& row : counts) {
    rays->points_count += row.points;
    rays->dropped_uncertain += row.dropped_uncertain;
  }
}

}  // namespace occupancy_fusion
