// Checks the map that the MapServer publishes, fed by the DisparityMapper with the Simulator's
// stereo camera in the room scene, against the scene's analytic ground truth; then that malformed
// disparity images (wrong encoding, a size that does not fit camera_info) are dropped, leave the
// map as it was, and do not stop the mapper.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <stereo_msgs/DisparityImage.h>

#include "occupancy_fusion/sim/scenes.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

struct Settings {
  int min_images = 40;
  double min_coverage = 0.8;
  double resolution = 0.1;
  double min_z = 0.05;
  double max_z = 2.0;
  std::string disparity_topic = "stereo/disparity";
  std::string optical_frame = "stereo_left_optical_frame";
};

// The DisparityMapper's counters, from /diagnostics.
struct MapperCounters {
  std::size_t integrated = 0;
  std::size_t dropped_invalid = 0;
  std::string map_version;
};

constexpr char kTask[] = "disparity mapping";

// The DisparityMapper's latest counters.
MapperCounters countersOf(const MapObserver& observer) {
  const DiagnosticValues values = observer.diagnostics(kTask);
  MapperCounters counters;
  counters.integrated = countIn(values, "images integrated");
  counters.dropped_invalid = countIn(values, "images dropped (invalid)");
  const auto version = values.find("map version");
  if (version != values.end()) counters.map_version = version->second;
  return counters;
}

Settings g_settings;
MapObserver* g_observer = nullptr;
ros::Publisher* g_disparity_publisher = nullptr;

// Whether the vertical segment over (x, y) within the height band meets a solid.
bool bandHitsSolid(const sim::Scene& scene, const Eigen::Vector2d& xy) {
  return columnHitsSolid(scene, xy, g_settings.min_z, g_settings.max_z,
                         0.25 * g_settings.resolution);
}

// A disparity image of the optical frame stamped now, every pixel at 10 px (a surface 1.6 m in
// front of the simulated camera): integrated, it would change the map.
stereo_msgs::DisparityImage plausibleDisparity(int width, int height) {
  stereo_msgs::DisparityImage message;
  message.header.frame_id = g_settings.optical_frame;
  message.header.stamp = ros::Time::now();
  message.image.header = message.header;
  message.image.width = static_cast<std::uint32_t>(width);
  message.image.height = static_cast<std::uint32_t>(height);
  message.image.encoding = "32FC1";
  message.image.step = static_cast<std::uint32_t>(width * sizeof(float));
  const std::vector<float> values(static_cast<std::size_t>(width) * height, 10.0f);
  message.image.data.resize(values.size() * sizeof(float));
  std::memcpy(message.image.data.data(), values.data(), message.image.data.size());
  message.f = 262.4f;
  message.T = 0.12f;
  message.min_disparity = 0.0f;
  message.max_disparity = static_cast<float>(width);
  return message;
}

// Surface samples 5 cm apart between 0.3 and 1.0 m high (the stereo camera, 1 m up and pitched
// 20 deg down, sees that band of every wall it faces), within 3.3 m of the circle's centre (the
// mapper's 4 m range from a camera up to 0.6 m off the centre) and not hidden from the centre
// at 1 m height by another surface.
std::vector<Eigen::Vector3d> surfaceSeenByTheTurn(const sim::Scene& scene) {
  const Eigen::Vector3d centre(0.0, 0.0, 1.0);
  std::vector<Eigen::Vector3d> seen;
  for (const Eigen::Vector3d& sample : scene.sampleSurface(0.05)) {
    if (sample.z() < 0.3 || sample.z() > 1.0) continue;
    const Eigen::Vector3d offset = sample - centre;
    if (offset.head<2>().norm() > 3.3) continue;
    const double distance = offset.norm();
    const auto hit = scene.castRay(centre, offset / distance, distance + 0.01);
    if (hit && *hit >= distance - 0.02) seen.push_back(sample);
  }
  return seen;
}

// The fraction of `samples` with a point of `points` within `radius`.
double coveredFraction(const std::vector<Eigen::Vector3d>& samples,
                       const std::vector<Eigen::Vector3d>& points, double radius) {
  std::size_t covered = 0;
  for (const Eigen::Vector3d& sample : samples) {
    for (const Eigen::Vector3d& point : points) {
      if ((point - sample).squaredNorm() <= radius * radius) {
        ++covered;
        break;
      }
    }
  }
  return samples.empty() ? 0.0 : static_cast<double>(covered) / samples.size();
}

TEST(SimDisparityMapping, MapMatchesGroundTruth) {
  ASSERT_TRUE(waitUntil(
      [] { return countersOf(*g_observer).integrated >= std::size_t(g_settings.min_images); },
      90.0))
      << "only " << countersOf(*g_observer).integrated << " disparity images integrated";
  ASSERT_TRUE(setSimulatorPaused(true));
  // Let images in flight be integrated and published; then the map stays as it is.
  ros::WallDuration(2.0).sleep();
  const sensor_msgs::PointCloud2::ConstPtr cloud =
      g_observer->latest<sensor_msgs::PointCloud2>("octomap_point_cloud_centers");
  const nav_msgs::OccupancyGrid::ConstPtr grid =
      g_observer->latest<nav_msgs::OccupancyGrid>("projected_map");
  ASSERT_TRUE(cloud && grid);
  const sim::Scene scene = sim::makeRoomScene();

  // False-occupied: voxel centres farther from every surface than a voxel diagonal plus the depth
  // noise at the 4 m range limit (sigma_z = 0.3 px / (0.12 m * 262.4 px) * (4 m)^2 = 0.15 m);
  // with patches of wrong disparity the OctoMap mode maps 17 % of its voxels there.
  const std::vector<Eigen::Vector3d> centres = cloudPoints(*cloud);
  const double tolerance = std::sqrt(3.0) * g_settings.resolution + 0.15;
  const double near_fraction = fractionNearSurface(centres, scene, tolerance);
  const std::size_t false_occupied = centres.size() - countNearSurface(centres, scene, tolerance);
  // Coverage: the surfaces every turn shows (between 0.3 and 1 m high, within 3.3 m of the
  // circle's centre, seen from it), each with an occupied voxel centre within a voxel diagonal.
  const std::vector<Eigen::Vector3d> seen = surfaceSeenByTheTurn(scene);
  const double coverage = coveredFraction(seen, centres, std::sqrt(3.0) * g_settings.resolution);
  ROS_INFO(
      "%zu occupied voxels, %zu (%.2f %%) farther than %.2f m from a surface; coverage of "
      "%zu seen surface samples %.3f",
      centres.size(), false_occupied, 100.0 * (1.0 - near_fraction), tolerance, seen.size(),
      coverage);
  std::printf("moving stereo camera: %zu occupied, %zu false-occupied, coverage %.3f\n",
              centres.size(), false_occupied, coverage);
  ASSERT_GE(seen.size(), 500u);
  EXPECT_GE(coverage, g_settings.min_coverage);
  EXPECT_LE(static_cast<double>(false_occupied), 0.05 * centres.size());

  // Free cells of the projected grid are free in the scene over the whole height band.
  std::size_t free_cells = 0, free_correct = 0;
  for (int y = 0; y < static_cast<int>(grid->info.height); ++y) {
    for (int x = 0; x < static_cast<int>(grid->info.width); ++x) {
      if (grid->data[static_cast<std::size_t>(x + grid->info.width * y)] != 0) continue;
      ++free_cells;
      free_correct += bandHitsSolid(scene, cellCentre(*grid, x, y)) ? 0 : 1;
    }
  }
  ROS_INFO("grid: %zu free cells, %.2f %% free in the scene", free_cells,
           100.0 * free_correct / std::max<std::size_t>(free_cells, 1));
  EXPECT_GE(free_cells, 800u);
  EXPECT_GE(double(free_correct) / free_cells, 0.98);

  // The last image's time by stage: each reported, every stage of a mapped image took time, and
  // together no longer than the image.
  const DiagnosticValues values = g_observer->diagnostics(kTask);
  double stages = 0.0;
  for (const char* key : {"last image conversion ms", "last image bundling ms",
                          "last image walks ms", "last image writing ms"}) {
    const auto value = values.find(key);
    ASSERT_NE(value, values.end()) << key;
    EXPECT_GT(std::stod(value->second), 0.0) << key;
    stages += std::stod(value->second);
  }
  ASSERT_NE(values.find("last image ms"), values.end());
  EXPECT_LE(stages, std::stod(values.at("last image ms")) + 1e-3);
}

TEST(SimDisparityMapping, MalformedImagesAreDroppedAndTheMapperRunsOn) {
  ASSERT_TRUE(setSimulatorPaused(true));
  // Images in flight integrated and reported: the count kept still over two diagnostics periods.
  std::size_t settled = 0;
  ASSERT_TRUE(
      waitUntilSteady([] { return countersOf(*g_observer).integrated; }, 2.5, 20.0, &settled));
  ASSERT_TRUE(waitUntil([] { return g_disparity_publisher->getNumSubscribers() > 0; }, 10.0))
      << "the DisparityMapper did not subscribe to the test's images";
  const MapperCounters before = countersOf(*g_observer);
  ASSERT_GT(before.integrated, 0u);

  // Wrong encoding: 16-bit data of the camera's size.
  stereo_msgs::DisparityImage wrong_encoding = plausibleDisparity(160, 240);
  wrong_encoding.image.width = 320;
  wrong_encoding.image.encoding = "16UC1";
  wrong_encoding.image.step = 320 * 2;
  g_disparity_publisher->publish(wrong_encoding);
  // Right encoding, but a size the camera_info (320 x 240) does not describe.
  g_disparity_publisher->publish(plausibleDisparity(100, 80));

  ASSERT_TRUE(waitUntil(
      [&] { return countersOf(*g_observer).dropped_invalid >= before.dropped_invalid + 2; }, 10.0))
      << "dropped " << countersOf(*g_observer).dropped_invalid - before.dropped_invalid;
  const MapperCounters after = countersOf(*g_observer);
  EXPECT_EQ(after.integrated, before.integrated);
  EXPECT_EQ(after.map_version, before.map_version);  // not a single voxel written

  // The mapper goes on with good images.
  ASSERT_TRUE(setSimulatorPaused(false));
  EXPECT_TRUE(
      waitUntil([&] { return countersOf(*g_observer).integrated > after.integrated; }, 10.0));
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sim_disparity_mapping_test");
  ros::NodeHandle node_handle;
  ros::NodeHandle private_node_handle("~");
  occupancy_fusion::Settings& settings = occupancy_fusion::g_settings;
  private_node_handle.param("min_images", settings.min_images, settings.min_images);
  private_node_handle.param("min_coverage", settings.min_coverage, settings.min_coverage);
  private_node_handle.param("resolution", settings.resolution, settings.resolution);
  private_node_handle.param("occupancy_min_z", settings.min_z, settings.min_z);
  private_node_handle.param("occupancy_max_z", settings.max_z, settings.max_z);
  private_node_handle.param("disparity_topic", settings.disparity_topic, settings.disparity_topic);
  private_node_handle.param("optical_frame", settings.optical_frame, settings.optical_frame);
  occupancy_fusion::MapObserver observer(node_handle);
  observer.watch<nav_msgs::OccupancyGrid>("projected_map");
  observer.watch<sensor_msgs::PointCloud2>("octomap_point_cloud_centers");
  occupancy_fusion::g_observer = &observer;
  // Advertised now, so the mapper is connected long before the malformed images go out.
  ros::Publisher disparity_publisher =
      node_handle.advertise<stereo_msgs::DisparityImage>(settings.disparity_topic, 2);
  occupancy_fusion::g_disparity_publisher = &disparity_publisher;
  return occupancy_fusion::runTestsWhileSpinning();
}
