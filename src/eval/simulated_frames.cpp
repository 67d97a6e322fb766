#include "occupancy_fusion/eval/simulated_frames.h"

namespace occupancy_fusion {

DisparityFrame disparityFrameOf(const sim::DisparityImage& image, const sim::PinholeCamera& camera,
                                double baseline, const FrameHeader& header) {
  DisparityFrame frame;
  frame.header = header;
  frame.camera.fx = frame.camera.fy = camera.fx;
  frame.camera.cx = camera.cx;
  frame.camera.cy = camera.cy;
  frame.camera.baseline = baseline;
  frame.width = image.width;
  frame.height = image.height;
  frame.disparity = image.disparity;
  return frame;
}

}  // namespace occupancy_fusion
