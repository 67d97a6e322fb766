#!/usr/bin/env bash
# Installs the dependencies, builds, and runs the demo: a simulated robot with a point-cloud
# camera, a depth camera, a stereo camera and two laser scanners records a room (a rosbag
# generated here), and offline_mapper maps all of it into one map (3D voxels + 2D laser layer).
# Results go to ./output/demo (or the folder given as the first argument).
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:/bin:$PATH"
# OpenMP threads sleep while they wait: spinning stalls frames when the cores are shared.
export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-PASSIVE}"
out="$(realpath -m "${1:-$root/output/demo}")"
"$root/scripts/install_dependencies.sh"
"$root/scripts/build.sh"
bin="$root/build/devel/lib/occupancy_fusion"
mkdir -p "$out"
echo "[demo] simulating a recording: $out/room.bag"
"$bin/simulate_recording" --scene room --frames 60 --rate 5 --output "$out/room.bag"
echo "[demo] mapping it"
# The simulated stereo camera has 0.1 px of disparity noise: the stereo error model (Eq. 7 of
# the stereo paper) is told so.
"$bin/offline_mapper" --config "$root/config/point_cloud_mapper.yaml" \
  --config "$root/config/depth_mapper.yaml" --config "$root/config/disparity_mapper.yaml" \
  --config "$root/config/laser_mapper.yaml" --config "$root/config/map_server.yaml" \
  --set stereo/disparity_sigma_px=0.1 \
  --bag "$out/room.bag" --output-dir "$out" --name room
echo "[demo] results in $out:"
ls -1 "$out"
