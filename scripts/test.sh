#!/usr/bin/env bash
# Installs the dependencies, builds, and runs every test (gtest unit tests and rostests).
# Prints "N passed, N failed" (test cases) and exits non-zero on any failure.
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:/bin:$PATH"
# OpenMP threads sleep while they wait: spinning stalls frames when the cores are shared.
export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-PASSIVE}"
# The rostests' nodes talk over loopback: name it, so tests pass on machines whose own host name
# does not resolve (containers, chroots, fresh cloud images).
export ROS_HOSTNAME="${ROS_HOSTNAME:-localhost}"
"$root/scripts/install_dependencies.sh"
"$root/scripts/build.sh" --tests
build="$root/build"
rm -rf "$build/test_results"
set +e
(cd "$build" && ctest --output-on-failure -j"${JOBS:-$(nproc)}")
ctest_status=$?
# libFuzzer harnesses (clang, ASan + UBSan), FUZZ_SECONDS (default 10) each; JUnit XML beside the
# tests' (counted below).
"$root/scripts/fuzz.sh" "${FUZZ_SECONDS:-10}"
# Every test executable and rostest leaves JUnit XML here (a crashed one a MISSING-*.xml).
/usr/bin/python3 "$root/scripts/count_test_results.py" "$build/test_results" > "$build/test_counts.txt"
count_status=$?
set -e
grep '^FAILED' "$build/test_counts.txt" || true
if ((ctest_status != 0 && count_status == 0)); then
  echo "ctest failed (exit $ctest_status) although every result file passed: a test crashed"
  sed -i 's/\([0-9]*\) failed/1 failed/' "$build/test_counts.txt"
  count_status=1
fi
tail -n 1 "$build/test_counts.txt"
exit "$count_status"
