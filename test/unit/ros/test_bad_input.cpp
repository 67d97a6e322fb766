// The bad-input matrix at the level of the functions the mapper nodelets call: a ROS message in,
// the core's input or a named rejection out; and, where bad values are skipped rather than the
// frame dropped, the map built from the frame equals the map built from its valid part alone.
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include "occupancy_fusion/integrators/depth/pyramid_depth_integrator.h"
#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"
#include "occupancy_fusion/integrators/point_cloud_integrator.h"
#include "occupancy_fusion/integrators/stereo/visibility_stereo_integrator.h"
#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/map/voxel_map.h"
#include "occupancy_fusion/params/config_readers.h"
#include "occupancy_fusion/params/parameter_source.h"
#include "occupancy_fusion/ros/conversions.h"
#include "occupancy_fusion/ros/depth_messages.h"
#include "occupancy_fusion/ros/disparity_messages.h"
#include "occupancy_fusion/ros/map_publisher.h"
#include "occupancy_fusion/sensors/laser_scan.h"

namespace occupancy_fusion {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
// The bad values of a depth or disparity pixel, each named for the failure message.
const std::vector<std::pair<std::string, float>> kBadValues = {
    {"NaN", kNaN}, {"+inf", kInf}, {"-inf", -kInf}, {"0", 0.0f}, {"negative", -1.5f}};

using VoxelDump = std::map<std::tuple<int, int, int>, float>;

VoxelDump dump(const VoxelMap& map) {
  VoxelDump voxels;
  map.forEachKnownVoxel([&](const VoxelIndex& index, float log_odds) {
    voxels[{index.x(), index.y(), index.z()}] = log_odds;
  });
  return voxels;
}

std::map<std::pair<int, int>, float> dump(const GridLayer2D& layer) {
  std::map<std::pair<int, int>, float> cells;
  layer.forEachKnownCell([&](const CellIndex& index, float log_odds) {
    cells[{index.x(), index.y()}] = log_odds;
  });
  return cells;
}

template <typename Exception, typename Fn>
std::string messageOf(Fn&& fn) {
  try {
    fn();
  } catch (const Exception& error) {
    return error.what();
  }
  return "(nothing thrown)";
}

// ---- depth images ---------------------------------------------------------------------------

constexpr int kWidth = 32, kHeight = 24;

sensor_msgs::Image floatImage(const std::vector<float>& values, const std::string& encoding) {
  sensor_msgs::Image image;
  image.width = kWidth;
  image.height = kHeight;
  image.encoding = encoding;
  image.step = kWidth * sizeof(float);
  image.data.resize(values.size() * sizeof(float));
  std::memcpy(image.data.data(), values.data(), image.data.size());
  return image;
}

sensor_msgs::CameraInfo cameraInfo(int width, int height, double f) {
  sensor_msgs::CameraInfo info;
  info.width = width;
  info.height = height;
  info.K = {f, 0.0, (width - 1) / 2.0, 0.0, f, (height - 1) / 2.0, 0.0, 0.0, 1.0};
  return info;
}

// A wall 2 m ahead, with a block of pixels (the "bad part") set to `bad`.
std::vector<float> wallWithBadBlock(float bad) {
  std::vector<float> depth(kWidth * kHeight, 2.0f);
  for (int v = 8; v < 16; ++v)
    for (int u = 10; u < 20; ++u) depth[v * kWidth + u] = bad;
  return depth;
}

VoxelDump depthMap(const std::vector<float>& depth) {
  VoxelMapConfig map_config;
  map_config.resolution = 0.1;
  VoxelMap map(map_config);
  const sensor_msgs::Image image = floatImage(depth, "32FC1");
  std::vector<float> storage;
  const DepthImageView view = depthInMetres(image, &storage);
  const CameraIntrinsics camera = depthCameraIntrinsics(cameraInfo(kWidth, kHeight, 30.0), image);
  PyramidDepthIntegrator(PyramidDepthConfig())
      .integrate(view, camera, Eigen::Isometry3d::Identity(), &map);
  return dump(map);
}

TEST(BadDepthInput, BadPixelsAreSkippedAsNoMeasurement) {
  // The reference: the bad block holds NaN, the documented "no measurement".
  const VoxelDump valid_part_only = depthMap(wallWithBadBlock(kNaN));
  ASSERT_FALSE(valid_part_only.empty());
  // The test can fail: a block of valid depths maps differently.
  ASSERT_NE(depthMap(wallWithBadBlock(1.0f)), valid_part_only);
  for (const auto& [name, value] : kBadValues) {
    EXPECT_EQ(depthMap(wallWithBadBlock(value)), valid_part_only) << name << " depth pixels";
  }
}

TEST(BadDepthInput, UnsupportedEncodingOrLayoutIsRejectedAsEncoding) {
  std::vector<float> storage;
  sensor_msgs::Image rgb = floatImage(wallWithBadBlock(2.0f), "rgb8");
  try {
    depthInMetres(rgb, &storage);
    FAIL() << "rgb8 accepted";
  } catch (const DepthImageRejected& error) {
    EXPECT_EQ(error.reason(), DepthImageRejected::Reason::kEncoding);
    EXPECT_NE(std::string(error.what()).find("'rgb8'"), std::string::npos) << error.what();
  }
  sensor_msgs::Image short_data = floatImage(wallWithBadBlock(2.0f), "32FC1");
  short_data.data.resize(short_data.data.size() / 2);
  EXPECT_THROW(depthInMetres(short_data, &storage), DepthImageRejected);
  sensor_msgs::Image foreign_order = floatImage(wallWithBadBlock(2.0f), "32FC1");
  foreign_order.is_bigendian = !foreign_order.is_bigendian;
  EXPECT_THROW(depthInMetres(foreign_order, &storage), DepthImageRejected);
}

TEST(BadDepthInput, CameraInfoOfAnotherSizeOrWithoutFocalLengthIsRejected) {
  const sensor_msgs::Image image = floatImage(wallWithBadBlock(2.0f), "32FC1");
  const auto reasonOf = [&](const sensor_msgs::CameraInfo& info) {
    try {
      depthCameraIntrinsics(info, image);
    } catch (const DepthImageRejected& error) {
      return std::make_pair(error.reason(), std::string(error.what()));
    }
    return std::make_pair(DepthImageRejected::Reason::kEncoding, std::string("accepted"));
  };
  const auto other_size = reasonOf(cameraInfo(64, 48, 30.0));
  EXPECT_EQ(other_size.first, DepthImageRejected::Reason::kCameraInfo);
  EXPECT_NE(other_size.second.find("64x48"), std::string::npos) << other_size.second;
  EXPECT_NE(other_size.second.find("32x24"), std::string::npos) << other_size.second;
  const auto zero_focal = reasonOf(cameraInfo(kWidth, kHeight, 0.0));
  EXPECT_EQ(zero_focal.first, DepthImageRejected::Reason::kCameraInfo);
  EXPECT_NE(zero_focal.second.find("focal length"), std::string::npos) << zero_focal.second;
  EXPECT_NO_THROW(depthCameraIntrinsics(cameraInfo(kWidth, kHeight, 30.0), image));
}

// ---- disparity images -----------------------------------------------------------------------

// Long focal length and baseline: the wall at 2 m is certain enough to be mapped.
constexpr double kStereoFocal = 300.0, kStereoBaseline = 0.2;  // px, m

stereo_msgs::DisparityImage disparityMessage(float bad) {
  StereoCamera camera;
  camera.fx = camera.fy = kStereoFocal;
  camera.cx = (kWidth - 1) / 2.0;
  camera.cy = (kHeight - 1) / 2.0;
  camera.baseline = kStereoBaseline;
  // d = f T / z: a wall at 2 m.
  std::vector<float> disparity = wallWithBadBlock(bad);
  for (float& d : disparity) {
    if (d == 2.0f) d = static_cast<float>(kStereoFocal * kStereoBaseline / 2.0);
  }
  // Written with the bad values as they are (disparityImageMessage writes NaN as -1).
  stereo_msgs::DisparityImage message =
      disparityImageMessage(std::vector<float>(kWidth * kHeight, 1.5f), kWidth, kHeight, camera);
  std::memcpy(message.image.data.data(), disparity.data(), message.image.data.size());
  // A matcher that searches negative disparities too: 0 and negative values reach the core.
  message.min_disparity = -16.0f;
  message.max_disparity = 100.0f;
  return message;
}

VoxelDump disparityMap(const stereo_msgs::DisparityImage& message) {
  VoxelMapConfig map_config;
  map_config.resolution = 0.1;
  VoxelMap map(map_config);
  const std::vector<float> disparity = validDisparities(message);
  const StereoCamera camera =
      stereoCameraOf(message, leftCameraInfoMessage({kStereoFocal, kStereoFocal, (kWidth - 1) / 2.0,
                                                     (kHeight - 1) / 2.0, kStereoBaseline},
                                                    kWidth, kHeight));
  const DisparityImageView view{kWidth, kHeight, disparity.data(), 0};
  // OctoMap's update on the same rays: in an empty map the paper's visibility stops rays early,
  // which would hide whether the bad block wrote anything.
  VisibilityStereoConfig config;
  config.method = StereoIntegrationMethod::kOctomap;
  VisibilityStereoIntegrator(config).integrate(view, camera, Eigen::Isometry3d::Identity(), &map);
  return dump(map);
}

TEST(BadDisparityInput, BadPixelsAreSkipped) {
  const VoxelDump valid_part_only = disparityMap(disparityMessage(kNaN));
  ASSERT_FALSE(valid_part_only.empty());
  ASSERT_NE(disparityMap(disparityMessage(60.0f)), valid_part_only);  // a block at 1 m
  for (const auto& [name, value] : kBadValues) {
    EXPECT_EQ(disparityMap(disparityMessage(value)), valid_part_only) << name << " disparities";
  }
}

TEST(BadDisparityInput, BadBaselineFocalLengthSizeOrEncodingIsRejectedNamingIt) {
  const sensor_msgs::CameraInfo info =
      leftCameraInfoMessage({30.0, 30.0, 15.5, 11.5, 0.1}, kWidth, kHeight);
  for (const float baseline : {0.0f, -0.1f, kNaN}) {
    stereo_msgs::DisparityImage message = disparityMessage(kNaN);
    message.T = baseline;
    const std::string why =
        messageOf<std::invalid_argument>([&] { stereoCameraOf(message, info); });
    EXPECT_NE(why.find("baseline"), std::string::npos) << "T = " << baseline << ": " << why;
  }
  stereo_msgs::DisparityImage zero_f = disparityMessage(kNaN);
  zero_f.f = 0.0f;
  EXPECT_NE(messageOf<std::invalid_argument>([&] { stereoCameraOf(zero_f, info); }).find("fx"),
            std::string::npos);
  const std::string other_size = messageOf<std::invalid_argument>(
      [&] { stereoCameraOf(disparityMessage(kNaN), leftCameraInfoMessage({}, 64, 48)); });
  EXPECT_NE(other_size.find("64x48"), std::string::npos) << other_size;
  stereo_msgs::DisparityImage mono16 = disparityMessage(kNaN);
  mono16.image.encoding = "16UC1";
  EXPECT_NE(messageOf<std::invalid_argument>([&] { validDisparities(mono16); }).find("'16UC1'"),
            std::string::npos);
}

// ---- camera_info and validity: the rules the nodelets and the bag reader share ---------------

TEST(CameraInfoRule, ProjectionWhereSetElseKBinningDividesRegionOfInterestRejected) {
  const sensor_msgs::Image image = floatImage(wallWithBadBlock(2.0f), "32FC1");
  sensor_msgs::CameraInfo info = cameraInfo(kWidth, kHeight, 30.0);  // P unset: K's
  EXPECT_DOUBLE_EQ(depthCameraIntrinsics(info, image).fx, 30.0);
  EXPECT_DOUBLE_EQ(depthCameraIntrinsics(info, image).cx, 15.5);
  // A rectified camera: P differs from K, and the image is P's.
  info.P = {28.0, 0.0, 14.0, 0.0, 0.0, 29.0, 11.0, 0.0, 0.0, 0.0, 1.0, 0.0};
  const CameraIntrinsics depth = depthCameraIntrinsics(info, image);
  EXPECT_DOUBLE_EQ(depth.fx, 28.0);
  EXPECT_DOUBLE_EQ(depth.fy, 29.0);
  EXPECT_DOUBLE_EQ(depth.cx, 14.0);
  EXPECT_DOUBLE_EQ(depth.cy, 11.0);
  // The disparity image keeps its own f and T; the rest is the same rule's.
  const StereoCamera stereo = stereoCameraOf(disparityMessage(kNaN), info);
  EXPECT_DOUBLE_EQ(stereo.fx, kStereoFocal);
  EXPECT_DOUBLE_EQ(stereo.fy, 29.0);
  EXPECT_DOUBLE_EQ(stereo.cx, 14.0);
  EXPECT_DOUBLE_EQ(stereo.cy, 11.0);
  // A camera_info of the full sensor binned 2 x 2 describes the half-size image.
  sensor_msgs::CameraInfo binned = info;
  binned.width = 2 * kWidth;
  binned.height = 2 * kHeight;
  binned.binning_x = binned.binning_y = 2;
  binned.P = {56.0, 0.0, 28.0, 0.0, 0.0, 58.0, 22.0, 0.0, 0.0, 0.0, 1.0, 0.0};
  const CameraIntrinsics half = depthCameraIntrinsics(binned, image);
  EXPECT_EQ(half.width, kWidth);
  EXPECT_DOUBLE_EQ(half.fx, 28.0);
  EXPECT_DOUBLE_EQ(half.cy, 11.0);
  EXPECT_DOUBLE_EQ(stereoCameraOf(disparityMessage(kNaN), binned).fy, 29.0);
  sensor_msgs::CameraInfo roi = info;
  roi.roi.width = 10;
  roi.roi.height = 10;
  EXPECT_THROW(depthCameraIntrinsics(roi, image), DepthImageRejected);
  EXPECT_THROW(stereoCameraOf(disparityMessage(kNaN), roi), std::invalid_argument);
}

TEST(DisparityValidity, OutsideTheValidWindowIsNoMatchAndAnUnsetMaximumBoundsNothing) {
  // A block at 1 m (60 px) inside a wall at 2 m (30 px): both above the unset maximum.
  stereo_msgs::DisparityImage message = disparityMessage(60.0f);
  message.min_disparity = 0.0f;
  message.max_disparity = 0.0f;  // not filled in
  message.valid_window.x_offset = 4;
  message.valid_window.y_offset = 2;
  message.valid_window.width = 20;
  message.valid_window.height = 18;
  const std::vector<float> disparity = validDisparities(message);
  const float wall = static_cast<float>(kStereoFocal * kStereoBaseline / 2.0);
  EXPECT_FLOAT_EQ(disparity[2 * kWidth + 4], wall);      // first pixel inside
  EXPECT_FLOAT_EQ(disparity[19 * kWidth + 23], wall);    // last pixel inside
  EXPECT_FLOAT_EQ(disparity[10 * kWidth + 15], 60.0f);   // the block
  EXPECT_TRUE(std::isnan(disparity[2 * kWidth + 3]));    // left of the window
  EXPECT_TRUE(std::isnan(disparity[1 * kWidth + 4]));    // above it
  EXPECT_TRUE(std::isnan(disparity[19 * kWidth + 24]));  // right of it
  EXPECT_TRUE(std::isnan(disparity[20 * kWidth + 23]));  // below it
  std::size_t valid = 0;
  for (const float d : disparity) valid += std::isnan(d) ? 0 : 1;
  EXPECT_EQ(valid, 20u * 18u);
}

// ---- laser scans ----------------------------------------------------------------------------

sensor_msgs::LaserScan scanMessage(int beams) {
  sensor_msgs::LaserScan scan;
  scan.angle_min = -1.0f;
  scan.angle_increment = 2.0f / (beams - 1);
  scan.angle_max = 1.0f;
  scan.range_min = 0.2f;
  scan.range_max = 8.0f;
  scan.ranges.assign(beams, 3.0f);
  return scan;
}

TEST(BadLaserInput, BadGeometryIsRejectedNamingIt) {
  sensor_msgs::LaserScan zero_increment = scanMessage(101);
  zero_increment.angle_increment = 0.0f;
  EXPECT_NE(messageOf<std::invalid_argument>([&] {
              checkedLaserScan(zero_increment);
            }).find("angle_increment"),
            std::string::npos);
  sensor_msgs::LaserScan too_few = scanMessage(101);
  too_few.ranges.resize(90);
  const std::string count = messageOf<std::invalid_argument>([&] { checkedLaserScan(too_few); });
  EXPECT_NE(count.find("90 ranges"), std::string::npos) << count;
  EXPECT_NE(count.find("101"), std::string::npos) << count;
  sensor_msgs::LaserScan min_above_max = scanMessage(101);
  min_above_max.range_min = 9.0f;
  EXPECT_NE(
      messageOf<std::invalid_argument>([&] { checkedLaserScan(min_above_max); }).find("range_max"),
      std::string::npos);
  // A negative increment is the same scan listed backwards, not an error.
  sensor_msgs::LaserScan backwards = scanMessage(101);
  backwards.ranges[0] = 1.0f;
  std::swap(backwards.angle_min, backwards.angle_max);
  backwards.angle_increment = -backwards.angle_increment;
  const LaserScan reversed = checkedLaserScan(backwards);
  EXPECT_NEAR(reversed.angle_min, -1.0, 1e-6);
  EXPECT_GT(reversed.angle_increment, 0.0);
  EXPECT_FLOAT_EQ(reversed.ranges.back(), 1.0f);
}

std::map<std::pair<int, int>, float> laserLayer(const sensor_msgs::LaserScan& message) {
  GridLayer2DConfig layer_config;
  layer_config.resolution = 0.1;
  GridLayer2D layer(layer_config);
  PolarLaserIntegrator().integrateIntoLayer(checkedLaserScan(message), Pose2D{}, &layer);
  return dump(layer);
}

TEST(BadLaserInput, RangesOutsideTheirLimitsAreSkippedBeams) {
  const auto withBeams = [](float value) {
    sensor_msgs::LaserScan scan = scanMessage(101);
    for (int i = 40; i < 60; ++i) scan.ranges[i] = value;
    return scan;
  };
  const auto valid_part_only = laserLayer(withBeams(kNaN));  // NaN: REP-117's invalid reading
  ASSERT_FALSE(valid_part_only.empty());
  ASSERT_NE(laserLayer(withBeams(2.0f)), valid_part_only);
  for (const float value : {0.1f /* < range_min */, 9.0f /* > range_max */, 0.0f, -2.0f}) {
    EXPECT_EQ(laserLayer(withBeams(value)), valid_part_only) << "ranges of " << value << " m";
  }
}

// ---- point clouds ---------------------------------------------------------------------------

sensor_msgs::PointCloud2 cloudOf(const std::vector<Eigen::Vector3f>& points) {
  sensor_msgs::PointCloud2 cloud;
  resizeXyzCloud(points.size(), &cloud);
  sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  for (const Eigen::Vector3f& p : points) {
    *x = p.x(), *y = p.y(), *z = p.z();
    ++x, ++y, ++z;
  }
  return cloud;
}

VoxelDump cloudMap(const sensor_msgs::PointCloud2& cloud) {
  VoxelMapConfig map_config;
  map_config.resolution = 0.1;
  VoxelMap map(map_config);
  PointCloudIntegrator().integrate(transformedPoints(cloud, Eigen::Isometry3d::Identity()),
                                   Eigen::Vector3d::Zero(), &map);
  return dump(map);
}

TEST(BadCloudInput, NonFinitePointsAreSkippedAndMissingFieldsRejected) {
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 20; ++i) points.emplace_back(2.0f, 0.1f * i - 1.0f, 0.3f);
  const VoxelDump valid_part_only = cloudMap(cloudOf(points));
  ASSERT_FALSE(valid_part_only.empty());
  for (const float bad : {kNaN, kInf, -kInf}) {
    std::vector<Eigen::Vector3f> with_bad = points;
    with_bad.emplace_back(bad, 0.0f, 0.0f);
    with_bad.emplace_back(1.0f, bad, 1.0f);
    EXPECT_EQ(cloudMap(cloudOf(with_bad)), valid_part_only) << bad;
  }
  sensor_msgs::PointCloud2 no_z = cloudOf(points);
  no_z.header.frame_id = "lidar";
  no_z.fields.pop_back();
  EXPECT_NE(messageOf<std::invalid_argument>([&] {
              transformedPoints(no_z, Eigen::Isometry3d::Identity());
            }).find("'lidar'"),
            std::string::npos);
}

// ---- parameters -----------------------------------------------------------------------------

// Doubles by key; every other type absent.
class DoubleParameters : public ParameterSource {
 public:
  explicit DoubleParameters(std::map<std::string, double> values) : values_(std::move(values)) {}
  bool get(const std::string& key, double* value) const override {
    const auto found = values_.find(key);
    if (found == values_.end()) return false;
    *value = found->second;
    return true;
  }
  bool get(const std::string&, int*) const override { return false; }
  bool get(const std::string&, bool*) const override { return false; }
  bool get(const std::string&, std::string*) const override { return false; }
  bool get(const std::string&, std::vector<std::string>*) const override { return false; }
  bool get(const std::string&, std::vector<double>*) const override { return false; }

 private:
  std::map<std::string, double> values_;
};

TEST(BadParameters, AreRejectedNamingTheParameter) {
  const std::vector<std::pair<std::map<std::string, double>, std::string>> cases = {
      {{{"resolution", -0.05}}, "resolution"},
      {{{"resolution", 0.0}}, "resolution"},
      {{{"sensor_model/min", 0.9}, {"sensor_model/max", 0.2}}, "sensor_model/min"},
      {{{"sensor_model/hit", 1.5}}, "sensor_model/hit"},
      {{{"sensor_model/miss", 0.0}}, "sensor_model/miss"},
      {{{"sensor_model/max", 1.0}}, "sensor_model/max"},
      {{{"spill_max_mb", -1.0}}, "spill_max_mb"},
      {{{"spill_max_mb", std::nan("")}}, "spill_max_mb"},
      {{{"max_memory_mb", -2.0}}, "max_memory_mb"},
      {{{"layer_max_memory_mb", -1.0}}, "layer_max_memory_mb"},
  };
  for (const auto& [values, name] : cases) {
    const std::string why = messageOf<std::invalid_argument>([&] {
      const VoxelMapConfig config = readVoxelMapConfig(DoubleParameters(values));
      VoxelMap map(config);
    });
    EXPECT_NE(why.find(name), std::string::npos) << name << ": " << why;
  }
  EXPECT_NO_THROW(readVoxelMapConfig(DoubleParameters({{"resolution", 0.1}})));
}

// Each case's values rejected by `read` with std::invalid_argument, its message naming the
// parameter.
template <class Values, class Read>
void expectEachRejectedNaming(const std::vector<std::pair<Values, std::string>>& cases, Read read) {
  for (const auto& [values, name] : cases) {
    const std::string why = messageOf<std::invalid_argument>([&] { read(values); });
    EXPECT_NE(why.find(name), std::string::npos) << name << ": " << why;
  }
}

// The MapServer's publishing rates: how often each output may be sent.
TEST(BadParameters, PublishingRatesAreRejectedNamingTheParameter) {
  const std::vector<std::pair<std::map<std::string, double>, std::string>> cases = {
      {{{"publish_rate", 0.0}}, "publish_rate"},
      {{{"publish_rate", std::nan("")}}, "publish_rate"},
      {{{"projected_map_rate", -1.0}}, "projected_map_rate"},
      {{{"projected_map_rate", std::numeric_limits<double>::infinity()}}, "projected_map_rate"},
  };
  expectEachRejectedNaming(cases, [](const std::map<std::string, double>& values) {
    readMapPublisherConfig(DoubleParameters(values));
  });
  const MapPublisherConfig defaults = readMapPublisherConfig(DoubleParameters({}));
  EXPECT_EQ(defaults.publish_rate, 1.0);
  EXPECT_EQ(defaults.projected_map_rate, 50.0);
  EXPECT_EQ(
      readMapPublisherConfig(DoubleParameters({{"projected_map_rate", 0.0}})).projected_map_rate,
      0.0);  // 0: projected_map at publish_rate
}

// A mapper nodelet's own settings: queue_size and threads.
TEST(BadParameters, MapperQueueAndThreadsAreRejectedNamingTheParameter) {
  class IntParameters : public DoubleParameters {
   public:
    explicit IntParameters(std::map<std::string, int> values)
        : DoubleParameters({}), values_(std::move(values)) {}
    using DoubleParameters::get;
    bool get(const std::string& key, int* value) const override {
      const auto found = values_.find(key);
      if (found == values_.end()) return false;
      *value = found->second;
      return true;
    }

   private:
    std::map<std::string, int> values_;
  };
  const std::vector<std::pair<std::map<std::string, int>, std::string>> cases = {
      {{{"queue_size", 0}}, "queue_size"},
      {{{"threads", -1}}, "threads"},
      {{{"threads", 257}}, "threads"},
  };
  expectEachRejectedNaming(cases, [](const std::map<std::string, int>& values) {
    readMapperNodeletConfig(IntParameters(values));
  });
  const MapperNodeletConfig defaults = readMapperNodeletConfig(IntParameters({}));
  EXPECT_EQ(defaults.queue_size, 5);
  EXPECT_EQ(defaults.threads, 0);
  const MapperNodeletConfig read =
      readMapperNodeletConfig(IntParameters({{"queue_size", 1}, {"threads", 256}}));
  EXPECT_EQ(read.queue_size, 1);
  EXPECT_EQ(read.threads, 256);
}

// The spill store's parameters reach the map's config, in bytes.
TEST(MapParameters, SpillFolderAndLimitReachTheMap) {
  class SpillParameters : public DoubleParameters {
   public:
    SpillParameters() : DoubleParameters({{"max_memory_mb", 64.0}, {"spill_max_mb", 2.5}}) {}
    using DoubleParameters::get;
    bool get(const std::string& key, std::string* value) const override {
      if (key != "spill_folder") return false;
      *value = "/maps/spill";
      return true;
    }
  };
  const VoxelMapConfig config = readVoxelMapConfig(SpillParameters());
  EXPECT_EQ(config.spill_folder, "/maps/spill");
  EXPECT_EQ(config.spill_max_bytes, std::size_t{5} * 1024 * 1024 / 2);
  EXPECT_EQ(config.max_memory_bytes, std::size_t{64} * 1024 * 1024);
  EXPECT_TRUE(readVoxelMapConfig(DoubleParameters({})).spill_folder.empty());
}

}  // namespace
}  // namespace occupancy_fusion
