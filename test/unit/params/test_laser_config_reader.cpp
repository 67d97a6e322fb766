#include "occupancy_fusion/params/laser_config_reader.h"

#include <gtest/gtest.h>

#include <map>
#include <stdexcept>
#include <string>
#include <variant>

#include "../../common/map_parameter_source.h"

namespace occupancy_fusion {
namespace {

using MapSource = MapParameterSource;

std::string errorOf(const MapSource& source) {
  try {
    readLaserMapperConfig(source);
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "";
}

TEST(LaserConfigReader, SourcesOverrideTheSharedBlockWhichOverridesTheDefaults) {
  const MapSource source({{"observation_sources", std::string("front rear")},
                          {"laser/method", std::string("exact")},
                          {"laser/range_sigma", 0.08},
                          {"laser/no_return_free_length", 4.0},
                          {"front/topic", std::string("front/scan")},
                          {"front/method", std::string("lines")},
                          {"rear/sensor_frame", std::string("rear_laser")},
                          {"rear/range_sigma", 0.02},
                          {"rear/prior", 0.3},
                          {"rear/negligible_log_ratio", 0.01},
                          {"rear/above_range_max_is_no_return", true},
                          {"local_grid/size_x", 12.0},
                          {"local_grid/frame_id", std::string("chassis")}});
  const LaserMapperConfig config = readLaserMapperConfig(source);
  ASSERT_EQ(config.sources.size(), 2u);
  const LaserSourceConfig& front = config.sources[0];
  const LaserSourceConfig& rear = config.sources[1];
  EXPECT_EQ(front.name, "front");
  EXPECT_EQ(front.topic, "front/scan");
  EXPECT_EQ(front.sensor_frame, "");
  EXPECT_EQ(front.integrator.method, PolarToCartesianMethod::kLines);
  EXPECT_DOUBLE_EQ(front.integrator.model.range_sigma, 0.08);
  EXPECT_DOUBLE_EQ(front.integrator.model.no_return_free_length, 4.0);
  EXPECT_DOUBLE_EQ(front.integrator.model.prior_occupancy, 0.5);
  EXPECT_FALSE(front.integrator.model.ranges.above_range_max_is_no_return);
  EXPECT_EQ(rear.topic, "rear");  // costmap_2d's default: the source's name
  EXPECT_EQ(rear.sensor_frame, "rear_laser");
  EXPECT_EQ(rear.integrator.method, PolarToCartesianMethod::kExact);
  EXPECT_DOUBLE_EQ(rear.integrator.model.range_sigma, 0.02);
  EXPECT_DOUBLE_EQ(rear.integrator.model.prior_occupancy, 0.3);
  EXPECT_DOUBLE_EQ(rear.integrator.model.negligible_log_ratio, 0.01);
  EXPECT_DOUBLE_EQ(front.integrator.model.negligible_log_ratio,
                   LaserSensorModelConfig().negligible_log_ratio);
  EXPECT_TRUE(rear.integrator.model.ranges.above_range_max_is_no_return);
  EXPECT_DOUBLE_EQ(config.local_grid.grid.size_x, 12.0);
  EXPECT_DOUBLE_EQ(config.local_grid.grid.size_y, LocalLaserGridConfig().size_y);
  EXPECT_EQ(config.local_grid.frame_id, "chassis");
  EXPECT_EQ(config.map_frame, "map");
}

TEST(LaserConfigReader, SourceNamesMayBeAList) {
  const MapSource source(
      {{"observation_sources", std::vector<std::string>{"left", "right", "back"}}});
  const auto sources = readLaserSourceConfigs(source);
  ASSERT_EQ(sources.size(), 3u);
  EXPECT_EQ(sources[2].topic, "back");
}

TEST(LaserConfigReader, ErrorsNameTheParameterWithItsFullKey) {
  using M = std::map<std::string, MapSource::Value>;
  const std::string front = "front";
  EXPECT_NE(errorOf(MapSource(M{})).find("observation_sources"), std::string::npos);
  EXPECT_NE(errorOf(MapSource(M{{"observation_sources", std::string("a a")}})).find("'a' twice"),
            std::string::npos);
  EXPECT_NE(errorOf(MapSource(M{{"observation_sources", front}, {"front/range_sigma", -0.1}}))
                .find("front/range_sigma"),
            std::string::npos);
  EXPECT_NE(errorOf(MapSource(M{{"observation_sources", front}, {"laser/prior", 1.0}}))
                .find("laser/prior"),
            std::string::npos);
  EXPECT_NE(
      errorOf(MapSource(M{{"observation_sources", front}, {"front/method", std::string("cubic")}}))
          .find("front/method"),
      std::string::npos);
  EXPECT_NE(errorOf(MapSource(M{{"observation_sources", front}, {"front/min_log_ratio", 0.5}}))
                .find("front/min_log_ratio"),
            std::string::npos);
  EXPECT_NE(errorOf(MapSource(M{{"observation_sources", front}, {"local_grid/size_y", 0.01}}))
                .find("local_grid/size_y"),
            std::string::npos);
  EXPECT_NE(errorOf(MapSource(M{{"observation_sources", front}, {"local_grid/publish_rate", 0.0}}))
                .find("local_grid/publish_rate"),
            std::string::npos);
  EXPECT_NE(errorOf(MapSource(M{{"observation_sources", front}, {"front/max_samples_per_axis", 0}}))
                .find("front/max_samples_per_axis"),
            std::string::npos);
}

TEST(LaserConfigReader, AbsentKeysKeepTheCoreDefaults) {
  const PolarLaserIntegratorConfig read = readPolarLaserIntegratorConfig(MapSource({}), "laser/");
  const PolarLaserIntegratorConfig defaults;
  EXPECT_EQ(read.method, defaults.method);
  EXPECT_DOUBLE_EQ(read.model.range_resolution, defaults.model.range_resolution);
  EXPECT_DOUBLE_EQ(read.model.max_log_ratio, defaults.model.max_log_ratio);
  EXPECT_DOUBLE_EQ(read.mipmap.safety_radius, defaults.mipmap.safety_radius);
  EXPECT_EQ(read.exact_cache_capacity, defaults.exact_cache_capacity);
}

}  // namespace
}  // namespace occupancy_fusion
