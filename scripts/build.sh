#!/usr/bin/env bash
# Builds the package in Release into ./build (catkin devel space: ./build/devel), with the tests
# when called with --tests. Quick when nothing changed.
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# Debian's python3 (with catkin_pkg) must come before any other python3 on PATH.
export PATH="/usr/bin:/bin:$PATH"
build="$root/build"
jobs="${JOBS:-$(nproc)}"
if [[ ! -f "$build/CMakeCache.txt" ]]; then
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=ON
fi
make -C "$build" -j"$jobs" --no-print-directory
if [[ "${1:-}" == "--tests" ]]; then
  make -C "$build" -j"$jobs" --no-print-directory tests
fi
