#!/usr/bin/env bash
# Installs the dependencies, builds, and runs the demo on the bundled real recordings (data/demo):
# make_demo_recording turns a CARMEN laser log of the Intel Research Lab, two Middlebury stereo
# pairs (matched here with OpenCV's StereoSGBM) and a simulated depth camera into one rosbag with
# tf; offline_mapper maps all of it into one map (3D voxels + 2D laser layer) and writes .bt, .ot,
# .pgm/.yaml and pictures; then demo.launch maps the same bag online under Xvfb and rviz's window
# is captured. Results go to ./output/demo (or the folder given as the first argument).
# DEMO_BUILD_DIR=<catkin build folder> uses that build as it is (no install, no build step).
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:/bin:$PATH"
# OpenMP threads sleep while they wait: spinning stalls frames when the cores are shared.
export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-PASSIVE}"
# ... after a few microseconds of spinning (libgomp), which bridges a frame's parallel regions.
export GOMP_SPINCOUNT="${GOMP_SPINCOUNT:-3000}"
out="$(realpath -m "${1:-$root/output/demo}")"
if [[ -z "${DEMO_BUILD_DIR:-}" ]]; then
  "$root/scripts/install_dependencies.sh"
  "$root/scripts/build.sh"
fi
build="$(realpath -m "${DEMO_BUILD_DIR:-$root/build}")"
bin="$build/devel/lib/occupancy_fusion"
data="$root/data/demo"
mkdir -p "$out"

echo "[demo] making the recording: $out/demo.bag"
"$bin/make_demo_recording" --carmen "$data/intel/intel_flaser_every2nd.log.gz" \
  --stereo "$data/middlebury/ArtL" --stereo "$data/middlebury/Motorcycle" \
  --output "$out/demo.bag"

echo "[demo] mapping it offline"
# Each sensor kind takes its parameters from its mapper's file, the 2D band from the map server's.
"$bin/offline_mapper" --config "$root/config/depth_mapper.yaml" \
  --config "$root/config/disparity_mapper.yaml" --config "$root/config/laser_mapper.yaml" \
  --config "$root/config/map_server.yaml" \
  --bag "$out/demo.bag" --output-dir "$out" --name demo

echo "[demo] mapping it online in rviz (headless) for a screenshot: $out/demo_rviz.png"
(
  source "$build/devel/setup.bash"
  export ROS_HOSTNAME=localhost
  ROS_MASTER_URI="http://localhost:$(python3 -c 'import socket; s=socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')"
  export ROS_MASTER_URI
  port="${ROS_MASTER_URI##*:}"
  # Xvfb picks a free display and tells its number on file descriptor 3.
  exec 3< <(exec Xvfb -displayfd 1 -screen 0 1200x800x24 +extension GLX -nolisten tcp 2>/dev/null)
  xvfb=$!
  read -r -u 3 display
  export DISPLAY=":$display"
  rate=4
  roslaunch -p "$port" occupancy_fusion demo.launch bag:="$out/demo.bag" rate:="$rate" \
    > "$out/demo_roslaunch.log" 2>&1 &
  launch=$!
  # Start-up, the bag at $rate times its speed (45 s of recording) and a few map updates.
  sleep 35
  import -display "$DISPLAY" -window root "$out/demo_rviz.png"
  kill -INT "$launch"
  wait "$launch" || true
  kill "$xvfb" 2>/dev/null || true
)
echo "[demo] results in $out:"
ls -1 "$out"
