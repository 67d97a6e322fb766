// A standing stereo camera in front of a wall, mapped by the DisparityMapper's visibility method
// with Table I's defaults: unknown space occludes partly (Eq. 1 with P(O) = 0.5), so every frame
// maps a few voxels deeper (Fig. 5a) until the visible surfaces are reached. The test records the
// map after every published update, reports the frames needed, and checks the final occupied
// voxels against the room scene's analytic surfaces. The count starts from an empty map (the
// simulator paused, the map reset), not from whatever the map held when this node came up: a
// test node started late under load would otherwise see a latched map already grown.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Empty.h>

#include "occupancy_fusion/sim/scenes.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

struct Settings {
  int images = 60;
  double resolution = 0.2;
  int min_occupied = 1;
};

// One published voxel cloud with the number of images the mapper had integrated when it came.
struct Snapshot {
  std::size_t images = 0;
  std::vector<Eigen::Vector3d> centres;
};

// Every published voxel cloud with the number of images the mapper had integrated when it came.
class CloudHistory {
 public:
  explicit CloudHistory(MapObserver* observer) : observer_(observer) {
    observer->watch<sensor_msgs::PointCloud2>(
        "octomap_point_cloud_centers", 10,
        [this](const sensor_msgs::PointCloud2::ConstPtr& cloud) { record(*cloud); });
  }
  std::size_t integrated() const {
    return observer_->diagnosticCount("disparity mapping", "images integrated");
  }
  std::vector<Snapshot> snapshots() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return snapshots_;
  }

 private:
  void record(const sensor_msgs::PointCloud2& cloud) {
    Snapshot snapshot;
    snapshot.centres = cloudPoints(cloud);
    snapshot.images = integrated();
    std::lock_guard<std::mutex> lock(mutex_);
    snapshots_.push_back(std::move(snapshot));
  }

  const MapObserver* observer_;
  mutable std::mutex mutex_;
  std::vector<Snapshot> snapshots_;
};

Settings g_settings;
CloudHistory* g_recorder = nullptr;

// Voxels whose centre lies within a voxel diagonal (a surface crossing the voxel) plus the depth
// noise at 1.6 m (sigma_z = 0.3 px / (0.12 m * 262.4 px) * (1.6 m)^2 = 0.024 m) of a surface.
std::size_t nearSurface(const sim::Scene& scene, const std::vector<Eigen::Vector3d>& centres) {
  return countNearSurface(centres, scene, std::sqrt(3.0) * g_settings.resolution + 0.05);
}

TEST(SimDisparityStanding, VisibilityMethodMapsTheVisibleSurfacesAfterEnoughFrames) {
  // Start from an empty map with the camera where it stands: pause, let the images in flight
  // through, reset the map and wait for the MapServer's empty cloud (a cloud of the old map
  // published while the reset ran would otherwise count as the first update).
  // (Some voxels mapped first, so that the reset changes the map and an empty cloud follows.)
  ASSERT_TRUE(waitUntil(
      [] {
        const std::vector<Snapshot> all = g_recorder->snapshots();
        return !all.empty() && !all.back().centres.empty();
      },
      30.0))
      << "the mapper mapped nothing";
  ASSERT_TRUE(setSimulatorPaused(true));
  const auto integrated = [] { return g_recorder->integrated(); };
  std::size_t baseline = 0;
  ASSERT_TRUE(waitUntilSteady(integrated, 2.5, 20.0, &baseline));
  const std::size_t before_reset = g_recorder->snapshots().size();
  std_srvs::Empty reset;
  ASSERT_TRUE(ros::service::call("/map_server/reset", reset));
  std::size_t first = 0;
  ASSERT_TRUE(waitUntil(
      [&] {
        const std::vector<Snapshot> all = g_recorder->snapshots();
        for (first = before_reset; first < all.size(); ++first) {
          if (all[first].centres.empty()) return true;
        }
        return false;
      },
      10.0))
      << "no empty cloud after the reset";
  ASSERT_TRUE(setSimulatorPaused(false));
  ASSERT_TRUE(waitUntil(
      [&] { return g_recorder->integrated() >= baseline + std::size_t(g_settings.images); }, 40.0))
      << "only " << g_recorder->integrated() - baseline << " disparity images integrated";
  ASSERT_TRUE(setSimulatorPaused(true));
  // 2.5 s without a new image: ten MapServer cycles (4 Hz) sent the last update.
  std::size_t final_count = 0;
  ASSERT_TRUE(waitUntilSteady(integrated, 2.5, 20.0, &final_count));
  std::vector<Snapshot> snapshots = g_recorder->snapshots();
  snapshots.erase(snapshots.begin(), snapshots.begin() + static_cast<std::ptrdiff_t>(first));
  for (Snapshot& snapshot : snapshots) snapshot.images -= std::min(snapshot.images, baseline);
  ASSERT_FALSE(snapshots.empty());
  const sim::Scene scene = sim::makeRoomScene();
  const std::vector<Eigen::Vector3d>& final_centres = snapshots.back().centres;
  const std::size_t near = nearSurface(scene, final_centres);
  const double near_fraction = final_centres.empty() ? 0.0 : double(near) / final_centres.size();
  // The frames the method needed: the first update holding 90 % of the final surface voxels.
  std::size_t frames_to_90 = 0;
  for (const Snapshot& snapshot : snapshots) {
    if (nearSurface(scene, snapshot.centres) >= 0.9 * near) {
      frames_to_90 = snapshot.images;
      break;
    }
  }
  ROS_INFO(
      "after %zu images: %zu occupied voxels, %.1f %% on the true surfaces; 90 %% of them "
      "mapped after %zu images",
      snapshots.back().images, final_centres.size(), 100.0 * near_fraction, frames_to_90);
  // The growth (image counts come from the mapper's 1 Hz diagnostics, so in steps of ~5).
  std::size_t last_count = 0;
  for (const Snapshot& snapshot : snapshots) {
    if (snapshot.centres.size() == last_count) continue;
    last_count = snapshot.centres.size();
    ROS_INFO("  images %zu: %zu occupied", snapshot.images, last_count);
  }
  EXPECT_GE(near_fraction, 0.95);
  EXPECT_GE(final_centres.size(), std::size_t(g_settings.min_occupied));
  // Gradual, not immediate (unknown space occludes): the first images map none of the wall.
  EXPECT_GT(frames_to_90, 1u);
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sim_disparity_standing_test");
  ros::NodeHandle node_handle;
  ros::NodeHandle private_node_handle("~");
  occupancy_fusion::Settings& settings = occupancy_fusion::g_settings;
  private_node_handle.param("images", settings.images, settings.images);
  private_node_handle.param("resolution", settings.resolution, settings.resolution);
  private_node_handle.param("min_occupied", settings.min_occupied, settings.min_occupied);
  occupancy_fusion::MapObserver observer(node_handle);
  occupancy_fusion::CloudHistory recorder(&observer);
  occupancy_fusion::g_recorder = &recorder;
  return occupancy_fusion::runTestsWhileSpinning();
}
