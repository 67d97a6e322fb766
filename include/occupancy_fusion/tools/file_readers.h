// InputReaders of recordings kept as plain files, whose frames carry their own poses
// (FrameHeader::T_map_sensor, the recording's world frame taken as the map frame): depth folders
// in the 7-Scenes layout, disparity folders in the Middlebury layout, CARMEN laser logs.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "occupancy_fusion/sensors/carmen_log.h"
#include "occupancy_fusion/sensors/middlebury_folder.h"
#include "occupancy_fusion/sensors/seven_scenes_folder.h"
#include "occupancy_fusion/tools/recording.h"

namespace occupancy_fusion {

// Depth frames of a 7-Scenes folder (sensors/seven_scenes_folder.h), kind "depth", frame_id
// "camera", stamp = the frame's position in the folder. A depth image without a pose file, or
// one that cannot be read, reaches onUnreadable.
class SevenScenesReader : public InputReader {
 public:
  // Throws std::invalid_argument when the folder has no intrinsics or no usable frame.
  explicit SevenScenesReader(const std::string& folder);

  std::string description() const override;
  std::size_t frameCount() const override { return folder_->size() + without_pose_.size(); }
  const PoseSource& poses() const override { return no_poses_; }
  void read(FrameConsumer* consumer, const std::function<void(std::size_t)>& after_frame) override;

 private:
  std::string path_;
  std::unique_ptr<SevenScenesFolder> folder_;
  std::vector<std::string> without_pose_;  // depth images whose pose file is missing
  NoPoseSource no_poses_;
};

// Disparity frames of the Middlebury-layout scene folders under a path
// (sensors/middlebury_folder.h: disp0*.pfm with calib.txt and optional pose0*.txt; without a
// pose file the left camera sits at the map's origin), kind "disparity", frame_id "camera".
class MiddleburyReader : public InputReader {
 public:
  // Throws std::invalid_argument when no scene folder is found or a calib.txt is bad.
  explicit MiddleburyReader(const std::string& path);

  std::string description() const override;
  std::size_t frameCount() const override;
  const PoseSource& poses() const override { return no_poses_; }
  void read(FrameConsumer* consumer, const std::function<void(std::size_t)>& after_frame) override;

 private:
  std::string path_;
  std::vector<std::unique_ptr<MiddleburyFolder>> scenes_;
  NoPoseSource no_poses_;
};

// Laser scans of a CARMEN log's FLASER lines (.gz accepted) with their corrected poses, kind
// "laser", frame_id "laser", stamp = the line's ipc timestamp.
class CarmenReader : public InputReader {
 public:
  // Reads the whole log; throws std::invalid_argument when it cannot be read, a FLASER line is
  // malformed (the message names the line) or it has no FLASER line.
  explicit CarmenReader(const std::string& path, const CarmenReadConfig& config = {});

  std::string description() const override;
  std::size_t frameCount() const override { return scans_.size(); }
  const PoseSource& poses() const override { return no_poses_; }
  void read(FrameConsumer* consumer, const std::function<void(std::size_t)>& after_frame) override;

  const std::vector<CarmenLaserScan>& scans() const { return scans_; }

 private:
  std::string path_;
  std::vector<CarmenLaserScan> scans_;
  NoPoseSource no_poses_;
};

}  // namespace occupancy_fusion
