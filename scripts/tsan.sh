#!/usr/bin/env bash
# ThreadSanitizer run of the multi-nodelet rostest sim_robot_mapping: the MapServer and the four
# mappers in one nodelet manager, fed by the Simulator, all built with -fsanitize=thread
# (CMake option OCCUPANCY_FUSION_TSAN). Exits non-zero if the test fails or if any process wrote
# a ThreadSanitizer report.
# Usage: scripts/tsan.sh [build folder, default ./build_tsan]
#
# How:
# - The nodelet manager is Debian's uninstrumented `nodelet` executable that dlopen()s our
#   instrumented library, so the TSAN runtime must be in the process from the start: libtsan is
#   preloaded into every process rostest starts (the Python ones, roslaunch and rosmaster, have
#   no instrumented code: TSAN checks only the accesses of instrumented code, ours).
# - ROS's own libraries (roscpp, tf2, ...) are not instrumented; their locks go through pthread
#   and are still seen by TSAN, so races between our code and theirs on our data are found.
# - OMP_NUM_THREADS=1: Debian's libgomp is not built with TSAN, so TSAN does not see the
#   synchronisation of its barriers and would report every OpenMP parallel loop as a race
#   (false positives). With one OpenMP thread the loops run on the calling thread; races between
#   the nodelets' threads (the case the shared map's lock is for) are still checked.
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:/bin:$PATH"
build="$(realpath -m "${1:-$root/build_tsan}")"
jobs="${JOBS:-$(nproc)}"

mkdir -p "$build"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 \
  -DCATKIN_ENABLE_TESTING=ON -DOCCUPANCY_FUSION_TSAN=ON > "$build/cmake.log" 2>&1 ||
  { cat "$build/cmake.log"; exit 1; }
make -C "$build" -j"$jobs" --no-print-directory occupancy_fusion_nodelets sim_robot_mapping

libtsan="$(g++ -print-file-name=libtsan.so)"
[[ -f "$libtsan" ]] || { echo "libtsan.so not found (g++ -print-file-name)"; exit 1; }
reports="$build/tsan_reports"
rm -rf "$reports" "$build/ros_home"
mkdir -p "$reports"
# rostest --text exits 0 even when the test node fails: the test's own result file decides.
result_file="$build/ros_home/test_results/occupancy_fusion/rosunit-sim_robot_mapping.xml"

set +e
(
  source "$build/devel/setup.bash"
  export ROS_HOSTNAME="${ROS_HOSTNAME:-localhost}" ROS_HOME="$build/ros_home"
  export OMP_NUM_THREADS=1 OMP_WAIT_POLICY=PASSIVE
  # One file per process (tsan.<pid>); history_size=4 keeps the second stack of a race readable.
  export TSAN_OPTIONS="log_path=$reports/tsan history_size=4 second_deadlock_stack=1 \
suppressions=$root/test/tsan/suppressions.txt"
  # A quarter of the sensor rates: instrumented code runs several times slower, and at the full
  # rates the mappers' queues overflow (the test checks that every frame sent was received).
  LD_PRELOAD="$libtsan" rostest --text occupancy_fusion sim_robot_mapping.test rate_scale:=0.25
)
test_status=$?
if ((test_status == 0)) && ! python3 - "$result_file" <<'PY'; then
import sys
import xml.etree.ElementTree as ElementTree
try:
    suites = ElementTree.parse(sys.argv[1]).getroot()
except (OSError, ElementTree.ParseError) as error:
    sys.exit(f"tsan: no readable test result ({error})")
passed = int(suites.get("tests", "0")) > 0 and suites.get("failures") == "0" and suites.get("errors") == "0"
sys.exit(0 if passed else f"tsan: the test failed ({sys.argv[1]})")
PY
  test_status=1
fi
set -e

# Frames of the dlopen()ed library are left unnamed by the runtime: named here, and the reports
# matching test/tsan/symbolized_suppressions.txt (which the runtime cannot match) left out.
for report in "$reports"/tsan.*; do
  [[ -f "$report" ]] || continue
  python3 "$root/test/tsan/symbolize.py" --suppressions "$root/test/tsan/symbolized_suppressions.txt" \
    "$build/devel/lib" "$report" > "$report.txt"
done
report_count="$(cat "$reports"/tsan.*.txt 2>/dev/null | grep -c '^WARNING: ThreadSanitizer' || true)"
if ((report_count > 0)); then
  echo "tsan: $report_count ThreadSanitizer report(s), in $reports/*.txt; kinds:"
  grep -h '^SUMMARY' "$reports"/*.txt | sort | uniq -c | sort -rn | head -n 40 || true
fi
echo "tsan: test status $test_status, $report_count ThreadSanitizer report(s)"
((test_status == 0 && report_count == 0))
