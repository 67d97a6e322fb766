#include "frame_rays.h"

#include <functional>

namespace occupancy_fusion {

namespace {

struct RowCounts {
  std::size_t points = 0, dropped_uncertain = 0;
};

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
  const Eigen::Isometry3f transform = T_map_camera.cast<float>();
  const Eigen::Vector3d origin = T_map_camera.translation();
  std::vector<RowCounts> counts(rows);
  // Eight rows a task: a few dozen tasks for a whole image, each long against a task's overhead.
  // Without a task group: this thread goes on to `alongside` while the rows wait for a thread.
#pragma omp taskloop grainsize(8) default(shared) nogroup
  for (int j = 0; j < rows; ++j) {
    const int v = j * step;
    const double ray_y = converter.rayY(v);
    const float* row = disparity.row(v);
    const std::size_t first = static_cast<std::size_t>(j) * columns;
    for (int i = 0; i < columns; ++i) {
      Eigen::Vector3f p;
      float sigma_z = 0.0f;
      RayTarget& end = rays->ends[first + i];
      const int u = i * step;
      const auto converted = converter.convert(u, ray_y, row[u], &p, &sigma_z);
      if (converted != DisparityPointConverter::Result::kPoint) {
        end.key = RayTarget::kNoPoint;
        if (converted == DisparityPointConverter::Result::kUncertain) ++counts[j].dropped_uncertain;
        continue;
      }
      ++counts[j].points;
      const Eigen::Vector3f point = transform * p;
      const float range_sigma = rangeSigmaOf(p, sigma_z);
      rays->points[first + i] = point;
      rays->range_sigmas[first + i] = range_sigma;
      end = rayTargetOf(point, range_sigma, origin, resolution, needs_direction);
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
