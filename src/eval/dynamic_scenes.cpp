#include "occupancy_fusion/eval/dynamic_scenes.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "occupancy_fusion/eval/simulated_frames.h"
#include "occupancy_fusion/map/spatial_key.h"
#include "occupancy_fusion/mapping/mapping_session.h"
#include "occupancy_fusion/sim/depth_camera.h"
#include "occupancy_fusion/sim/laser_scanner.h"
#include "occupancy_fusion/sim/scenes.h"
#include "occupancy_fusion/sim/stereo_camera.h"
#include "occupancy_fusion/sim/trajectory.h"

namespace occupancy_fusion {
namespace {

constexpr double kStamp0 = 100.0;   // s, frame 0
constexpr double kMaxRange = 8.0;   // m, the cameras' rendered depth
constexpr double kBaseline = 0.12;  // m
const sim::PinholeCamera kCamera{320, 240, 250.0, 250.0, 159.5, 119.5};
constexpr double kPersonSpeed = 1.0;  // m/s

// A camera 0.8 m up looking along the corridor, 0.2 rad down; a laser 0.3 m up, level.
Eigen::Isometry3d cameraPose(double x) {
  return Eigen::Translation3d(x, 0.0, 0.8) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()) *
         Eigen::Isometry3d(sim::opticalFrameInBody());
}
Eigen::Isometry3d laserPose(double x) {
  return Eigen::Isometry3d(Eigen::Translation3d(x, 0.0, 0.3));
}

Eigen::AlignedBox3d box(double x0, double y0, double z0, double x1, double y1, double z1) {
  return Eigen::AlignedBox3d(Eigen::Vector3d(x0, y0, z0), Eigen::Vector3d(x1, y1, z1));
}

// Where the object is at frame k (nullopt: gone), and the frame it is gone from.
class ObjectMotion {
 public:
  explicit ObjectMotion(const DynamicSceneCase& setup) : setup_(setup) {}

  int changeFrame() const {
    if (setup_.event != DynamicEvent::kPerson) return setup_.frames_before;
    // Across the corridor's 2.4 m, from wall to wall.
    return static_cast<int>(std::ceil(2.4 / kPersonSpeed * setup_.rate()));
  }
  int frames() const { return changeFrame() + setup_.frames_after; }
  // m along the corridor: 2.5 m before the box and the door's doorway 6 m ahead; the person
  // crosses 4 m ahead, in front of the end wall (within the cameras' range: rays that pass
  // where it was must end on something to clear it).
  double sensorStart() const { return setup_.event == DynamicEvent::kPerson ? 13.0 : 1.0; }

  std::optional<Eigen::AlignedBox3d> at(int k) const {
    // The chair: moved across the corridor at the change and left there.
    if (setup_.event == DynamicEvent::kChair) {
      return k < changeFrame() ? box(3.6, -0.9, 0.0, 4.1, -0.4, 0.9)
                               : box(3.6, 0.4, 0.0, 4.1, 0.9, 0.9);
    }
    if (k >= changeFrame()) return std::nullopt;
    switch (setup_.event) {
      case DynamicEvent::kRemovedBox:
        return box(3.5, -0.5, 0.0, 4.3, 0.5, 0.5);
      case DynamicEvent::kPerson: {
        const double y = -1.2 + kPersonSpeed * k / setup_.rate();
        return box(16.8, y, 0.0, 17.2, y + 0.3, 1.7);
      }
      case DynamicEvent::kDoor:
        return box(7.0, 1.2, 0.0, 8.0, 1.4, 2.0);
      case DynamicEvent::kChair:
        break;
    }
    return std::nullopt;
  }

  // Every place the object held, one box each (the person's path: one per frame).
  std::vector<Eigen::AlignedBox3d> places() const {
    std::vector<Eigen::AlignedBox3d> boxes;
    for (int k = 0; k < changeFrame(); ++k) {
      if (setup_.event != DynamicEvent::kPerson && k > 0) break;
      boxes.push_back(*at(k));
    }
    return boxes;
  }

 private:
  const DynamicSceneCase& setup_;
};

// The corridor, with a room's wall behind its doorway (x in [7, 8]) for the door to open onto.
sim::Scene staticScene() {
  sim::Scene scene = sim::makeCorridorScene();
  scene.add(sim::Box::axisAligned(Eigen::Vector3d(6.0, 3.0, 0.0), Eigen::Vector3d(9.0, 3.2, 2.5)));
  return scene;
}

sim::Scene sceneAt(const sim::Scene& corridor, const ObjectMotion& motion, int k) {
  sim::Scene scene = corridor;
  if (const auto object = motion.at(k)) {
    scene.add(sim::Box::axisAligned(object->min(), object->max()));
  }
  return scene;
}

bool isLaser(DynamicMapper mapper) { return mapper == DynamicMapper::kLaser; }

MappingSessionConfig sessionConfig(const DynamicSceneCase& setup) {
  MappingSessionConfig config = setup.mapping;
  config.map.resolution = setup.resolution;
  if (setup.mapper == DynamicMapper::kStereoTableI) {
    const DisparityConversionConfig disparity = config.stereo.disparity;
    config.stereo = visibilityStereoConfigFor(StereoParameterSet::kTableI);
    config.stereo.disparity = disparity;
  } else if (setup.mapper == DynamicMapper::kStereoOctomap) {
    config.stereo.method = StereoIntegrationMethod::kOctomap;
  }
  return config;
}

FrameHeader headerFor(const char* kind, double stamp, const Eigen::Isometry3d& T_map_sensor) {
  FrameHeader header;
  header.kind = kind;
  header.source = std::string("/") + kind;
  header.frame_id = kind;
  header.stamp = stamp;
  header.T_map_sensor = T_map_sensor;
  return header;
}

// Frame k of the case's sensor into the session.
void mapFrame(const DynamicSceneCase& setup, const sim::Scene& scene, int k, double x,
              MappingSession* session) {
  const double stamp = kStamp0 + k / setup.rate();
  switch (setup.mapper) {
    case DynamicMapper::kDepth: {
      DepthImageFrame frame;
      frame.header = headerFor("depth", stamp, cameraPose(x));
      frame.camera = kCamera;
      frame.depth = sim::renderDepth(scene, kCamera, cameraPose(x), kMaxRange).depth;
      session->integrate(frame);
      return;
    }
    case DynamicMapper::kPointCloud: {
      PointCloudFrame frame;
      frame.header = headerFor("point_cloud", stamp, cameraPose(x));
      for (const Eigen::Vector3d& point :
           sim::renderPointCloud(scene, kCamera, cameraPose(x), kMaxRange)) {
        frame.points.push_back(point.cast<float>());
      }
      session->integrate(frame);
      return;
    }
    case DynamicMapper::kLaser: {
      LaserScanFrame frame;
      frame.header = headerFor("laser", stamp, laserPose(x));
      frame.scan = toLaserScan(sim::renderScan(scene, sim::LaserScanner(), laserPose(x), k));
      session->integrate(frame);
      return;
    }
    default: {
      sim::DisparityNoise noise;
      noise.sigma_px = setup.disparity_noise_px;
      const sim::DisparityImage image =
          sim::renderDisparity(scene, kCamera, kBaseline, cameraPose(x), kMaxRange, noise, k);
      session->integrate(disparityFrameOf(image, kCamera, kBaseline,
                                          headerFor("disparity", stamp, cameraPose(x))));
      return;
    }
  }
}

// Whether `seen` holds for a ray of the sensor at `eye` towards any of a voxel's centre and
// corners (drawn in by a tenth of a voxel, so that one touching a surface counts as seen from the
// side it faces): seen(unit direction, distance to the point). Cells of the laser layer: their
// centre and corners in the scan plane.
template <class Seen>
bool anyPart(const Eigen::Vector3d& eye, const Eigen::Vector3d& centre, double resolution,
             bool planar, Seen seen) {
  const double reach = 0.4 * resolution;
  for (int corner = -1; corner < (planar ? 4 : 8); ++corner) {
    Eigen::Vector3d point = centre;
    if (corner >= 0) {
      point += reach * Eigen::Vector3d(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1,
                                       planar ? 0 : (corner & 4 ? 1 : -1));
    }
    const Eigen::Vector3d offset = point - eye;
    const double distance = offset.norm();
    if (seen(Eigen::Vector3d(offset / distance), distance)) return true;
  }
  return false;
}

// Whether the sensor sees any part of the voxel past the static scene (the objects left out):
// what lies hidden behind the static scene cannot be seen free by any sensor.
bool anyPartInSight(const sim::Scene& scene, const Eigen::Vector3d& eye,
                    const Eigen::Vector3d& centre, double resolution, bool planar) {
  return anyPart(eye, centre, resolution, planar,
                 [&](const Eigen::Vector3d& direction, double distance) {
                   return !scene.castRay(eye, direction, distance);
                 });
}

// Whether a ray of the sensor through any part of the voxel returns from the static scene farther
// behind it than `behind(range of the return)`, within `range`: what lets a measurement say that
// the voxel is free now. A ray without a return, or one ending within the sensor's own range
// error of the voxel, says nothing.
template <class Behind>
bool anyPartSeenThrough(const sim::Scene& scene, const Eigen::Vector3d& eye,
                        const Eigen::Vector3d& centre, double resolution, bool planar, double range,
                        Behind behind) {
  return anyPart(eye, centre, resolution, planar,
                 [&](const Eigen::Vector3d& direction, double distance) {
                   const std::optional<double> hit = scene.castRay(eye, direction, range);
                   return hit && *hit - distance > behind(*hit);
                 });
}

// How far behind a voxel a return must lie to pass it clearly: a voxel diagonal and three of
// the sensor's range sigmas at the return's range (depth images: Eq. 7's sigma; stereo: the
// disparity noise as range, z^2 sigma_d / (f b); the laser: its range sigma; point clouds: none
// beyond the voxel, as OctoMap's update).
double passMargin(const DynamicSceneCase& setup, double range) {
  double sigma = 0.0;
  switch (setup.mapper) {
    case DynamicMapper::kDepth:
      sigma = setup.mapping.depth.sigma + setup.mapping.depth.sigma_quadratic * range * range;
      break;
    case DynamicMapper::kStereoDefault:
    case DynamicMapper::kStereoTableI:
    case DynamicMapper::kStereoOctomap:
      sigma = range * range * setup.disparity_noise_px / (kCamera.fx * kBaseline);
      break;
    case DynamicMapper::kLaser:
      sigma = setup.mapping.laser.model.range_sigma;
      break;
    case DynamicMapper::kPointCloud:
      break;
  }
  return std::sqrt(3.0) * setup.resolution + 3.0 * sigma;
}

// The map's occupied voxels (the laser layer's cells, at z = 0) in the places the object held,
// grown by a voxel, whose centre lies farther than a voxel diagonal from the corridor's surfaces:
// what the object left in the map.
class ObjectRegion {
 public:
  ObjectRegion(const sim::Scene& corridor, const ObjectMotion& motion, double resolution,
               bool planar)
      : corridor_(corridor), resolution_(resolution), planar_(planar) {
    for (Eigen::AlignedBox3d place : motion.places()) {
      place.min().array() -= resolution;
      place.max().array() += resolution;
      places_.push_back(place);
    }
  }

  // Those the sensor sees now (in_view of their centre): what leaves the view cannot be cleared;
  // and of those, the ones seen_through.
  template <class InView, class SeenThrough>
  std::pair<std::size_t, std::size_t> count(const MappingSession& session, InView in_view,
                                            SeenThrough seen_through) const {
    std::size_t count = 0, through = 0;
    const auto add = [&](const Eigen::Vector3d& point) {
      if (!left(point) || !in_view(point)) return;
      ++count;
      through += seen_through(point) ? 1 : 0;
    };
    if (planar_) {
      session.laserLayer().forEachKnownCell([&](const CellIndex& cell, float value) {
        if (session.laserLayer().classify(value) != Occupancy::kOccupied) return;
        const Eigen::Vector2d centre = session.laserLayer().centerOf(cell);
        add(Eigen::Vector3d(centre.x(), centre.y(), 0.3));
      });
      return {count, through};
    }
    session.map().forEachOccupiedVoxel([&](const VoxelIndex& voxel, float) {
      add((voxel.cast<double>().array() + 0.5).matrix() * resolution_);
    });
    return {count, through};
  }

 private:
  bool left(const Eigen::Vector3d& centre) const {
    const bool inside =
        std::any_of(places_.begin(), places_.end(), [&](const Eigen::AlignedBox3d& place) {
          if (!planar_) return place.contains(centre);
          return centre.x() >= place.min().x() && centre.x() <= place.max().x() &&
                 centre.y() >= place.min().y() && centre.y() <= place.max().y();
        });
    if (!inside) return false;
    auto cached =
        far_.find(packKey(Eigen::Vector3i((centre / resolution_).array().floor().cast<int>())));
    if (cached != far_.end()) return cached->second;
    const double reach = (planar_ ? std::sqrt(2.0) : std::sqrt(3.0)) * resolution_;
    const bool far = !corridor_.isOccupied(centre) && corridor_.distanceToSurface(centre) > reach;
    far_.emplace(packKey(Eigen::Vector3i((centre / resolution_).array().floor().cast<int>())), far);
    return far;
  }

  const sim::Scene& corridor_;
  double resolution_;
  bool planar_;
  std::vector<Eigen::AlignedBox3d> places_;
  mutable SpatialKeyMap<bool> far_;
};

// Of the corridor's surface samples in front of the sensor (within 6 m, 0.1-2 m high; the laser:
// its plane), those with an occupied voxel (cell) within one voxel.
double staticCoverage(const sim::Scene& corridor, const MappingSession& session, double x,
                      double resolution, bool planar) {
  std::size_t samples = 0, covered = 0;
  for (const Eigen::Vector3d& sample : corridor.sampleSurface(resolution)) {
    if (sample.x() < x + 1.0 || sample.x() > x + 6.0) continue;
    if (planar ? std::abs(sample.z() - 0.3) > 0.5 * resolution
               : (sample.z() < 0.1 || sample.z() > 2.0)) {
      continue;
    }
    ++samples;
    bool found = false;
    for (int d = 0; d < 27 && !found; ++d) {
      const Eigen::Vector3d near =
          sample + resolution * Eigen::Vector3d(d % 3 - 1, (d / 3) % 3 - 1, d / 9 - 1);
      found = planar ? session.laserLayer().occupancyAt(near.head<2>()) == Occupancy::kOccupied
                     : session.map().occupancyAt(near) == Occupancy::kOccupied;
    }
    covered += found ? 1 : 0;
  }
  return samples == 0 ? 0.0 : static_cast<double>(covered) / samples;
}

// Frames without the object after which `ghost` stays below 5 % of `object_voxels` (ghost[i] is
// after i + 1 frames); -1: not within them.
int framesBelow(const std::vector<std::size_t>& ghost, std::size_t object_voxels) {
  const double bound = 0.05 * static_cast<double>(object_voxels);
  int frames = -1;
  for (int i = static_cast<int>(ghost.size()) - 1; i >= 0; --i) {
    if (static_cast<double>(ghost[static_cast<std::size_t>(i)]) >= bound) break;
    frames = i + 1;
  }
  return frames;
}

}  // namespace

std::string toString(DynamicEvent event) {
  switch (event) {
    case DynamicEvent::kRemovedBox:
      return "removed_box";
    case DynamicEvent::kPerson:
      return "person";
    case DynamicEvent::kDoor:
      return "door";
    case DynamicEvent::kChair:
      return "chair";
  }
  return "?";
}

std::string toString(DynamicMapper mapper) {
  switch (mapper) {
    case DynamicMapper::kDepth:
      return "depth";
    case DynamicMapper::kStereoDefault:
      return "stereo";
    case DynamicMapper::kStereoTableI:
      return "stereo_table_i";
    case DynamicMapper::kStereoOctomap:
      return "stereo_octomap";
    case DynamicMapper::kPointCloud:
      return "point_cloud";
    case DynamicMapper::kLaser:
      return "laser";
  }
  return "?";
}

DynamicEvent dynamicEventFromString(const std::string& name) {
  for (DynamicEvent event : {DynamicEvent::kRemovedBox, DynamicEvent::kPerson, DynamicEvent::kDoor,
                             DynamicEvent::kChair}) {
    if (toString(event) == name) return event;
  }
  throw std::invalid_argument("unknown event '" + name + "' (removed_box, person, door, chair)");
}

DynamicMapper dynamicMapperFromString(const std::string& name) {
  for (DynamicMapper mapper :
       {DynamicMapper::kDepth, DynamicMapper::kStereoDefault, DynamicMapper::kStereoTableI,
        DynamicMapper::kStereoOctomap, DynamicMapper::kPointCloud, DynamicMapper::kLaser}) {
    if (toString(mapper) == name) return mapper;
  }
  throw std::invalid_argument(
      "unknown mapper '" + name +
      "' (depth, stereo, stereo_table_i, stereo_octomap, point_cloud, laser)");
}

double DynamicSceneCase::rate() const {
  if (rate_hz > 0.0) return rate_hz;
  return mapper == DynamicMapper::kLaser ? 10.0 : 15.0;
}

void DynamicSceneCase::validate() const {
  if (!(resolution > 0.0) || !(speed >= 0.0) || speed > 2.0 || !(rate_hz >= 0.0)) {
    throw std::invalid_argument("dynamic scene: resolution > 0, speed in [0, 2] m/s, rate >= 0");
  }
  if (frames_before < 1 || frames_after < 1) {
    throw std::invalid_argument("dynamic scene: frames_before and frames_after must be >= 1");
  }
  if (!(disparity_noise_px >= 0.0)) throw std::invalid_argument("disparity noise must be >= 0");
}

DynamicSceneResult evaluateDynamicScene(const DynamicSceneCase& setup) {
  setup.validate();
  DynamicSceneResult result;
  result.setup = setup;
  const sim::Scene corridor = staticScene();
  const ObjectMotion motion(setup);
  result.change_frame = motion.changeFrame();
  MappingSession session(sessionConfig(setup), nullptr, nullptr);
  const ObjectRegion region(corridor, motion, setup.resolution, isLaser(setup.mapper));
  double seconds = 0.0, x = motion.sensorStart();
  for (int k = 0; k < motion.frames(); ++k) {
    x = motion.sensorStart() + setup.speed * k / setup.rate();
    const sim::Scene scene = sceneAt(corridor, motion, k);
    const auto start = std::chrono::steady_clock::now();
    mapFrame(setup, scene, k, x, &session);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const bool laser = isLaser(setup.mapper);
    const Eigen::Isometry3d sensor = laser ? laserPose(x) : cameraPose(x);
    const Eigen::Isometry3d sensor_from_world = sensor.inverse();
    const auto in_view = [&](const Eigen::Vector3d& point) {
      const Eigen::Vector3d local = sensor_from_world * point;
      if (laser) {
        if (!(local.x() > 0.0 && local.head<2>().norm() < sim::LaserScanner().range_max)) {
          return false;
        }
      } else {
        if (!(local.z() > 0.1 && local.z() < kMaxRange)) return false;
        const double u = kCamera.fx * local.x() / local.z() + kCamera.cx;
        const double v = kCamera.fy * local.y() / local.z() + kCamera.cy;
        if (!(u >= 0.0 && u < kCamera.width && v >= 0.0 && v < kCamera.height)) return false;
      }
      return anyPartInSight(corridor, sensor.translation(), point, setup.resolution, laser);
    };
    const double range = laser ? sim::LaserScanner().range_max : kMaxRange;
    const auto seen_through = [&](const Eigen::Vector3d& point) {
      return anyPartSeenThrough(corridor, sensor.translation(), point, setup.resolution, laser,
                                range, [&](double hit) { return passMargin(setup, hit); });
    };
    const auto [left, through] = region.count(session, in_view, seen_through);
    if (k < result.change_frame) {
      result.object_voxels = std::max(result.object_voxels, left);
    } else {
      result.ghost.push_back(left);
      result.ghost_seen_through.push_back(through);
    }
  }
  result.frames_to_clear = framesBelow(result.ghost, result.object_voxels);
  result.frames_to_clear_seen_through =
      framesBelow(result.ghost_seen_through, result.object_voxels);
  result.static_coverage =
      staticCoverage(corridor, session, x, setup.resolution, isLaser(setup.mapper));
  result.ms_per_frame = 1e3 * seconds / motion.frames();
  return result;
}

}  // namespace occupancy_fusion
