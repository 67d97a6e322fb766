#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "occupancy_fusion/params/depth_config_reader.h"
#include "occupancy_fusion/tools/yaml_parameter_source.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

std::string readErrorOf(const std::string& yaml) {
  try {
    readPyramidDepthConfig(YamlParameterSource::fromString(yaml));
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "(no exception)";
}

TEST(DepthConfigReader, ReadsEveryField) {
  const PyramidDepthConfig config = readPyramidDepthConfig(YamlParameterSource::fromString(R"(
depth:
  method: andert
  k: 0.1
  sigma: 0.15
  sigma_quadratic: 0.003
  min_range: 0.3
  max_range: 4.5
  unknown_behind_sigmas: 2.5
  max_pyramid_levels: 7
)"));
  EXPECT_EQ(config.method, DepthMethod::kAndert);
  EXPECT_DOUBLE_EQ(config.k, 0.1);
  EXPECT_DOUBLE_EQ(config.sigma, 0.15);
  EXPECT_DOUBLE_EQ(config.sigma_quadratic, 0.003);
  EXPECT_DOUBLE_EQ(config.min_range, 0.3);
  EXPECT_DOUBLE_EQ(config.max_range, 4.5);
  EXPECT_DOUBLE_EQ(config.unknown_behind_sigmas, 2.5);
  EXPECT_EQ(config.max_pyramid_levels, 7);
}

TEST(DepthConfigReader, AbsentKeysKeepDefaults) {
  const PyramidDepthConfig config =
      readPyramidDepthConfig(YamlParameterSource::fromString("resolution: 0.1\n"));
  const PyramidDepthConfig defaults;
  EXPECT_EQ(config.method, defaults.method);
  EXPECT_DOUBLE_EQ(config.k, defaults.k);
  EXPECT_DOUBLE_EQ(config.sigma, defaults.sigma);
  EXPECT_DOUBLE_EQ(config.max_range, defaults.max_range);
  EXPECT_EQ(config.max_pyramid_levels, defaults.max_pyramid_levels);
}

TEST(DepthConfigReader, ErrorsNameTheParameterKey) {
  EXPECT_NE(readErrorOf("depth: {method: octomap}").find("depth/method"), std::string::npos);
  EXPECT_NE(readErrorOf("depth: {sigma: -1}").find("depth/sigma"), std::string::npos);
  // k / (sigma sqrt(2 pi)) = 0.8 / (0.5 * 2.507) = 0.64 >= 0.5: Eq. 7 would give p > 1.
  EXPECT_NE(readErrorOf("depth: {k: 0.8, sigma: 0.5}").find("depth/k"), std::string::npos);
  EXPECT_NE(readErrorOf("depth: {min_range: 5, max_range: 4}").find("depth/max_range"),
            std::string::npos);
  EXPECT_NE(readErrorOf("depth: {max_pyramid_levels: 0}").find("depth/max_pyramid_levels"),
            std::string::npos);
  EXPECT_NE(readErrorOf("depth: {k: fast}").find("depth/k"), std::string::npos);
}

// The shipped config file parses and sets every field (its k and sigma are scaled to its 0.05 m
// map, the rest are the defaults it documents).
TEST(DepthConfigReader, ShippedConfigFileSetsEveryField) {
  const fs::path repository = OCCUPANCY_FUSION_SOURCE_DIR;
  const YamlParameterSource source =
      YamlParameterSource::fromFile((repository / "config/depth_mapper.yaml").string());
  const PyramidDepthConfig config = readPyramidDepthConfig(source);
  const PyramidDepthConfig defaults;
  EXPECT_EQ(config.method, defaults.method);
  EXPECT_DOUBLE_EQ(config.k, 0.05);
  EXPECT_DOUBLE_EQ(config.sigma, 0.05);
  EXPECT_DOUBLE_EQ(config.sigma_quadratic, defaults.sigma_quadratic);
  EXPECT_DOUBLE_EQ(config.min_range, defaults.min_range);
  EXPECT_DOUBLE_EQ(config.max_range, defaults.max_range);
  EXPECT_DOUBLE_EQ(config.unknown_behind_sigmas, defaults.unknown_behind_sigmas);
  EXPECT_EQ(config.max_pyramid_levels, defaults.max_pyramid_levels);
  for (const char* key :
       {"depth/method", "depth/k", "depth/sigma", "depth/sigma_quadratic", "depth/min_range",
        "depth/max_range", "depth/unknown_behind_sigmas", "depth/max_pyramid_levels"}) {
    std::string text;
    EXPECT_TRUE(source.get(key, &text)) << key;
  }
}

}  // namespace
}  // namespace occupancy_fusion
