#!/usr/bin/env bash
# Builds the libFuzzer harnesses of test/fuzz with clang under AddressSanitizer and
# UndefinedBehaviorSanitizer into build/fuzz, and runs each for a few seconds. Each run starts from
# the checked-in inputs of test/fuzz/corpus/<harness> (seeds, and the input of every bug found,
# replayed first) and the seeds the harness writes itself. One result line per harness; one JUnit
# test case per harness in build/test_results/occupancy_fusion/fuzz.xml (counted by
# scripts/count_test_results.py), failed on a crash, sanitizer report, leak, timeout (10 s for
# one input) or memory use over 2 GiB. Inputs that fail are kept in build/fuzz/artifacts/.
# Usage: scripts/fuzz.sh [seconds per harness, default 10] [harness names...]
# FUZZ_BUILD_DIR and FUZZ_RESULTS_DIR override the build and JUnit folders.
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:/bin:$PATH"
seconds="${1:-10}"
shift || true
build="${FUZZ_BUILD_DIR:-$root/build/fuzz}"
results="${FUZZ_RESULTS_DIR:-$root/build/test_results/occupancy_fusion}"
mkdir -p "$results"
report="$build/results.tsv"

write_junit() {
  /usr/bin/python3 - "$report" "$results/fuzz.xml" <<'PY'
import sys
import xml.etree.ElementTree as ElementTree
suite = ElementTree.Element("testsuite", name="fuzz")
for line in open(sys.argv[1]):
    name, status, detail = line.rstrip("\n").split("\t", 2)
    case = ElementTree.SubElement(suite, "testcase", classname="fuzz", name=name)
    if status != "ok":
        ElementTree.SubElement(case, "failure", message=detail).text = detail
    else:
        ElementTree.SubElement(case, "system-out").text = detail
ElementTree.ElementTree(suite).write(sys.argv[2], encoding="utf-8", xml_declaration=True)
PY
}

mkdir -p "$build"
: > "$report"
if ! { cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 \
         -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCATKIN_ENABLE_TESTING=OFF \
         -DOCCUPANCY_FUSION_FUZZ=ON > "$build/configure.log" 2>&1 &&
       make -C "$build" -j"${JOBS:-$(nproc)}" --no-print-directory fuzz_harnesses \
         > "$build/build.log" 2>&1; }; then
  tail -n 30 "$build/configure.log" "$build/build.log" 2>/dev/null || true
  printf 'build\tfailed\tthe clang build of the fuzz harnesses failed (see build/fuzz/*.log)\n' \
    >> "$report"
  write_junit
  echo "fuzz: build failed"
  exit 1
fi

harnesses=("$@")
if ((${#harnesses[@]} == 0)); then
  for source in "$root"/test/fuzz/fuzz_*.cpp; do harnesses+=("$(basename "$source" .cpp)"); done
fi
failed=0
for harness in "${harnesses[@]}"; do
  corpus="$build/corpus/$harness"      # grows from run to run
  checked_in="$root/test/fuzz/corpus/$harness"
  artifacts="$build/artifacts/$harness/"
  mkdir -p "$corpus" "$checked_in" "$artifacts"
  log="$build/$harness.log"
  status=0
  FUZZ_SEED_DIR="$corpus" ASAN_OPTIONS="detect_leaks=1" UBSAN_OPTIONS="print_stacktrace=1" \
    "$build/fuzz/$harness" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$artifacts" "$corpus" "$checked_in" > "$log" 2>&1 ||
    status=$?
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")
  coverage=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$log" | tail -n 1)
  if ((status == 0)); then
    detail="${runs:-?} runs, ${speed:-?} exec/s, ${coverage:-no coverage line}, $(ls "$corpus" | wc -l) inputs in corpus"
    echo "fuzz $harness: ok, $detail"
    printf '%s\tok\t%s\n' "$harness" "$detail" >> "$report"
  else
    finding=$(grep -m 1 -E '^SUMMARY:|ERROR: libFuzzer' "$log" || echo "exit status $status")
    echo "fuzz $harness: FAILED after ${runs:-?} runs: $finding (log: $log, input: $artifacts)"
    grep -m 20 -E 'runtime error|ERROR:|#[0-9]+ 0x' "$log" || true
    printf '%s\tfailed\t%s\n' "$harness" "$finding" >> "$report"
    failed=1
  fi
done
write_junit
exit "$failed"
