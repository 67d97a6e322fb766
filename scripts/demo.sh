#!/usr/bin/env bash
# Installs the dependencies, builds, and runs the demo: a simulated robot with a point-cloud
# camera, a depth camera, a stereo camera and two laser scanners records a room (a rosbag
# generated here), and offline_mapper maps all of it into one map (3D voxels + 2D laser layer).
# Results go to ./output/demo (or the folder given as the first argument).
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
# The simulated cameras are noise-free but for 0.1 px of disparity noise: a narrow depth model
# (k / (sigma sqrt(2 pi)) < 0.5, Eq. 7) and that disparity sigma suit them at 5 cm.
"$bin/offline_mapper" --config "$root/config/point_cloud_mapper.yaml" \
  --config "$root/config/depth_mapper.yaml" --config "$root/config/disparity_mapper.yaml" \
  --config "$root/config/laser_mapper.yaml" --config "$root/config/map_server.yaml" \
  --set depth/k=0.05 --set depth/sigma=0.05 --set stereo/disparity_sigma_px=0.1 \
  --bag "$out/room.bag" --output-dir "$out" --name room
echo "[demo] results in $out:"
ls -1 "$out"
