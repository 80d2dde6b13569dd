#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/) with clang under ASan+UBSan and runs each one for a bounded
# time and number of executions, seeded from fuzz/corpus/<target>/. Installs nothing: run
# scripts/install-deps.sh first. Prints, per target, the executions and the coverage reached, then
# one closing line "fuzz: N passed, N failed"; a target that crashes (or breaks the bad-input
# contract, see fuzz/fuzz_pipeline.h) fails, and its reproducer's path is printed.
#
# Environment: BUILD_DIR (default build-fuzz), FUZZ_SECONDS (per slow target, default 75),
# FUZZ_GLB_RUNS (executions of the fast GLB container target, default 1000000).
set -uo pipefail

cd "$(dirname "$0")/.."
root=$(pwd)
build=${BUILD_DIR:-build-fuzz}
seconds=${FUZZ_SECONDS:-75}
glb_runs=${FUZZ_GLB_RUNS:-1000000}
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$root}

start=$(date +%s)
if ! CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DRDTF_BUILD_FUZZ=ON -DRDTF_BUILD_TESTS=OFF -DRDTF_SANITIZE=ON -DRDTF_WERROR=ON \
    -DCMAKE_CXX_COMPILER_LAUNCHER=ccache >"$build.configure.log" 2>&1; then
  cat "$build.configure.log"
  echo "fuzz: 0 passed, 1 failed (configure)"
  exit 1
fi
if ! cmake --build "$build" -j2 --target rdtf_fuzzers; then
  echo "fuzz: 0 passed, 1 failed (build)"
  exit 1
fi
echo "fuzz: built in $(( $(date +%s) - start )) s"

# Fresh per run: the corpus each target grows, its crash artifacts, and TMPDIR for the fixed
# temp folders the targets make (the URDF target writes its input there).
out="$build/fuzz-run"
rm -rf "$out"
mkdir -p "$out/tmp"
export TMPDIR="$root/$out/tmp"
# Leaks are reported by ASan at exit like any crash; UBSan stops at the first finding.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

passed=0
failed=0
total_units=0

# run_target NAME DICT LIMIT...: one bounded libFuzzer run; LIMIT is -runs=N or -max_total_time=S.
run_target() {
  local name=$1 dict=$2
  shift 2
  local log="$out/$name.log" work="$out/corpus-$name"
  mkdir -p "$work"
  "$build/fuzz/${name}_fuzzer" -max_len=4096 -dict="fuzz/$dict" -timeout=25 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$out/$name-" "$@" "$work" "fuzz/corpus/$name" \
    >"$log" 2>&1
  local status=$?
  local units cov
  units=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  [ -n "$units" ] || units=$(grep -oE '^#[0-9]+' "$log" | tail -1 | tr -d '#')
  [ -n "$units" ] || units=0
  cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$log" | tail -1)
  total_units=$(( total_units + units ))
  if [ $status -eq 0 ]; then
    passed=$(( passed + 1 ))
    echo "fuzz: $name: ok, $units executions, ${cov:-no coverage line}"
  else
    failed=$(( failed + 1 ))
    local reproducer
    reproducer=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -1)
    echo "fuzz: $name: FAILED (exit $status) after $units executions, ${cov:-no coverage line}"
    echo "fuzz: $name: reproducer: ${reproducer:-none written}; log: $log"
    grep -m1 -E 'ERROR: |runtime error|rdtf fuzz:' "$log" | sed "s/^/fuzz: $name:   /"
  fi
}

run_target glb glb.dict -runs="$glb_runs"
run_target convert_gltf gltf.dict -max_total_time="$seconds"
run_target convert_glb glb.dict -max_total_time="$seconds"
run_target extras gltf.dict -max_total_time="$seconds"
run_target urdf_import urdf.dict -max_total_time="$seconds"

echo "fuzz: $total_units executions in all, $(( $(date +%s) - start )) s including the build"
echo "fuzz: $passed passed, $failed failed"
[ $failed -eq 0 ]
