#!/usr/bin/env bash
# A long run through a building much larger than the map's memory bound (`benchmark spill`: a
# depth camera along a corridor with a room every 8 m): first without a bound, then with a bound
# of a quarter of what that map needed and a spill store. Reports the peak resident memory and
# the integration time per frame of both, whether the two saved .ot files are identical byte for
# byte (and the laser layers' .laser.npy, the layer bounded to a quarter of its size too), the time
# and peak memory of saving (streamed, and through liboctomap's OcTree for comparison), and draws
# spill_run.png (scripts/spill_run_plot.py). Writes into the output folder:
# unbounded.csv, bounded.csv (per frame), unbounded.ot, bounded.ot, spill_run.txt, spill_run.png.
# Usage: scripts/spill_long_run.sh [metres, default 300] [output folder, default
#        ./output/spill_run] [resolution, default 0.05] [1: the camera comes back the same way,
#        so that every block is written again (paged in from the store); default 0]
# SPILL_BUILD_DIR=<catkin build folder> uses that build as it is (no install, no build step).
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:/bin:$PATH"
length="${1:-300}"
out="$(realpath -m "${2:-$root/output/spill_run}")"
resolution="${3:-0.05}"
comes_back="${4:-0}"
if [[ -z "${SPILL_BUILD_DIR:-}" ]]; then
  "$root/scripts/install_dependencies.sh"
  "$root/scripts/build.sh"
fi
build="$(realpath -m "${SPILL_BUILD_DIR:-$root/build}")"
benchmark="$build/devel/lib/occupancy_fusion/benchmark"
mkdir -p "$out"
rm -rf "$out/store"

echo "spill run: $length m without a bound" >&2
"$benchmark" spill --length "$length" --resolution "$resolution" --return "$comes_back" \
  --csv "$out/unbounded.csv" --save_liboctomap 1 \
  --save "$out/unbounded" | tee "$out/unbounded.txt"
map_mb=$(grep -o 'map_mb=[0-9.]*' "$out/unbounded.txt" | head -1 | cut -d= -f2)
bound=$(python3 -c "print(round($map_mb / 4, 1))")
layer_mb=$(grep -o 'layer_mb=[0-9.]*' "$out/unbounded.txt" | head -1 | cut -d= -f2)
layer_bound=$(python3 -c "print(round($layer_mb / 4, 2))")
echo "spill run: $length m with a bound of $bound MiB (a quarter of $map_mb MiB) and" \
  "$layer_bound MiB for the laser layer (a quarter of $layer_mb MiB)" >&2
"$benchmark" spill --length "$length" --resolution "$resolution" --return "$comes_back" \
  --bound_mb "$bound" --layer_bound_mb "$layer_bound" \
  --spill_folder "$out/store" --csv "$out/bounded.csv" --save "$out/bounded" --save_liboctomap 1 \
  | tee "$out/bounded.txt"
if cmp -s "$out/unbounded.ot" "$out/bounded.ot"; then same="identical"; else same="DIFFERENT"; fi
if cmp -s "$out/unbounded.laser.npy" "$out/bounded.laser.npy"; then
  layer_same="identical"
else
  layer_same="DIFFERENT"
fi
{
  grep '^spill' "$out/unbounded.txt"
  grep '^spill' "$out/bounded.txt"
  grep '^saved ' "$out/unbounded.txt" "$out/bounded.txt"
  echo "saved maps: $same ($(stat -c %s "$out/bounded.ot") bytes)"
  echo "saved laser layers: $layer_same ($(stat -c %s "$out/bounded.laser.npy") bytes)"
  echo "store on disk: $(du -sh "$out/store" | cut -f1)"
} | tee "$out/spill_run.txt"
python3 "$root/scripts/spill_run_plot.py" "$out/unbounded.csv" "$out/bounded.csv" "$bound" \
  "$out/spill_run.png"
echo "spill run: wrote $out/spill_run.txt and $out/spill_run.png" >&2
[[ "$same" == "identical" && "$layer_same" == "identical" ]]
