// Checks the map that the MapServer publishes (octomap_binary), fed by the DepthMapper with the
// Simulator's depth camera in the depth paper's BOX scene, against the scene's analytic ground
// truth and against the surface points the depth images themselves show. Then feeds bad frames
// (wrong encoding, camera_info that does not fit) and checks that they leave the map unchanged
// while the mapper keeps running.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include <boost/make_shared.hpp>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <octomap/OcTree.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "occupancy_fusion/Octomap.h"
#include "occupancy_fusion/sim/scenes.h"
#include "rostest_support.h"

namespace occupancy_fusion {
namespace {

struct Settings {
  int min_images = 40;
  double resolution = 0.1;
  int pixel_step = 2;  // every 2nd pixel in u and v gives a surface sample
};
Settings g_settings;
constexpr double kNearCamera = 1.0;  // m

// A depth image's valid pixels back-projected into its optical frame (subsampled).
struct ObservedImage {
  ros::Time stamp;
  std::string frame;
  std::vector<Eigen::Vector3d> points;
};

// The depth camera's images (as surface samples) and its latest camera_info, as a second
// subscriber sees them.
class DepthImageRecorder {
 public:
  explicit DepthImageRecorder(MapObserver* observer) : tf_buffer_(ros::Duration(300.0)) {
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_);
    observer->watch<sensor_msgs::CameraInfo>(
        "camera/depth/camera_info", 20,
        [this](const sensor_msgs::CameraInfo::ConstPtr& info) { onInfo(info); });
    observer->watch<sensor_msgs::Image>(
        "camera/depth/image", 20,
        [this](const sensor_msgs::Image::ConstPtr& image) { onImage(image); });
  }

  sensor_msgs::CameraInfo::ConstPtr latestInfo() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return info_;
  }
  void stopObserving() {
    std::lock_guard<std::mutex> lock(mutex_);
    observing_ = false;
  }
  // Surface samples of every observed image and the camera centre that saw each, in the map
  // frame.
  struct Ray {
    Eigen::Vector3d origin, end;
  };
  std::vector<Ray> observedRays() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Ray> rays;
    for (const ObservedImage& image : images_) {
      Eigen::Isometry3d T_map_camera;
      try {
        T_map_camera = tf2::transformToEigen(
            tf_buffer_.lookupTransform("map", image.frame, image.stamp, ros::Duration(1.0)));
      } catch (const tf2::TransformException& error) {
        ROS_WARN("observed image skipped: %s", error.what());
        continue;
      }
      for (const Eigen::Vector3d& p : image.points) {
        rays.push_back({T_map_camera.translation(), T_map_camera * p});
      }
    }
    return rays;
  }

 private:
  void onInfo(const sensor_msgs::CameraInfo::ConstPtr& info) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (info->width > 0 && info->K[0] > 0.0) info_ = info;  // not the test's own bad ones
  }
  void onImage(const sensor_msgs::Image::ConstPtr& image) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!observing_ || !info_ || image->encoding != sensor_msgs::image_encodings::TYPE_32FC1 ||
        image->width != info_->width || image->height != info_->height) {
      return;
    }
    const double fx = info_->K[0], fy = info_->K[4], cx = info_->K[2], cy = info_->K[5];
    ObservedImage observed{image->header.stamp, image->header.frame_id, {}};
    const auto* depth = reinterpret_cast<const float*>(image->data.data());
    const int step = g_settings.pixel_step;
    for (int v = step / 2; v < static_cast<int>(image->height); v += step) {
      for (int u = step / 2; u < static_cast<int>(image->width); u += step) {
        const float z = depth[static_cast<std::size_t>(v) * image->width + u];
        if (!(z > 0.0f)) continue;
        observed.points.emplace_back((u - cx) / fx * z, (v - cy) / fy * z, z);
      }
    }
    images_.push_back(std::move(observed));
  }

  mutable std::mutex mutex_;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  sensor_msgs::CameraInfo::ConstPtr info_;
  bool observing_ = true;
  std::vector<ObservedImage> images_;
};

// The DepthMapper's and the MapServer's counts, as last reported.
struct Counters {
  std::size_t integrated = 0, dropped_encoding = 0, dropped_camera_info = 0;
  std::size_t camera_infos = 0;     // camera_info messages the DepthMapper received
  ros::WallTime depth_status_time;  // when the DepthMapper's status last came
  std::size_t known_voxels = 0;     // from the MapServer
};

Counters countersOf(const MapObserver& observer) {
  const DiagnosticValues depth = observer.diagnostics("depth mapping");
  Counters counters;
  counters.integrated = countIn(depth, "images integrated");
  counters.dropped_encoding = countIn(depth, "images dropped (encoding)");
  counters.dropped_camera_info = countIn(depth, "images dropped (camera_info)");
  counters.camera_infos = countIn(depth, "camera_info received");
  counters.depth_status_time = observer.diagnosticsArrival("depth mapping");
  counters.known_voxels = observer.diagnosticCount("map publishing", "known voxels");
  return counters;
}

// The latest map and when it came.
std::pair<occupancy_fusion::Octomap::ConstPtr, ros::WallTime> latestMap(
    const MapObserver& observer) {
  return {observer.latest<occupancy_fusion::Octomap>("octomap_binary"),
          observer.arrival("octomap_binary")};
}

MapObserver* g_observer = nullptr;
DepthImageRecorder* g_images = nullptr;

std::unique_ptr<octomap::OcTree> treeOf(const occupancy_fusion::Octomap& message) {
  auto tree = std::make_unique<octomap::OcTree>(message.resolution);
  std::stringstream data;
  data.write(reinterpret_cast<const char*>(message.data.data()),
             static_cast<std::streamsize>(message.data.size()));
  tree->readBinaryData(data);
  tree->expand();  // every leaf one voxel
  return tree;
}

// Whether an occupied voxel lies within one voxel (the 3x3x3 neighbourhood) of the point's.
bool occupiedNear(const octomap::OcTree& tree, const Eigen::Vector3d& point) {
  octomap::OcTreeKey key;
  if (!tree.coordToKeyChecked(point.x(), point.y(), point.z(), key)) return false;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const octomap::OcTreeKey neighbour(key[0] + dx, key[1] + dy, key[2] + dz);
        const octomap::OcTreeNode* node = tree.search(neighbour);
        if (node && tree.isNodeOccupied(node)) return true;
      }
    }
  }
  return false;
}

// Waits until the mapper has integrated everything in flight and the map that follows it has
// been published; returns that map.
occupancy_fusion::Octomap::ConstPtr settledMap() {
  std::size_t integrated = countersOf(*g_observer).integrated;
  ros::WallTime stable_since = ros::WallTime::now();
  waitUntil(
      [&] {
        const std::size_t now = countersOf(*g_observer).integrated;
        if (now != integrated) {
          integrated = now;
          stable_since = ros::WallTime::now();
        }
        return ros::WallTime::now() - stable_since > ros::WallDuration(2.5);
      },
      20.0);
  const ros::WallTime since = ros::WallTime::now();
  // Unchanged maps are not re-sent: the latest one is current if none came for 1.5 s.
  waitUntil(
      [&] {
        return ros::WallTime::now() - latestMap(*g_observer).second > ros::WallDuration(1.5) &&
               ros::WallTime::now() - since > ros::WallDuration(1.5);
      },
      20.0);
  return latestMap(*g_observer).first;
}

TEST(SimDepthMapping, MapMatchesGroundTruth) {
  ASSERT_TRUE(waitUntil(
      [] {
        return countersOf(*g_observer).integrated >=
               static_cast<std::size_t>(g_settings.min_images);
      },
      90.0))
      << "only " << countersOf(*g_observer).integrated << " depth images integrated";
  ASSERT_TRUE(setSimulatorPaused(true));
  const occupancy_fusion::Octomap::ConstPtr message = settledMap();
  g_images->stopObserving();
  ASSERT_TRUE(message);
  EXPECT_EQ(message->header.frame_id, "map");
  EXPECT_NEAR(message->resolution, g_settings.resolution, 1e-9);
  const std::unique_ptr<octomap::OcTree> tree = treeOf(*message);

  const sim::Scene scene = sim::makeBoxScene();
  const double diagonal = std::sqrt(3.0) * g_settings.resolution;

  // Occupied voxels lie on the true surfaces; free voxels lie in free space.
  std::size_t occupied = 0, occupied_on_surface = 0, free = 0, free_really = 0;
  std::size_t clear_voxels = 0, clear_labelled_free = 0;
  for (auto leaf = tree->begin_leafs(); leaf != tree->end_leafs(); ++leaf) {
    const Eigen::Vector3d centre(leaf.getX(), leaf.getY(), leaf.getZ());
    const bool is_occupied = tree->isNodeOccupied(*leaf);
    const bool in_solid = scene.isOccupied(centre);
    const double to_surface = scene.distanceToSurface(centre);
    if (is_occupied) {
      ++occupied;
      occupied_on_surface += to_surface <= diagonal ? 1 : 0;
    } else {
      ++free;
      free_really += in_solid ? 0 : 1;
    }
    // Known voxels wholly in free space, more than a voxel diagonal from any surface.
    if (!in_solid && to_surface > diagonal) {
      ++clear_voxels;
      clear_labelled_free += is_occupied ? 0 : 1;
    }
  }

  // The surface the depth images showed: each sample must have an occupied voxel next to it.
  // Half way along its ray lies space the camera saw through: it must be free in the map.
  const std::vector<DepthImageRecorder::Ray> rays = g_images->observedRays();
  std::size_t covered = 0, on_true_surface = 0;
  std::set<std::tuple<int, int, int>> surface_voxels, seen_free_voxels, seen_free_labelled_free;
  for (const DepthImageRecorder::Ray& ray : rays) {
    const Eigen::Vector3d& p = ray.end;
    covered += occupiedNear(*tree, p) ? 1 : 0;
    on_true_surface += scene.distanceToSurface(p) < 1e-3 ? 1 : 0;
    const octomap::OcTreeKey key = tree->coordToKey(p.x(), p.y(), p.z());
    surface_voxels.emplace(key[0], key[1], key[2]);
    const Eigen::Vector3d middle = 0.5 * (ray.origin + ray.end);
    const octomap::OcTreeKey middle_key = tree->coordToKey(middle.x(), middle.y(), middle.z());
    const octomap::point3d centre = tree->keyToCoord(middle_key);
    // Voxels that a surface cuts are not wholly free: left out. So are voxels nearer than 1 m
    // to the camera: there the pyramid's coarsest layers (64 x 64 pixel blocks of a 160 x 120
    // image) leave about a tenth of them unknown, which is no error (unknown, not occupied).
    if ((middle - ray.origin).norm() < kNearCamera) continue;
    if (scene.distanceToSurface(Eigen::Vector3d(centre.x(), centre.y(), centre.z())) <= diagonal) {
      continue;
    }
    seen_free_voxels.emplace(middle_key[0], middle_key[1], middle_key[2]);
    const octomap::OcTreeNode* node = tree->search(middle_key);
    if (node && !tree->isNodeOccupied(node)) {
      seen_free_labelled_free.emplace(middle_key[0], middle_key[1], middle_key[2]);
    }
  }
  ROS_INFO(
      "BOX: %zu occupied voxels, %.2f %% within a voxel diagonal of a surface; %zu free voxels, "
      "%.2f %% outside solids; %zu clear voxels, %.2f %% free; %zu observed surface samples in "
      "%zu voxels, %.2f %% next to an occupied voxel; %zu voxels seen through, %.2f %% free",
      occupied, 100.0 * occupied_on_surface / occupied, free, 100.0 * free_really / free,
      clear_voxels, 100.0 * clear_labelled_free / clear_voxels, rays.size(), surface_voxels.size(),
      100.0 * covered / rays.size(), seen_free_voxels.size(),
      100.0 * seen_free_labelled_free.size() / seen_free_voxels.size());

  // The samples really are on the scene's surfaces (the test's own back-projection is right).
  ASSERT_GT(rays.size(), 50000u);
  EXPECT_EQ(on_true_surface, rays.size());
  EXPECT_GE(static_cast<double>(covered) / rays.size(), 0.95);
  EXPECT_GE(static_cast<double>(occupied_on_surface) / occupied, 0.95);
  // Counts: every voxel holding observed surface needs an occupied voxel, and the occupied
  // surface is a few voxels thick (Eq. 7 is above 0.5 within about +-1.5 sigma = 1.5 voxels of
  // the measurement along each ray), not a slab.
  EXPECT_GE(occupied, surface_voxels.size() * 9 / 10);
  EXPECT_LE(occupied, surface_voxels.size() * 5);
  ASSERT_GT(seen_free_voxels.size(), 2000u);
  EXPECT_GE(static_cast<double>(seen_free_labelled_free.size()) / seen_free_voxels.size(), 0.98);
  EXPECT_GE(free, seen_free_voxels.size());
  EXPECT_GE(static_cast<double>(free_really) / free, 0.98);
  EXPECT_GE(static_cast<double>(clear_labelled_free) / clear_voxels, 0.98);
}
// A 32FC1 image of the camera's size, every pixel at `depth` metres.
sensor_msgs::ImagePtr flatDepthImage(const sensor_msgs::CameraInfo& info, float depth,
                                     const ros::Time& stamp) {
  auto image = boost::make_shared<sensor_msgs::Image>();
  image->header.stamp = stamp;
  image->header.frame_id = info.header.frame_id;
  image->width = info.width;
  image->height = info.height;
  image->encoding = sensor_msgs::image_encodings::TYPE_32FC1;
  image->step = info.width * sizeof(float);
  image->data.resize(static_cast<std::size_t>(image->step) * info.height);
  std::vector<float> pixels(static_cast<std::size_t>(info.width) * info.height, depth);
  std::memcpy(image->data.data(), pixels.data(), image->data.size());
  return image;
}

// Publishes the camera_info, waits until the DepthMapper has it (its "camera_info received"
// count, read fresh before: the simulator is paused, so the test is the only sender), then the
// image with the same stamp: the image cannot overtake its camera_info on its own connection and
// be paired with the previous one.
void sendFrame(ros::Publisher& info_pub, ros::Publisher& image_pub, sensor_msgs::CameraInfo info,
               const sensor_msgs::ImagePtr& image) {
  const ros::WallTime asked = ros::WallTime::now();
  ASSERT_TRUE(waitUntil([&] { return countersOf(*g_observer).depth_status_time > asked; }, 5.0));
  const std::size_t received = countersOf(*g_observer).camera_infos;
  info.header.stamp = image->header.stamp;
  info_pub.publish(info);
  ASSERT_TRUE(waitUntil([&] { return countersOf(*g_observer).camera_infos >= received + 1; }, 5.0))
      << "the DepthMapper did not report the camera_info";
  image_pub.publish(image);
}

TEST(SimDepthMapping, BadFramesLeaveTheMapUnchanged) {
  ros::NodeHandle node_handle;
  ros::Publisher image_pub = node_handle.advertise<sensor_msgs::Image>("camera/depth/image", 5);
  ros::Publisher info_pub =
      node_handle.advertise<sensor_msgs::CameraInfo>("camera/depth/camera_info", 5);
  const sensor_msgs::CameraInfo::ConstPtr info = g_images->latestInfo();
  ASSERT_TRUE(info);
  // The test's own Observer subscribes to both topics (an intra-process link, counted at once):
  // the DepthMapper is connected when a second subscriber is.
  ASSERT_TRUE(waitUntil(
      [&] { return image_pub.getNumSubscribers() >= 2 && info_pub.getNumSubscribers() >= 2; },
      10.0))
      << "the DepthMapper did not connect to the test's publishers";
  const Counters before = countersOf(*g_observer);
  const ros::WallTime map_time_before = latestMap(*g_observer).second;

  // 1 m in front of the camera everywhere: integrated, it would change thousands of voxels.
  auto wrong_encoding = flatDepthImage(*info, 1.0f, ros::Time::now());
  wrong_encoding->encoding = sensor_msgs::image_encodings::RGBA8;  // 4 bytes per pixel too
  sendFrame(info_pub, image_pub, *info, wrong_encoding);
  sensor_msgs::CameraInfo wrong_size = *info;
  wrong_size.width = info->width / 2;
  sendFrame(info_pub, image_pub, wrong_size, flatDepthImage(*info, 1.0f, ros::Time::now()));
  // Neither P (the rectified image's, the one the rule reads where set) nor K has fx.
  sensor_msgs::CameraInfo no_focal_length = *info;
  no_focal_length.P[0] = 0.0;
  no_focal_length.K[0] = 0.0;
  sendFrame(info_pub, image_pub, no_focal_length, flatDepthImage(*info, 1.0f, ros::Time::now()));

  ASSERT_TRUE(waitUntil(
      [&] {
        const Counters now = countersOf(*g_observer);
        return now.dropped_encoding == before.dropped_encoding + 1 &&
               now.dropped_camera_info == before.dropped_camera_info + 2;
      },
      10.0))
      << "the bad frames were not all reported as dropped";
  ros::WallDuration(2.0).sleep();  // four publishing cycles: a change would have been sent
  const Counters after = countersOf(*g_observer);
  EXPECT_EQ(after.integrated, before.integrated);
  EXPECT_EQ(after.known_voxels, before.known_voxels);
  EXPECT_EQ(latestMap(*g_observer).second, map_time_before) << "the map changed";

  // The same frame with its own camera_info is integrated: the bad ones were dropped for what
  // was wrong with them, and a change of the map would have been seen.
  sendFrame(info_pub, image_pub, *info, flatDepthImage(*info, 1.0f, ros::Time::now()));
  EXPECT_TRUE(waitUntil([&] { return latestMap(*g_observer).second > map_time_before; }, 10.0))
      << "a good frame did not change the map";

  // The mapper keeps running on the simulator's images.
  ASSERT_TRUE(setSimulatorPaused(false));
  const std::size_t integrated = countersOf(*g_observer).integrated;
  EXPECT_TRUE(
      waitUntil([&] { return countersOf(*g_observer).integrated >= integrated + 5; }, 20.0));
}

}  // namespace
}  // namespace occupancy_fusion

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sim_depth_mapping_test");
  ros::NodeHandle node_handle;
  ros::NodeHandle private_node_handle("~");
  occupancy_fusion::Settings& settings = occupancy_fusion::g_settings;
  private_node_handle.param("min_images", settings.min_images, settings.min_images);
  private_node_handle.param("resolution", settings.resolution, settings.resolution);
  occupancy_fusion::MapObserver observer(node_handle);
  observer.watch<occupancy_fusion::Octomap>("octomap_binary");
  occupancy_fusion::DepthImageRecorder images(&observer);
  occupancy_fusion::g_observer = &observer;
  occupancy_fusion::g_images = &images;
  return occupancy_fusion::runTestsWhileSpinning();
}
