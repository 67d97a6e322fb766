#!/usr/bin/env bash
# Installs the dependencies, builds, and runs every test (gtest unit tests and rostests).
# Prints "N passed, N failed" (test cases) and exits non-zero on any failure.
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:/bin:$PATH"
"$root/scripts/install_dependencies.sh"
"$root/scripts/build.sh" --tests
build="$root/build"
rm -rf "$build/test_results"
set +e
(cd "$build" && ctest --output-on-failure -j"${JOBS:-$(nproc)}")
ctest_status=$?
summary=$(catkin_test_results "$build/test_results" 2>&1)
results_status=$?
set -e
echo "$summary" | grep -v '^Skipping' | tail -n 20
# "Summary: 42 tests, 0 errors, 1 failures, 0 skipped"
read -r total errors failures skipped < <(echo "$summary" |
  sed -n 's/^Summary: \([0-9]*\) tests, \([0-9]*\) errors, \([0-9]*\) failures, \([0-9]*\) skipped.*/\1 \2 \3 \4/p')
total=${total:-0}; errors=${errors:-0}; failures=${failures:-0}; skipped=${skipped:-0}
failed=$((errors + failures))
passed=$((total - failed - skipped))
if ((ctest_status != 0 && failed == 0)); then failed=1; fi  # a crash that left no result file
if ((total == 0)); then failed=$((failed + 1)); echo "no test ran"; fi
echo "${passed} passed, ${failed} failed, ${skipped} skipped"
((failed == 0 && results_status == 0))
