// Sensor trajectories for the simulator. Camera poses are poses of the optical frame
// (z forward, x right, y down) in the world (z up); robot poses are body frames (REP-103:
// x forward, y left, z up).
#pragma once

#include <Eigen/Geometry>
#include <vector>

namespace occupancy_fusion {
namespace sim {

// T_body_optical: the optical frame of a camera looking along its body's +x (the fixed rotation
// between ROS's camera_link and camera_optical_frame, rpy = (-pi/2, 0, -pi/2)).
Eigen::Isometry3d opticalFrameInBody();

// Optical frame at `eye` looking at `target`, with image "up" (-y) as close to `up` as possible.
// Throws std::invalid_argument if target == eye or the view direction is parallel to `up`.
Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                         const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

// n camera poses evenly spaced on a horizontal circle: pose k sits at
// center + (radius cos(2 pi k / n), radius sin(2 pi k / n), height) and looks at look_at.
std::vector<Eigen::Isometry3d> orbitTrajectory(const Eigen::Vector3d& center, double radius,
                                               double height, int n,
                                               const Eigen::Vector3d& look_at);

// The depth paper's sweep (Sec. 5.1: "rotating the camera around the x and y axis at 4 deg",
// 181 images): all poses at `position`; pose 0 has orientation R_world_start; poses 1..a turn
// it about the camera's own x axis by k * step_deg (k = 1..a), poses a+1..n-1 about its own y
// axis by k * step_deg (k = 1..b), with a = ceil((n-1)/2), b = floor((n-1)/2). With the defaults
// (181, 4 deg) each axis makes one full turn of 90 steps, its last view repeating the first.
// Default start: looking along world +x, image up = world +z.
std::vector<Eigen::Isometry3d> rotationSweep(
    const Eigen::Vector3d& position, int n = 181, double step_deg = 4.0,
    const Eigen::Matrix3d& R_world_start = opticalFrameInBody().linear());

// n >= 2 robot (body) poses from start to end, evenly spaced, yaw (rad, about world z)
// interpolated linearly from yaw_start to yaw_end. To face along the path use
// yaw = atan2(end.y - start.y, end.x - start.x) for both. Camera poses follow as
// pose * T_body_sensor * opticalFrameInBody().
std::vector<Eigen::Isometry3d> straightLinePath(const Eigen::Vector3d& start,
                                                const Eigen::Vector3d& end, int n, double yaw_start,
                                                double yaw_end);

// Robot (body) poses every step_m metres of travel along the outline of `rectangle` (x, y in m)
// with its corners rounded to arcs of corner_radius, driven counter-clockwise (seen from above)
// for `laps` laps: pose k lies k * step_m along the outline from the start (start_x, min y) on the
// bottom side, heading +x, z = 0, yaw along the direction of travel (so it turns smoothly, by
// step_m / corner_radius per pose, on the arcs). floor(laps * length / step_m) + 1 poses. Throws
// std::invalid_argument unless step_m > 0, laps >= 0, 0 < corner_radius <= half the shorter side
// and start_x lies on the straight part of the bottom side.
std::vector<Eigen::Isometry3d> roundedRectanglePath(const Eigen::AlignedBox2d& rectangle,
                                                    double corner_radius, double start_x,
                                                    double step_m, double laps);

// Length (m) of one lap of roundedRectanglePath: the perimeter less 8 - 2 pi corner radii.
double roundedRectangleLength(const Eigen::AlignedBox2d& rectangle, double corner_radius);

}  // namespace sim
}  // namespace occupancy_fusion
