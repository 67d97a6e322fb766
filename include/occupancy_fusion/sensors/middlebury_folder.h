// Reader of rectified stereo scenes in the Middlebury 2014 layout (MiddEval3):
//   <folder>/calib.txt              cam0/cam1 K matrices, doffs (px), baseline (mm), width, ...
//   <folder>/disp0<id>.pfm          disparity of the left image (cam0), px; inf = unknown
//   <folder>/im0<id>.png, im1<id>.png   the left and right rectified images (optional)
//   <folder>/pose0<id>.txt          4 x 4 row-major camera-to-world transform of the left
//                                   camera's optical frame, metres (optional: identity)
// A folder holds one view (Middlebury's own: disp0.pfm or MiddEval3's ground truth disp0GT.pfm,
// with im0.png, im1.png) or several of one camera (disp0_000.pfm, disp0_001.pfm, ... with
// pose0_000.txt, im0_000.png, ...). <id> is the part of the name after "disp0" with a trailing
// "GT" (MiddEval3's ground-truth marker) removed: disp0GT.pfm pairs with im0.png and pose0.txt.
// Middlebury's disp1*.pfm (disparity of the right image) are not frames.
//
// Disparity convention. Middlebury stores d = x_left - x_right in each image's own pixel
// coordinates; the two principal points differ by doffs = cx1 - cx0, so depth is
// z = f * b / (d + doffs). The frames returned here hold d + doffs (the ROS
// stereo_msgs/DisparityImage convention, what stereo_image_proc publishes), so that StereoCamera
// and disparityToPoints() (z = f * b / d) apply unchanged. Unknown pixels become NaN.
// ROS-free, for the offline mapper and the benchmark.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

#include "occupancy_fusion/sensors/disparity_image.h"

namespace occupancy_fusion {

// ---------------------------------------------------------------------------------------------
// PFM (portable float map): the header "Pf" (1 channel) or "PF" (3 channels), width, height and
// a scale, separated by white space, then one white-space byte and width * height * channels
// float32 values. The scale's sign gives the byte order (negative: little-endian, positive:
// big-endian; its magnitude carries no meaning here). Rows are stored bottom to top.

struct PfmImage {
  int width = 0;
  int height = 0;
  int channels = 1;
  std::vector<float> values;  // row-major, rows top to bottom, channels interleaved

  float at(int u, int v, int channel = 0) const {
    return values[(static_cast<std::size_t>(v) * width + u) * channels + channel];
  }
};

// Parses the bytes of a PFM file. Throws std::runtime_error on a bad header or short data.
PfmImage parsePfm(const std::string& bytes);
PfmImage readPfm(const std::string& path);  // throws std::runtime_error naming the file

// ---------------------------------------------------------------------------------------------
// calib.txt: "key=value" entries separated by white space or new lines, the matrices as
// "[ a b c ; d e f ; g h i ]".

struct MiddleburyCalibration {
  double fx = 0.0;          // px, cam0
  double fy = 0.0;          // px, cam0
  double cx0 = 0.0;         // px, principal point of cam0 (left)
  double cy0 = 0.0;         // px
  double cx1 = 0.0;         // px, principal point of cam1 (right)
  double doffs = 0.0;       // px, cx1 - cx0: added to a stored disparity for depth
  double baseline_m = 0.0;  // m (the file gives millimetres)
  int width = 0;            // px; 0 where the file has no width
  int height = 0;           // px; 0 where the file has no height
  int ndisp = 0;            // px, the disparity search range (0 where absent)
  double vmin = 0.0;        // px, smallest disparity that occurs (0 where absent)
  double vmax = 0.0;        // px, largest disparity that occurs (0 where absent)

  // The left camera for disparities in the d + doffs convention: fx, fy, cx0, cy0, baseline_m.
  StereoCamera camera() const;
  // z = f * b / (d + doffs) for a stored (Middlebury) disparity d.
  double depthFromStoredDisparity(double stored_disparity_px) const {
    return fx * baseline_m / (stored_disparity_px + doffs);
  }
};

// Throws std::runtime_error naming the missing or malformed key (cam0, baseline are required;
// doffs defaults to cx1 - cx0 where cam1 is given, else 0).
MiddleburyCalibration parseMiddleburyCalibration(const std::string& text);
MiddleburyCalibration readMiddleburyCalibration(const std::string& path);

// ---------------------------------------------------------------------------------------------
// Scene folders.

struct MiddleburyFrame {
  std::string name;  // the disparity file's stem, "disp0GT"
  int width = 0;
  int height = 0;
  std::vector<float> disparity;  // px, d + doffs (z = f * b / value), row-major, NaN = unknown
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // left optical frame

  DisparityImageView view() const { return {width, height, disparity.data(), 0}; }
};

class MiddleburyFolder {
 public:
  // Reads calib.txt and lists the frames (disp0*.pfm) in the order of their names. Throws
  // std::runtime_error naming what is missing or bad.
  explicit MiddleburyFolder(const std::string& folder);

  const std::string& folder() const { return folder_; }
  const MiddleburyCalibration& calibration() const { return calibration_; }
  StereoCamera camera() const { return calibration_.camera(); }
  std::size_t size() const { return names_.size(); }
  const std::string& name(std::size_t index) const { return names_.at(index); }
  // Loads one frame: disparity shifted by doffs, its size checked against calib.txt's, and its
  // pose from pose0<id>.txt where that exists (rotation re-orthonormalised), else identity.
  MiddleburyFrame frame(std::size_t index) const;
  // im0<id>.png / im1<id>.png of a frame; empty where the file does not exist.
  std::string leftImagePath(std::size_t index) const;
  std::string rightImagePath(std::size_t index) const;

 private:
  std::string siblingPath(std::size_t index, const std::string& prefix,
                          const std::string& extension) const;

  std::string folder_;
  MiddleburyCalibration calibration_;
  std::vector<std::string> names_;  // stems "disp0GT", "disp0_000", ...
};

// The view id of a frame's stem: "disp0GT" -> "", "disp0_003" -> "_003", "disp0_003GT" -> "_003".
std::string middleburyViewId(const std::string& disparity_stem);

// Scene folders under path: path itself where it holds a calib.txt, else its sub-folders that
// do, in the order of their names. Throws std::runtime_error when there is none.
std::vector<std::string> findMiddleburyScenes(const std::string& path);

}  // namespace occupancy_fusion
