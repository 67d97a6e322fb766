#!/usr/bin/env bash
# Soak test: the demo's real recordings (make_demo_recording: Intel laser scans, Middlebury stereo
# disparity, simulated depth; see scripts/demo.sh) played in a loop (rosbag play -l, so ROS time
# jumps back at every loop) into mapping.launch with the depth, disparity and laser mappers in one
# manager, while the MapServer publishes every output at 10 Hz to watching subscribers and
# ~save_map is called every 5 s. scripts/soak_monitor.py samples the manager's resident memory
# and the mappers' per-frame integration time every 5 s into soak.csv; scripts/soak_plot.py
# draws soak.png. Not part of scripts/test.sh (it runs for minutes).
# Usage: scripts/soak.sh [duration in s, default 600] [output folder, default ./output/soak]
# SOAK_BUILD_DIR=<catkin build folder> uses that build as it is (no install, no build step).
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:/bin:$PATH"
export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-PASSIVE}"
# ... after a few microseconds of spinning (libgomp), which bridges a frame's parallel regions.
export GOMP_SPINCOUNT="${GOMP_SPINCOUNT:-3000}"
duration="${1:-600}"
out="$(realpath -m "${2:-$root/output/soak}")"
if [[ -z "${SOAK_BUILD_DIR:-}" ]]; then
  "$root/scripts/install_dependencies.sh"
  "$root/scripts/build.sh"
fi
build="$(realpath -m "${SOAK_BUILD_DIR:-$root/build}")"
bin="$build/devel/lib/occupancy_fusion"
data="$root/data/demo"
mkdir -p "$out/saved"

if [[ ! -f "$out/demo.bag" ]]; then
  "$bin/make_demo_recording" --carmen "$data/intel/intel_flaser_every2nd.log.gz" \
    --stereo "$data/middlebury/ArtL" --stereo "$data/middlebury/Motorcycle" \
    --output "$out/demo.bag"
fi

# mapping.launch as demo.launch runs it, but publishing as fast as the map server is allowed to.
cat > "$out/soak.launch" << 'EOF'
<launch>
  <param name="use_sim_time" value="true"/>
  <include file="$(find occupancy_fusion)/launch/mapping.launch">
    <arg name="depth" value="true"/>
    <arg name="disparity" value="true"/>
    <arg name="laser" value="true"/>
    <arg name="image" value="camera/depth/image"/>
    <arg name="front_scan" value="scan"/>
  </include>
  <param name="map_server/publish_rate" value="10.0"/>
</launch>
EOF

source "$build/devel/setup.bash"
source "$root/scripts/mapping_graph.sh"
start_mapping_graph "$out/soak.launch" "$out/roslaunch.log"
rosbag play -q -l --clock "$out/demo.bag" > "$out/rosbag.log" 2>&1 &
player=$!
python3 "$root/scripts/soak_monitor.py" --duration "$duration" --csv "$out/soak.csv" \
  --save-prefix "$out/saved/map"
python3 "$root/scripts/soak_plot.py" "$out/soak.csv" "$out/soak.png"
echo "soak: $out/soak.csv, $out/soak.png"
