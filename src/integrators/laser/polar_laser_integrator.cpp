#include "occupancy_fusion/integrators/laser/polar_laser_integrator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace occupancy_fusion {

void PolarLaserIntegratorConfig::validate() const {
  model.validate();
  if (max_samples_per_axis < 1) {
    throw std::invalid_argument("PolarLaserIntegratorConfig.max_samples_per_axis must be >= 1");
  }
  mipmap.validate();
  if (exact_cache_capacity < 1) {
    throw std::invalid_argument("PolarLaserIntegratorConfig.exact_cache_capacity must be >= 1");
  }
}

PolarLaserIntegrator::PolarLaserIntegrator(const PolarLaserIntegratorConfig& config)
    : config_((config.validate(), config)), exact_cache_(config.exact_cache_capacity) {}

void PolarLaserIntegrator::integrate(const LaserScan& scan, const Pose2D& sensor,
                                     LogOddsRaster* raster) {
  buildPolarField(scan, config_.model, &field_);
  project(field_, sensor, config_.method, raster);
}

void PolarLaserIntegrator::project(const PolarField& field, const Pose2D& sensor,
                                   PolarToCartesianMethod method, LogOddsRaster* raster) {
  if (raster->data.size() != static_cast<std::size_t>(raster->width) * raster->height) {
    throw std::invalid_argument("PolarLaserIntegrator: raster data does not match its size");
  }
  switch (method) {
    case PolarToCartesianMethod::kExact:
      exact_cache_.get(OverlayGeometry::of(field, sensor, *raster)).apply(field, raster);
      return;
    case PolarToCartesianMethod::kSampling:
      projectSampling(field, sensor, config_.max_samples_per_axis, raster);
      return;
    case PolarToCartesianMethod::kMipmap:
      projectMipmap(field, sensor, config_.mipmap, raster);
      return;
    case PolarToCartesianMethod::kLines:
      projectLines(field, sensor, raster);
      return;
  }
}

LogOddsRaster rasterAround(const PolarField& field, const Pose2D& sensor, double resolution) {
  double min_x = sensor.x;
  double max_x = sensor.x;
  double min_y = sensor.y;
  double max_y = sensor.y;
  for (int b = 0; b < field.beams; ++b) {
    const int observed = field.observed_cells[static_cast<std::size_t>(b)];
    if (observed == 0) continue;
    // The chord ends of the beam's far edge, pushed out by one range cell to
    // cover the arc.
    const double reach = (observed + 1) * field.range_resolution;
    for (double side : {-0.5, 0.5}) {
      const double angle = sensor.yaw + field.angle(b) + side * field.angle_increment;
      const double x = sensor.x + reach * std::cos(angle);
      const double y = sensor.y + reach * std::sin(angle);
      min_x = std::min(min_x, x);
      max_x = std::max(max_x, x);
      min_y = std::min(min_y, y);
      max_y = std::max(max_y, y);
    }
  }
  LogOddsRaster raster;
  raster.resolution = resolution;
  raster.origin_cell = CellIndex(static_cast<int>(std::floor(min_x / resolution)) - 1,
                                 static_cast<int>(std::floor(min_y / resolution)) - 1);
  raster.width = static_cast<int>(std::floor(max_x / resolution)) + 2 - raster.origin_cell.x();
  raster.height = static_cast<int>(std::floor(max_y / resolution)) + 2 - raster.origin_cell.y();
  raster.data.assign(static_cast<std::size_t>(raster.width) * raster.height,
                     std::numeric_limits<float>::quiet_NaN());
  return raster;
}

void PolarLaserIntegrator::integrateIntoLayer(const LaserScan& scan, const Pose2D& sensor,
                                              GridLayer2D* layer, float weight) {
  const LogOddsRaster raster = rasterOf(scan, sensor, layer->resolution(), weight);
  layer->addRaster(raster.origin_cell, raster.width, raster.height, raster.data.data());
}

LogOddsRaster PolarLaserIntegrator::rasterOf(const LaserScan& scan, const Pose2D& sensor,
                                             double resolution, float weight) {
  buildPolarField(scan, config_.model, &field_);
  LogOddsRaster raster = rasterAround(field_, sensor, resolution);
  project(field_, sensor, config_.method, &raster);
  if (weight != 1.0f) {
    for (float& value : raster.data) value *= weight;  // NaN (no information) stays NaN
  }
  return raster;
}

Pose2D planarPose(const Eigen::Isometry3d& T_frame_sensor, double max_tilt, bool* upside_down) {
  const Eigen::Matrix3d& R = T_frame_sensor.linear();
  const double cos_tilt = std::abs(R(2, 2));  // angle between the sensor's z and the frame's
  if (cos_tilt < std::cos(max_tilt)) {
    throw std::invalid_argument("planarPose: the scan plane tilts " +
                                std::to_string(std::acos(std::min(1.0, cos_tilt))) +
                                " rad from horizontal, more than max_tilt");
  }
  *upside_down = R(2, 2) < 0.0;
  Pose2D pose;
  pose.x = T_frame_sensor.translation().x();
  pose.y = T_frame_sensor.translation().y();
  pose.yaw = std::atan2(R(1, 0), R(0, 0));  // heading of the sensor's x axis
  return pose;
}

LaserScan mirrorScan(const LaserScan& scan) {
  LaserScan out = scan;
  out.angle_min = -(scan.angle_min + (scan.beamCount() - 1) * scan.angle_increment);
  std::reverse(out.ranges.begin(), out.ranges.end());
  return out;
}

void LocalLaserGridConfig::validate() const {
  if (!(std::isfinite(resolution) && resolution > 0.0)) {
    throw std::invalid_argument("LocalLaserGridConfig.resolution must be finite and > 0");
  }
  if (!(std::isfinite(size_x) && size_x >= resolution)) {
    throw std::invalid_argument("LocalLaserGridConfig.size_x must be finite and >= resolution");
  }
  if (!(std::isfinite(size_y) && size_y >= resolution)) {
    throw std::invalid_argument("LocalLaserGridConfig.size_y must be finite and >= resolution");
  }
}

LocalLaserGrid::LocalLaserGrid(const LocalLaserGridConfig& grid,
                               const PolarLaserIntegratorConfig& integrator)
    : config_((grid.validate(), grid)), integrator_config_(integrator), integrator_(integrator) {
  const int width = static_cast<int>(std::round(config_.size_x / config_.resolution));
  const int height = static_cast<int>(std::round(config_.size_y / config_.resolution));
  grid_.resolution = config_.resolution;
  grid_.origin_cell = CellIndex(-width / 2, -height / 2);  // the vehicle's origin in the middle
  grid_.width = width;
  grid_.height = height;
  clear();
}

int LocalLaserGrid::addScanner(const Pose2D& sensor_in_vehicle,
                               const PolarLaserIntegratorConfig& integrator) {
  scanners_.push_back(sensor_in_vehicle);
  own_integrators_.push_back(std::make_unique<PolarLaserIntegrator>(integrator));
  return static_cast<int>(scanners_.size()) - 1;
}

void LocalLaserGrid::moveScanner(int scanner, const Pose2D& sensor_in_vehicle) {
  if (scanner < 0 || scanner >= scannerCount()) {
    throw std::invalid_argument("LocalLaserGrid::moveScanner: no scanner " +
                                std::to_string(scanner));
  }
  scanners_[static_cast<std::size_t>(scanner)] = sensor_in_vehicle;
}

int LocalLaserGrid::addScanner(const Pose2D& sensor_in_vehicle) {
  scanners_.push_back(sensor_in_vehicle);
  own_integrators_.push_back(nullptr);
  if (integrator_config_.exact_cache_capacity < scanners_.size()) {
    integrator_config_.exact_cache_capacity = scanners_.size();
    integrator_ = PolarLaserIntegrator(integrator_config_);
  }
  return static_cast<int>(scanners_.size()) - 1;
}

void LocalLaserGrid::clear() {
  grid_.data.assign(static_cast<std::size_t>(grid_.width) * grid_.height,
                    std::numeric_limits<float>::quiet_NaN());
}

void LocalLaserGrid::add(int scanner, const LaserScan& scan) {
  if (scanner < 0 || scanner >= scannerCount()) {
    throw std::invalid_argument("LocalLaserGrid::add: no scanner " + std::to_string(scanner));
  }
  const auto id = static_cast<std::size_t>(scanner);
  PolarLaserIntegrator& integrator = own_integrators_[id] ? *own_integrators_[id] : integrator_;
  integrator.integrate(scan, scanners_[id], &grid_);
}

const LogOddsRaster& LocalLaserGrid::fuse(const std::vector<LaserScan>& scans) {
  if (scans.size() != scanners_.size()) {
    throw std::invalid_argument("LocalLaserGrid::fuse: " + std::to_string(scans.size()) +
                                " scans for " + std::to_string(scanners_.size()) + " scanners");
  }
  clear();
  for (int i = 0; i < scannerCount(); ++i) {
    if (!scans[static_cast<std::size_t>(i)].ranges.empty())
      add(i, scans[static_cast<std::size_t>(i)]);
  }
  return grid_;
}

}  // namespace occupancy_fusion
