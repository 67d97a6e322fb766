#include "occupancy_fusion/tools/file_readers.h"

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <stdexcept>

namespace occupancy_fusion {
namespace {

namespace fs = std::filesystem;

const std::string kDepthSuffix = ".depth.png";

// Names ("frame-000000") of the folder's depth images, as SevenScenesFolder looks for them.
std::vector<std::string> depthImageNames(const std::string& folder) {
  const fs::path root(folder);
  const fs::path frames = fs::is_directory(root / "frames") ? root / "frames" : root;
  std::vector<std::string> names;
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(frames, error)) {
    const std::string file = entry.path().filename().string();
    if (file.size() > kDepthSuffix.size() &&
        file.compare(file.size() - kDepthSuffix.size(), kDepthSuffix.size(), kDepthSuffix) == 0) {
      names.push_back(file.substr(0, file.size() - kDepthSuffix.size()));
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

void reportProgress(const std::function<void(std::size_t)>& after_frame, std::size_t* delivered) {
  ++*delivered;
  if (after_frame) after_frame(*delivered);
}

}  // namespace

SevenScenesReader::SevenScenesReader(const std::string& folder) : path_(folder) {
  try {
    folder_ = std::make_unique<SevenScenesFolder>(folder);
  } catch (const std::runtime_error& error) {
    throw std::invalid_argument("depth folder " + folder + ": " + error.what());
  }
  std::vector<std::string> listed;
  for (std::size_t i = 0; i < folder_->size(); ++i) listed.push_back(folder_->name(i));
  for (const std::string& name : depthImageNames(folder)) {
    if (!std::binary_search(listed.begin(), listed.end(), name)) without_pose_.push_back(name);
  }
}

std::string SevenScenesReader::description() const {
  const CameraIntrinsics& camera = folder_->camera();
  std::ostringstream text;
  text << "7-Scenes folder " << path_ << ": " << folder_->size() << " depth images of "
       << camera.width << " x " << camera.height << " px with poses";
  if (!without_pose_.empty()) text << ", " << without_pose_.size() << " without pose";
  return text.str();
}

void SevenScenesReader::read(FrameConsumer* consumer,
                             const std::function<void(std::size_t)>& after_frame) {
  std::size_t delivered = 0;
  for (const std::string& name : without_pose_) {
    FrameHeader header;
    header.kind = "depth";
    header.source = path_ + "/" + name;
    header.frame_id = "camera";
    consumer->onUnreadable(header, name + ".pose.txt is missing");
    reportProgress(after_frame, &delivered);
  }
  for (std::size_t i = 0; i < folder_->size(); ++i) {
    DepthImageFrame frame;
    frame.header.kind = "depth";
    frame.header.source = path_ + "/" + folder_->name(i);
    frame.header.frame_id = "camera";
    frame.header.stamp = static_cast<double>(i);
    try {
      SevenScenesFrame loaded = folder_->frame(i);
      frame.camera = folder_->camera();
      frame.depth = std::move(loaded.depth);
      frame.header.T_map_sensor = loaded.T_world_camera;
    } catch (const std::runtime_error& error) {
      consumer->onUnreadable(frame.header, error.what());
      reportProgress(after_frame, &delivered);
      continue;
    }
    consumer->onDepthImage(frame);
    reportProgress(after_frame, &delivered);
  }
}

MiddleburyReader::MiddleburyReader(const std::string& path) : path_(path) {
  try {
    for (const std::string& scene : findMiddleburyScenes(path)) {
      scenes_.push_back(std::make_unique<MiddleburyFolder>(scene));
    }
  } catch (const std::runtime_error& error) {
    throw std::invalid_argument("disparity folder " + path + ": " + error.what());
  }
}

std::size_t MiddleburyReader::frameCount() const {
  std::size_t frames = 0;
  for (const auto& scene : scenes_) frames += scene->size();
  return frames;
}

std::string MiddleburyReader::description() const {
  std::ostringstream text;
  text << "Middlebury folder " << path_ << ": " << frameCount() << " disparity maps in "
       << scenes_.size() << (scenes_.size() == 1 ? " scene" : " scenes");
  return text.str();
}

void MiddleburyReader::read(FrameConsumer* consumer,
                            const std::function<void(std::size_t)>& after_frame) {
  std::size_t delivered = 0;
  for (const auto& scene : scenes_) {
    for (std::size_t i = 0; i < scene->size(); ++i) {
      DisparityFrame frame;
      frame.header.kind = "disparity";
      frame.header.source = scene->folder() + "/" + scene->name(i) + ".pfm";
      frame.header.frame_id = "camera";
      frame.header.stamp = static_cast<double>(delivered);
      try {
        MiddleburyFrame loaded = scene->frame(i);
        frame.camera = scene->camera();
        frame.width = loaded.width;
        frame.height = loaded.height;
        frame.disparity = std::move(loaded.disparity);
        frame.header.T_map_sensor = loaded.T_world_camera;
      } catch (const std::runtime_error& error) {
        consumer->onUnreadable(frame.header, error.what());
        reportProgress(after_frame, &delivered);
        continue;
      }
      consumer->onDisparityImage(frame);
      reportProgress(after_frame, &delivered);
    }
  }
}

CarmenReader::CarmenReader(const std::string& path, const CarmenReadConfig& config) : path_(path) {
  try {
    scans_ = readCarmenLog(path, config);
  } catch (const std::runtime_error& error) {
    throw std::invalid_argument("CARMEN log " + path + ": " + error.what());
  }
  if (scans_.empty()) throw std::invalid_argument("CARMEN log " + path + " has no FLASER line");
}

std::string CarmenReader::description() const {
  std::ostringstream text;
  text << "CARMEN log " << path_ << ": " << scans_.size() << " FLASER scans of "
       << scans_.front().scan.beamCount() << " beams";
  return text.str();
}

void CarmenReader::read(FrameConsumer* consumer,
                        const std::function<void(std::size_t)>& after_frame) {
  std::size_t delivered = 0;
  for (const CarmenLaserScan& record : scans_) {
    LaserScanFrame frame;
    frame.header.kind = "laser";
    frame.header.source = path_ + ":" + std::to_string(record.line_number);
    frame.header.frame_id = "laser";
    frame.header.stamp = record.ipc_timestamp;
    frame.header.T_map_sensor =
        Eigen::Isometry3d(Eigen::Translation3d(record.x, record.y, 0.0) *
                          Eigen::AngleAxisd(record.theta, Eigen::Vector3d::UnitZ()));
    frame.scan = record.scan;
    consumer->onLaserScan(frame);
    reportProgress(after_frame, &delivered);
  }
}

}  // namespace occupancy_fusion
