#!/usr/bin/env bash
# The whole robot's budget in the ROS graph: mapping.launch with the depth, disparity and laser
# mappers and the MapServer in one manager, fed at native rates by a recorded robot played with
# rosbag (simulate_recording, generated once into the output folder: the room scene, a depth
# camera 640 x 480 at 30 Hz, a stereo camera's disparity 640 x 480 at 15 Hz with a matcher's
# patches, two laser scanners at 40 Hz, tf at 120 Hz; stereo matching is not part of it), with
# projected_map and the markers subscribed. scripts/robot_budget_monitor.py measures after a
# warm-up: per sensor the frames sent, integrated and dropped, and the latency from each frame's
# stamp to the first projected_map that holds it (projected_map_stamps), in the bag's time, and
# per sensor that latency split into the player's lag and the mapping's share; the
# mapping manager's and the player's CPU share of the cores. Writes robot_budget.csv (per 5 s
# window), robot_budget.txt (the summary) and robot_budget.png (scripts/robot_budget_plot.py).
# (The Simulator nodelet renders these sensors at about 11 Hz on two cores: too slow to feed
# them live.)
# Usage: scripts/robot_budget.sh [seconds measured, default 60] [output folder, default
#        ./output/robot_budget] [name:=value ...  arguments of the generated launch file:
#        resolution (default 0.05), publish_rate (the MapServer's, default 20 Hz), stereo_input
#        (full, half or quarter; default full), worker_threads (the manager's; default
#        mapping.launch's, 6), queue_size (the mappers' input queues; default their configs', 5),
#        stereo_method (visibility or octomap), disparity (false: no DisparityMapper),
#        depth_threads and disparity_threads (the mappers' ~threads; default their configs'),
#        disparity_queue_size (the DisparityMapper's queue alone)]
# BUDGET_BUILD_DIR=<catkin build folder> uses that build as it is (no install, no build step).
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:/bin:$PATH"
duration="${1:-60}"
warmup=15
out="$(realpath -m "${2:-$root/output/robot_budget}")"
shift 2 || shift $#
if [[ -z "${BUDGET_BUILD_DIR:-}" ]]; then
  "$root/scripts/install_dependencies.sh"
  "$root/scripts/build.sh"
fi
build="$(realpath -m "${BUDGET_BUILD_DIR:-$root/build}")"
bin="$build/devel/lib/occupancy_fusion"
mkdir -p "$out"

seconds=$((warmup + duration + 5))
bag="$out/robot_${seconds}s.bag"
if [[ ! -f "$bag" ]]; then
  echo "robot budget: recording $seconds s of the simulated robot into $bag" >&2
  "$bin/simulate_recording" --output "$bag.tmp" --scene room --frames $((seconds * 120)) \
    --rate 120 --sensors depth,disparity,scan --every depth=4,disparity=8,scan=3 \
    --image-size 640x480 --disparity-patches 0.2
  mv "$bag.tmp" "$bag"
fi

cat > "$out/robot_budget.launch" << 'EOF'
<launch>
  <arg name="resolution" default="0.05"/>
  <arg name="publish_rate" default="20.0"/>
  <arg name="stereo_input" default="full"/>
  <arg name="worker_threads" default="6"/>  <!-- the manager's; mapping.launch's default -->
  <arg name="queue_size" default=""/>       <!-- the mappers' input queues; "": their configs' -->
  <arg name="stereo_method" default="visibility"/>
  <arg name="disparity" default="true"/>      <!-- false: no DisparityMapper -->
  <arg name="depth_threads" default=""/>       <!-- the mappers' ~threads; "": their configs' -->
  <arg name="disparity_threads" default=""/>
  <arg name="disparity_queue_size" default=""/>  <!-- the DisparityMapper's alone, after queue_size -->
  <param name="use_sim_time" value="true"/>
  <include file="$(find occupancy_fusion)/launch/mapping.launch">
    <arg name="depth" value="true"/>
    <arg name="disparity" value="$(arg disparity)"/>
    <arg name="laser" value="true"/>
    <arg name="image" value="camera/depth/image"/>
    <arg name="front_scan" value="scan_front"/>
    <arg name="rear_scan" value="scan_rear"/>
    <arg name="stereo_method" value="$(arg stereo_method)"/>
    <arg name="worker_threads" value="$(arg worker_threads)"/>
  </include>
  <param name="map_server/publish_rate" value="$(arg publish_rate)"/>
  <param name="map_server/resolution" value="$(arg resolution)"/>
  <param name="depth_mapper/resolution" value="$(arg resolution)"/>
  <param name="disparity_mapper/resolution" value="$(arg resolution)"/>
  <param name="laser_mapper/resolution" value="$(arg resolution)"/>
  <param name="disparity_mapper/stereo/input_resolution" value="$(arg stereo_input)"/>
  <param if="$(eval arg('depth_threads') != '')" name="depth_mapper/threads"
         value="$(arg depth_threads)"/>
  <param if="$(eval arg('disparity_threads') != '')" name="disparity_mapper/threads"
         value="$(arg disparity_threads)"/>
  <group if="$(eval arg('queue_size') != '')">
    <param name="depth_mapper/queue_size" value="$(arg queue_size)"/>
    <param unless="$(eval arg('disparity_queue_size') != '')" name="disparity_mapper/queue_size"
           value="$(arg queue_size)"/>
    <param name="laser_mapper/queue_size" value="$(arg queue_size)"/>
  </group>
  <param if="$(eval arg('disparity_queue_size') != '')" name="disparity_mapper/queue_size"
         value="$(arg disparity_queue_size)"/>
</launch>
EOF

source "$build/devel/setup.bash"
source "$root/scripts/mapping_graph.sh"
start_mapping_graph "$out/robot_budget.launch" "$out/roslaunch.log" "$@"
# The clock at 100 Hz: every node under use_sim_time receives it (at 1 kHz the clock alone took
# about a sixth of the 2 cores); the monitor reads the bag's time off its own wall clock.
rosbag play -q --clock --hz 100 "$bag" > "$out/rosbag.log" 2>&1 &
player=$!
echo "robot budget: measuring for $duration s (after $warmup s of warm-up) into $out" >&2
python3 "$root/scripts/robot_budget_monitor.py" --duration "$duration" --warmup "$warmup" \
  --player-pid "$player" --bag "$bag" --topic /camera/depth/image --topic /stereo/disparity \
  --topic /scan_front --topic /scan_rear --lag-topic /scan_front --lag-topic /scan_rear \
  --lag-topic /camera/depth/image=/camera/depth/camera_info \
  --lag-topic /stereo/disparity=/stereo/left/camera_info \
  --csv "$out/robot_budget.csv" \
  --summary "$out/robot_budget.txt"
python3 "$root/scripts/robot_budget_plot.py" "$out/robot_budget.csv" "$out/robot_budget.png"
echo "robot budget: $out/robot_budget.txt, $out/robot_budget.csv, $out/robot_budget.png"
