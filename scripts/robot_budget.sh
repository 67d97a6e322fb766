#!/usr/bin/env bash
# The whole robot's budget in the ROS graph: mapping.launch with the depth, disparity and laser
# mappers and the MapServer in one manager, fed at native rates by the Simulator in a process of
# its own (a depth camera 640 x 480 at 30 Hz, a stereo camera's disparity 640 x 480 at 15 Hz,
# two laser scanners at 40 Hz; stereo matching is the simulator's, so it is counted apart), with
# projected_map and the markers subscribed. scripts/robot_budget_monitor.py measures, after a
# warm-up: per sensor the frames sent, integrated and dropped, and the latency from each frame's
# stamp to the first projected_map that holds it (projected_map_stamps); the mapping manager's
# and the simulator's CPU share of the cores. Writes robot_budget.csv (per 5 s window),
# robot_budget.txt (the summary) and robot_budget.png (scripts/robot_budget_plot.py).
# Usage: scripts/robot_budget.sh [seconds measured, default 120] [output folder, default
#        ./output/robot_budget] [name:=value ...  roslaunch arguments of the generated launch file:
#        resolution, publish_rate, depth_rate, stereo_rate, laser_rate, depth_width, depth_height,
#        stereo_width, stereo_height, stereo_input (full, half or quarter)]
# BUDGET_BUILD_DIR=<catkin build folder> uses that build as it is (no install, no build step).
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:/bin:$PATH"
duration="${1:-120}"
out="$(realpath -m "${2:-$root/output/robot_budget}")"
shift 2 || shift $#
if [[ -z "${BUDGET_BUILD_DIR:-}" ]]; then
  "$root/scripts/install_dependencies.sh"
  "$root/scripts/build.sh"
fi
build="$(realpath -m "${BUDGET_BUILD_DIR:-$root/build}")"
mkdir -p "$out"

cat > "$out/robot_budget.launch" << 'EOF'
<launch>
  <arg name="resolution" default="0.05"/>
  <arg name="publish_rate" default="20.0"/>
  <arg name="depth_rate" default="30.0"/>
  <arg name="depth_width" default="640"/>
  <arg name="depth_height" default="480"/>
  <arg name="stereo_rate" default="15.0"/>
  <arg name="stereo_width" default="640"/>
  <arg name="stereo_height" default="480"/>
  <arg name="stereo_input" default="full"/>
  <arg name="laser_rate" default="40.0"/>

  <node pkg="occupancy_fusion" type="simulator_node" name="simulator" output="screen">
    <rosparam file="$(find occupancy_fusion)/config/simulator.yaml" command="load"/>
    <param name="camera/rate" value="$(arg depth_rate)"/>
    <param name="camera/width" value="$(arg depth_width)"/>
    <param name="camera/height" value="$(arg depth_height)"/>
    <param name="stereo/rate" value="$(arg stereo_rate)"/>
    <param name="stereo/width" value="$(arg stereo_width)"/>
    <param name="stereo/height" value="$(arg stereo_height)"/>
    <param name="front_laser/rate" value="$(arg laser_rate)"/>
    <param name="rear_laser/rate" value="$(arg laser_rate)"/>
  </node>

  <include file="$(find occupancy_fusion)/launch/mapping.launch">
    <arg name="depth" value="true"/>
    <arg name="disparity" value="true"/>
    <arg name="laser" value="true"/>
    <arg name="image" value="camera/depth/image"/>
  </include>
  <param name="map_server/publish_rate" value="$(arg publish_rate)"/>
  <param name="map_server/resolution" value="$(arg resolution)"/>
  <param name="depth_mapper/resolution" value="$(arg resolution)"/>
  <param name="disparity_mapper/resolution" value="$(arg resolution)"/>
  <param name="laser_mapper/resolution" value="$(arg resolution)"/>
  <param name="disparity_mapper/stereo/input_resolution" value="$(arg stereo_input)"/>
</launch>
EOF

source "$build/devel/setup.bash"
export ROS_HOSTNAME=localhost
port="$(python3 -c 'import socket; s=socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://localhost:$port"
roslaunch -p "$port" "$out/robot_budget.launch" "$@" > "$out/roslaunch.log" 2>&1 &
launch=$!
cleanup() {
  kill -INT "$launch" 2> /dev/null || true
  wait "$launch" 2> /dev/null || true
}
trap cleanup EXIT
timeout 120 python3 -c '
import time, rosgraph
master = rosgraph.Master("/robot_budget")
while True:
    try:
        master.lookupService("/map_server/save_map")
        master.lookupNode("/simulator")
        break
    except Exception:  # master not up yet, or not advertised yet
        time.sleep(1)'
echo "robot budget: measuring for $duration s (after 15 s of warm-up) into $out" >&2
python3 "$root/scripts/robot_budget_monitor.py" --duration "$duration" --warmup 15 \
  --topic /camera/depth/image --topic /stereo/disparity --topic /front_laser/scan \
  --topic /rear_laser/scan --csv "$out/robot_budget.csv" --summary "$out/robot_budget.txt"
python3 "$root/scripts/robot_budget_plot.py" "$out/robot_budget.csv" "$out/robot_budget.png"
echo "robot budget: $out/robot_budget.txt, $out/robot_budget.csv, $out/robot_budget.png"
