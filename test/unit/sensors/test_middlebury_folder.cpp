// The Middlebury scene reader: PFM bytes in both byte orders, calib.txt as the data set writes it,
// the d + doffs disparity convention and per-view pose files, on files written here.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "occupancy_fusion/sensors/middlebury_folder.h"

#include "../../common/test_folder.h"

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

// The float's four bytes in the given order, assembled from its bit pattern (not the host's).
std::string floatBytes(float value, bool little_endian) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  std::string bytes(4, '\0');
  for (int i = 0; i < 4; ++i) {
    const int shift = little_endian ? 8 * i : 8 * (3 - i);
    bytes[i] = static_cast<char>((bits >> shift) & 0xFF);
  }
  return bytes;
}

// A 1-channel PFM of the given rows (top to bottom), written bottom to top as the format wants.
std::string pfmBytes(const std::vector<std::vector<float>>& rows_top_to_bottom, bool little_endian,
                     const std::string& scale_text) {
  std::string bytes = "Pf\n" + std::to_string(rows_top_to_bottom.front().size()) + " " +
                      std::to_string(rows_top_to_bottom.size()) + "\n" + scale_text + "\n";
  for (auto row = rows_top_to_bottom.rbegin(); row != rows_top_to_bottom.rend(); ++row) {
    for (float value : *row) bytes += floatBytes(value, little_endian);
  }
  return bytes;
}

void writeFile(const fs::path& path, const std::string& bytes) {
  std::ofstream file(path, std::ios::binary);
  file << bytes;
}

const float kInf = std::numeric_limits<float>::infinity();

// Artl's calib.txt as the data set ships it: stray spaces, entries split across lines.
const char* kArtCalibration =
    "cam0=[ 935 0 148 ; 0 935 138 ; 0 0 1 ] \n"
    "cam1=[ 935 0 198 ; 0 935 138 ; 0 0 1 ]\n"
    " doffs= 50 \n"
    "baseline= 160\n"
    " width= 3 \n"
    "height= 2 \n"
    "ndisp= 64\n"
    " isint= 0\n"
    " vmin= 16\n"
    " vmax= 58\n"
    " dyavg= 0\n"
    " dymax= 0\n";

TEST(PfmTest, LittleEndianRowsBottomToTop) {
  // 1.5 = 0x3FC00000: little-endian bytes 00 00 C0 3F. Check the writer against that by hand so
  // that the reader is not tested only against its own mirror image.
  EXPECT_EQ(floatBytes(1.5f, true), std::string("\x00\x00\xC0\x3F", 4));
  EXPECT_EQ(floatBytes(1.5f, false), std::string("\x3F\xC0\x00\x00", 4));
  const PfmImage image =
      parsePfm(pfmBytes({{1.5f, 2.0f, 3.0f}, {-4.0f, kInf, 6.25f}}, true, "-1.0"));
  EXPECT_EQ(image.width, 3);
  EXPECT_EQ(image.height, 2);
  EXPECT_EQ(image.channels, 1);
  EXPECT_EQ(image.at(0, 0), 1.5f);  // the top row, stored last
  EXPECT_EQ(image.at(2, 0), 3.0f);
  EXPECT_EQ(image.at(0, 1), -4.0f);
  EXPECT_TRUE(std::isinf(image.at(1, 1)));
  EXPECT_EQ(image.at(2, 1), 6.25f);
}

TEST(PfmTest, BigEndianWithPositiveScale) {
  const PfmImage image = parsePfm(pfmBytes({{1.5f, 2.0f}, {-4.0f, 0.125f}}, false, "1"));
  EXPECT_EQ(image.at(0, 0), 1.5f);
  EXPECT_EQ(image.at(1, 0), 2.0f);
  EXPECT_EQ(image.at(0, 1), -4.0f);
  EXPECT_EQ(image.at(1, 1), 0.125f);
}

TEST(PfmTest, ByteOrderFollowsTheScaleSign) {
  // The same little-endian data read as big-endian gives other values: the sign matters.
  std::string bytes = pfmBytes({{1.5f}}, true, "-1");
  EXPECT_EQ(parsePfm(bytes).at(0, 0), 1.5f);
  bytes.replace(bytes.find("-1"), 2, "+1");
  EXPECT_NE(parsePfm(bytes).at(0, 0), 1.5f);
}

TEST(PfmTest, ThreeChannelsInterleaved) {
  std::string bytes = "PF\n1 2\n-1\n";
  for (float value : {4.0f, 5.0f, 6.0f, 1.0f, 2.0f, 3.0f}) bytes += floatBytes(value, true);
  const PfmImage image = parsePfm(bytes);
  EXPECT_EQ(image.channels, 3);
  EXPECT_EQ(image.at(0, 0, 0), 1.0f);  // top row stored second
  EXPECT_EQ(image.at(0, 0, 2), 3.0f);
  EXPECT_EQ(image.at(0, 1, 1), 5.0f);
}

TEST(PfmTest, RejectsBadHeadersAndShortData) {
  EXPECT_THROW(parsePfm("P5\n1 1\n-1\n\x00\x00\x00\x00"), std::runtime_error);
  EXPECT_THROW(parsePfm("Pf\n0 1\n-1\n"), std::runtime_error);
  EXPECT_THROW(parsePfm("Pf\n1 1\n0\n" + floatBytes(1.0f, true)), std::runtime_error);
  EXPECT_THROW(parsePfm("Pf\n2 1\n-1\n" + floatBytes(1.0f, true)), std::runtime_error);
  EXPECT_THROW(parsePfm("Pf\n2"), std::runtime_error);
}

TEST(MiddleburyCalibrationTest, ParsesTheDataSetsLayout) {
  const MiddleburyCalibration calibration = parseMiddleburyCalibration(kArtCalibration);
  EXPECT_DOUBLE_EQ(calibration.fx, 935.0);
  EXPECT_DOUBLE_EQ(calibration.fy, 935.0);
  EXPECT_DOUBLE_EQ(calibration.cx0, 148.0);
  EXPECT_DOUBLE_EQ(calibration.cy0, 138.0);
  EXPECT_DOUBLE_EQ(calibration.cx1, 198.0);
  EXPECT_DOUBLE_EQ(calibration.doffs, 50.0);
  EXPECT_DOUBLE_EQ(calibration.baseline_m, 0.160);
  EXPECT_EQ(calibration.width, 3);
  EXPECT_EQ(calibration.height, 2);
  EXPECT_EQ(calibration.ndisp, 64);
  EXPECT_DOUBLE_EQ(calibration.vmin, 16.0);
  EXPECT_DOUBLE_EQ(calibration.vmax, 58.0);
  // Stored d = 25 px: z = 935 * 0.16 / (25 + 50) = 1.99466... m.
  EXPECT_NEAR(calibration.depthFromStoredDisparity(25.0), 935.0 * 0.16 / 75.0, 1e-12);
  const StereoCamera camera = calibration.camera();
  EXPECT_DOUBLE_EQ(camera.cx, 148.0);
  EXPECT_DOUBLE_EQ(camera.baseline, 0.16);
}

TEST(MiddleburyCalibrationTest, DoffsDefaultsToThePrincipalPointDifference) {
  const MiddleburyCalibration calibration = parseMiddleburyCalibration(
      "cam0=[100 0 10; 0 100 20; 0 0 1]\ncam1=[100 0 13.5; 0 100 20; 0 0 1]\nbaseline=50\n");
  EXPECT_DOUBLE_EQ(calibration.doffs, 3.5);
  EXPECT_DOUBLE_EQ(calibration.baseline_m, 0.05);
  EXPECT_EQ(calibration.width, 0);
}

TEST(MiddleburyCalibrationTest, RejectsMissingAndMalformedEntries) {
  EXPECT_THROW(parseMiddleburyCalibration("baseline=1"), std::runtime_error);  // no cam0
  EXPECT_THROW(parseMiddleburyCalibration("cam0=[1 0 0; 0 1 0; 0 0 1]"), std::runtime_error);
  EXPECT_THROW(parseMiddleburyCalibration("cam0=[1 0 0; 0 1 0; 0 0]\nbaseline=1"),
               std::runtime_error);
  EXPECT_THROW(parseMiddleburyCalibration("cam0=[1 0 0; 0 1 0; 0 0 1]\nbaseline=abc"),
               std::runtime_error);
  EXPECT_THROW(parseMiddleburyCalibration("cam0=[1 0 0; 0 1 0; 0 0 1]\nbaseline=-3"),
               std::runtime_error);
  EXPECT_THROW(parseMiddleburyCalibration("cam0=[1 0 0; 0 1 0; 0 0 1] baseline"),
               std::runtime_error);
}

TEST(MiddleburyFolderTest, GroundTruthViewAddsDoffsAndMarksUnknownNaN) {
  const TemporaryFolder folder;
  writeFile(folder.path() / "calib.txt", kArtCalibration);
  writeFile(folder.path() / "disp0GT.pfm",
            pfmBytes({{25.0f, kInf, 10.0f}, {0.5f, 30.0f, kInf}}, true, "-1"));
  writeFile(folder.path() / "disp1GT.pfm", pfmBytes({{1.0f}}, true, "-1"));  // right view: no frame
  writeFile(folder.path() / "im0.png", "not read");
  const MiddleburyFolder scene(folder.path().string());
  ASSERT_EQ(scene.size(), 1u);
  EXPECT_EQ(scene.name(0), "disp0GT");
  EXPECT_EQ(scene.leftImagePath(0), (folder.path() / "im0.png").string());
  EXPECT_EQ(scene.rightImagePath(0), "");
  const MiddleburyFrame frame = scene.frame(0);
  ASSERT_EQ(frame.width, 3);
  ASSERT_EQ(frame.height, 2);
  EXPECT_FLOAT_EQ(frame.view().at(0, 0), 75.0f);
  EXPECT_TRUE(std::isnan(frame.view().at(1, 0)));
  EXPECT_FLOAT_EQ(frame.view().at(0, 1), 50.5f);
  EXPECT_TRUE(std::isnan(frame.view().at(2, 1)));
  EXPECT_TRUE(frame.T_world_camera.isApprox(Eigen::Isometry3d::Identity()));

  // Through disparityToPoints, pixel (0, 0) lands at the depth of z = f b / (d + doffs).
  DisparityConversionConfig config;
  const StereoPoints points = disparityToPoints(frame.view(), scene.camera(), config);
  ASSERT_EQ(points.size(), 4u);
  EXPECT_NEAR(points.points[0].z(), 935.0 * 0.16 / 75.0, 1e-5);
  EXPECT_NEAR(points.points[0].x(), (0.0 - 148.0) / 935.0 * (935.0 * 0.16 / 75.0), 1e-5);
}

TEST(MiddleburyFolderTest, SeveralViewsWithPoseFiles) {
  const TemporaryFolder folder;
  writeFile(folder.path() / "calib.txt", kArtCalibration);
  writeFile(folder.path() / "disp0_001.pfm", pfmBytes({{1, 2, 3}, {4, 5, 6}}, false, "1"));
  writeFile(folder.path() / "disp0_000.pfm", pfmBytes({{1, 2, 3}, {4, 5, 6}}, true, "-1"));
  // A quarter turn about z and a translation, camera to world.
  writeFile(folder.path() / "pose0_001.txt", "0 -1 0 1.5\n1 0 0 -2\n0 0 1 0.25\n0 0 0 1\n");
  writeFile(folder.path() / "im0_001.png", "");
  writeFile(folder.path() / "im1_001.png", "");
  const MiddleburyFolder scene(folder.path().string());
  ASSERT_EQ(scene.size(), 2u);
  EXPECT_EQ(scene.name(0), "disp0_000");
  EXPECT_EQ(scene.name(1), "disp0_001");
  EXPECT_EQ(scene.leftImagePath(0), "");
  EXPECT_EQ(scene.rightImagePath(1), (folder.path() / "im1_001.png").string());
  EXPECT_TRUE(scene.frame(0).T_world_camera.isApprox(Eigen::Isometry3d::Identity()));
  const MiddleburyFrame second = scene.frame(1);
  EXPECT_FLOAT_EQ(second.view().at(2, 1), 56.0f);  // big-endian 6 + doffs 50
  const Eigen::Vector3d x_axis = second.T_world_camera * Eigen::Vector3d::UnitX();
  EXPECT_TRUE(x_axis.isApprox(Eigen::Vector3d(1.5, -1.0, 0.25), 1e-12));
}

TEST(MiddleburyFolderTest, RejectsAMapOfAnotherSizeThanCalibTxt) {
  const TemporaryFolder folder;
  writeFile(folder.path() / "calib.txt", kArtCalibration);  // 3 x 2
  writeFile(folder.path() / "disp0.pfm", pfmBytes({{1, 2}, {3, 4}}, true, "-1"));
  const MiddleburyFolder scene(folder.path().string());
  EXPECT_THROW(scene.frame(0), std::runtime_error);
}

TEST(MiddleburyFolderTest, ViewIdsAndSceneDiscovery) {
  EXPECT_EQ(middleburyViewId("disp0GT"), "");
  EXPECT_EQ(middleburyViewId("disp0"), "");
  EXPECT_EQ(middleburyViewId("disp0_003GT"), "_003");
  EXPECT_THROW(middleburyViewId("disp1"), std::invalid_argument);

  const TemporaryFolder folder;
  for (const char* scene : {"b_scene", "a_scene"}) {
    fs::create_directories(folder.path() / scene);
    writeFile(folder.path() / scene / "calib.txt", kArtCalibration);
  }
  fs::create_directories(folder.path() / "not_a_scene");
  const std::vector<std::string> scenes = findMiddleburyScenes(folder.path().string());
  ASSERT_EQ(scenes.size(), 2u);
  EXPECT_EQ(fs::path(scenes[0]).filename(), "a_scene");
  EXPECT_EQ(findMiddleburyScenes(scenes[1]), std::vector<std::string>{scenes[1]});
  EXPECT_THROW(findMiddleburyScenes((folder.path() / "not_a_scene").string()), std::runtime_error);
  EXPECT_THROW(MiddleburyFolder((folder.path() / "a_scene").string()),
               std::runtime_error);  // no pfm
}

}  // namespace
}  // namespace occupancy_fusion
