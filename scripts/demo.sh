#!/usr/bin/env bash
# Installs the dependencies, builds, and runs the demo: a simulated robot with a depth camera
# records a room (a rosbag generated here), and offline_mapper maps it. Results go to
# ./output/demo (or the folder given as the first argument).
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:/bin:$PATH"
out="$(realpath -m "${1:-$root/output/demo}")"
"$root/scripts/install_dependencies.sh"
"$root/scripts/build.sh"
bin="$root/build/devel/lib/occupancy_fusion"
mkdir -p "$out"
echo "[demo] simulating a recording: $out/room.bag"
"$bin/simulate_recording" --scene room --frames 60 --rate 5 --output "$out/room.bag"
echo "[demo] mapping it"
"$bin/offline_mapper" --config "$root/config/point_cloud_mapper.yaml" \
  --config "$root/config/map_server.yaml" --bag "$out/room.bag" \
  --output-dir "$out" --name room
echo "[demo] results in $out:"
ls -1 "$out"
