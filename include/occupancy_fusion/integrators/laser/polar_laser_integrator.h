// Yguel et al. 2006: occupancy grids from several 2D laser scanners. Each scan
// becomes a polar grid of log-ratios (the sensor model,
// laser/laser_sensor_model.h), is changed into cartesian cells by one of four
// methods (laser/polar_to_cartesian.h) and summed into a grid (Eq. 8). Two
// products: the vehicle-frame local grid that fuses every scanner each cycle
// (the paper's V-grid), and accumulation into the shared map's world-frame
// GridLayer2D.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <memory>
#include <vector>

#include "occupancy_fusion/integrators/laser/laser_sensor_model.h"
#include "occupancy_fusion/integrators/laser/polar_to_cartesian.h"
#include "occupancy_fusion/map/grid_layer_2d.h"
#include "occupancy_fusion/sensors/laser_scan.h"

namespace occupancy_fusion {

struct PolarLaserIntegratorConfig {
  LaserSensorModelConfig model;
  PolarToCartesianMethod method = PolarToCartesianMethod::kMipmap;
  int max_samples_per_axis = 16;  // sampling: cap on sqrt(ns) of Eq. 6 near the sensor
  MipmapConfig mipmap;
  std::size_t exact_cache_capacity = 4;  // exact: overlays kept (one per fixed geometry)

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// Not thread-safe (the exact overlay cache is shared state): one instance per
// thread.
class PolarLaserIntegrator {
 public:
  explicit PolarLaserIntegrator(
      const PolarLaserIntegratorConfig& config = PolarLaserIntegratorConfig());  // validates

  const PolarLaserIntegratorConfig& config() const { return config_; }
  const ExactOverlayCache& exactCache() const { return exact_cache_; }

  // Adds the scan's log-ratios into `raster` (cells without information are
  // left alone) through the configured method; `sensor` is the scanner's pose
  // in the raster's frame.
  void integrate(const LaserScan& scan, const Pose2D& sensor, LogOddsRaster* raster);
  // The same for a polar field already built, with an explicit method
  // (benchmarks, tests).
  void project(const PolarField& field, const Pose2D& sensor, PolarToCartesianMethod method,
               LogOddsRaster* raster);

  // World product: adds the scan into `layer` (GridLayer2D::addRaster, clamped
  // there) over the cells its observed beams can reach. `sensor` is the
  // scanner's pose in the layer's frame. With the exact method a moving sensor
  // costs one overlay computation per new pose.
  // `weight` scales the scan's log-ratios: a scan standing for several taken from about its pose.
  void integrateIntoLayer(const LaserScan& scan, const Pose2D& sensor, GridLayer2D* layer,
                          float weight = 1.0f);
  // What integrateIntoLayer adds to a layer of `resolution` (its cells without information NaN):
  // rasters of several scans can be made side by side and added in their order.
  LogOddsRaster rasterOf(const LaserScan& scan, const Pose2D& sensor, double resolution,
                         float weight = 1.0f);

 private:
  PolarLaserIntegratorConfig config_;
  ExactOverlayCache exact_cache_;
  PolarField field_;  // the last scan's Z-grid; its buffers are reused by the next scan
};

// The raster window (cells of `resolution`, aligned with the frame's lattice)
// that holds every cell a field's observed beams reach from `sensor`; all NaN.
LogOddsRaster rasterAround(const PolarField& field, const Pose2D& sensor, double resolution);

// The scan plane of a scanner whose pose in a frame is T_frame_sensor, for 2D
// mapping in that frame's x-y plane. Throws std::invalid_argument if the scan
// plane tilts more than max_tilt (rad) from horizontal. A scanner mounted
// upside down (z axis down) sweeps clockwise in the frame: *upside_down is set
// and the scan must be passed through mirrorScan().
Pose2D planarPose(const Eigen::Isometry3d& T_frame_sensor, double max_tilt, bool* upside_down);
// The same scan seen from a frame whose z axis is flipped: beam angles negated,
// order reversed.
LaserScan mirrorScan(const LaserScan& scan);

struct LocalLaserGridConfig {
  double resolution = 0.05;  // m
  double size_x = 20.0;      // m, along the vehicle's x, centred on the vehicle's origin
  double size_y = 20.0;      // m

  void validate() const;  // throws std::invalid_argument naming the bad field
};

// The V-grid: a vehicle-frame grid rebuilt every cycle from the latest scan of
// every scanner. The scanners are fixed on the vehicle, so with the exact
// method each one's overlay is computed once (the integrator's cache holds one
// per scanner) and every later cycle only applies it.
class LocalLaserGrid {
 public:
  // The integrator's exact_cache_capacity is raised to the number of scanners
  // when needed.
  LocalLaserGrid(const LocalLaserGridConfig& grid, const PolarLaserIntegratorConfig& integrator);

  // Adds a scanner fixed at `sensor_in_vehicle`; returns its id (0, 1, ...).
  int addScanner(const Pose2D& sensor_in_vehicle);
  // The same for a scanner with settings of its own (sensor model, method): it gets its own
  // integrator.
  int addScanner(const Pose2D& sensor_in_vehicle, const PolarLaserIntegratorConfig& integrator);
  // A scanner remounted: later cycles place its scans at `sensor_in_vehicle`.
  void moveScanner(int scanner, const Pose2D& sensor_in_vehicle);
  int scannerCount() const { return static_cast<int>(scanners_.size()); }

  void clear();                                  // every cell unknown (NaN)
  void add(int scanner, const LaserScan& scan);  // sums the scan's log-ratios in
  // One cycle: clear(), then add scans[i] from scanner i (an empty ranges
  // vector skips it).
  const LogOddsRaster& fuse(const std::vector<LaserScan>& scans);
  const LogOddsRaster& grid() const { return grid_; }

 private:
  LocalLaserGridConfig config_;
  PolarLaserIntegratorConfig integrator_config_;
  PolarLaserIntegrator integrator_;
  std::vector<Pose2D> scanners_;
  // Per scanner: its own integrator, or null for the shared one.
  std::vector<std::unique_ptr<PolarLaserIntegrator>> own_integrators_;
  LogOddsRaster grid_;
};

}  // namespace occupancy_fusion
