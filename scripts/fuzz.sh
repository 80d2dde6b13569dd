#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/) with clang under ASan+UBSan and runs each one for a bounded
# number of executions or a bounded time, seeded from fuzz/corpus/<target>/ and the target's
# regression reproducers (tests/data/fuzz-regressions/<target>/). Installs nothing: run
# scripts/install-deps.sh first (clang, libclang-rt-14-dev); uses ccache only if it is installed.
#
#   bash scripts/fuzz.sh                     # every target, the budgets below (what CI runs)
#   bash scripts/fuzz.sh convert_gltf extras # only these targets (no executions floor)
#
# Budgets: glb (the GLB container parser, ~30,000 executions per CPU-second) runs a fixed number
# of executions, FUZZ_GLB_RUNS, which alone reaches the floor of 1,000,000 executions per run; the
# pipeline targets (convert_gltf, convert_glb, extras, urdf_import: ~300-7,000 per CPU-second) run
# FUZZ_SECONDS each, `bus` (LCM datagrams to rdtfd's and the clients' handlers) FUZZ_BUS_SECONDS,
# `client` (datagram sequences to rdtf_client) FUZZ_CLIENT_SECONDS and the decoders (`draco`,
# `meshopt`: compressed meshes) FUZZ_DECODER_SECONDS each: 4 x 143 + 60 + 30 + 2 x 30 s, the
# 4 x 180 s the pipeline targets had before `bus` came. FUZZ_JOBS targets
# run at once (default: one per CPU, so two on CI's 2 cores).
# Every libFuzzer run starts afresh from the seeds; what it finds goes to $BUILD_DIR/fuzz-run/.
#
# Prints, per target, its executions, executions per second and coverage (libFuzzer's cov: edges,
# ft: features), then the total, then one closing line "fuzz: N passed, N failed". Each target
# is one test; it fails if it crashes, leaks, hangs past 25 s on one input, or breaks the
# bad-input contract (fuzz/fuzz_pipeline.h); its reproducer is printed, with its bytes in base64
# so that a CI log is enough to recreate it. When every target runs, the floor of executions in
# all (FUZZ_MIN_EXECUTIONS) is one more test: fewer executions (a machine too slow for the
# budgets) fail the run.
#
# Environment: BUILD_DIR (default build-fuzz), FUZZ_SECONDS (default 143), FUZZ_BUS_SECONDS (default
# 60), FUZZ_CLIENT_SECONDS (default 30), FUZZ_DECODER_SECONDS (default 30), FUZZ_GLB_RUNS (default
# 1000000), FUZZ_MIN_EXECUTIONS (default 1000000 when every target runs, else 0 = no floor),
# FUZZ_JOBS (default nproc), FUZZ_RUNS_MAX_SECONDS (cap on the glb target's time, default 600).
set -uo pipefail

cd "$(dirname "$0")/.."
root=$(pwd)
build=${BUILD_DIR:-build-fuzz}
seconds=${FUZZ_SECONDS:-143}
bus_seconds=${FUZZ_BUS_SECONDS:-60}
client_seconds=${FUZZ_CLIENT_SECONDS:-30}
decoder_seconds=${FUZZ_DECODER_SECONDS:-30}
glb_runs=${FUZZ_GLB_RUNS:-1000000}
runs_cap=${FUZZ_RUNS_MAX_SECONDS:-600}
jobs=${FUZZ_JOBS:-$(nproc)}
all_targets=(convert_gltf convert_glb extras urdf_import bus client draco meshopt glb)  # Longest first.
if (($# > 0)); then
  targets=("$@")
  min_executions=${FUZZ_MIN_EXECUTIONS:-0}
else
  targets=("${all_targets[@]}")
  min_executions=${FUZZ_MIN_EXECUTIONS:-1000000}
fi
for t in "${targets[@]}"; do
  if [[ ! -f fuzz/${t}_fuzzer.cc ]]; then
    echo "fuzz: no target '$t' (targets: ${all_targets[*]})"
    echo "fuzz: 0 passed, 1 failed"
    exit 1
  fi
done

start=$(date +%s)
echo "fuzz: load average at start: $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) CPUs, $jobs at once"

# ccache only where it is installed (a fresh CI machine has none); an empty launcher also clears
# one a previous configure of the same build folder put in its cache.
launcher=
if command -v ccache >/dev/null 2>&1; then
  launcher=ccache
  export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$root}
fi
mkdir -p "$build"
# Line tables only: what a sanitizer's or libFuzzer's stack trace needs (file and line), and a
# shorter build than full debug information (docs/benchmarks.md, "Build time").
line_tables="-O2 -gline-tables-only -DNDEBUG"
if ! CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_FLAGS_RELWITHDEBINFO="$line_tables" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$line_tables" \
    -DRDTF_BUILD_FUZZ=ON -DRDTF_BUILD_TESTS=OFF -DRDTF_SANITIZE=ON -DRDTF_WERROR=ON \
    -DCMAKE_CXX_COMPILER_LAUNCHER="$launcher" >"$build/fuzz-configure.log" 2>&1; then
  cat "$build/fuzz-configure.log"
  echo "fuzz: 0 passed, 1 failed (configure)"
  exit 1
fi
if ! cmake --build "$build" -j"$(nproc)" --target rdtf_fuzzers; then
  echo "fuzz: 0 passed, 1 failed (build)"
  exit 1
fi
echo "fuzz: built in $(($(date +%s) - start)) s${launcher:+ (with ccache)}"

# Fresh per run: the corpus each target grows, its crash artifacts, and TMPDIR for the fixed
# temp folders the targets make (the URDF target writes its input there).
out="$build/fuzz-run"
rm -rf "$out"
mkdir -p "$out/tmp"
export TMPDIR="$root/$out/tmp"
# Leaks are reported by ASan at exit like any crash; UBSan stops at the first finding.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# The GLB pipeline target sees GLB containers whose JSON chunk is glTF: both dictionaries.
cat fuzz/glb.dict fuzz/gltf.dict >"$out/convert_glb.dict"

dict_of() {
  case $1 in
    glb) echo fuzz/glb.dict ;;
    convert_glb) echo "$out/convert_glb.dict" ;;
    urdf_import) echo fuzz/urdf.dict ;;
    bus | client | draco | meshopt) echo "" ;;
    *) echo fuzz/gltf.dict ;;
  esac
}

# run_target NAME: one bounded libFuzzer run; writes $out/NAME.log and $out/NAME.seconds.
run_target() {
  local name=$1 t0 limit
  local work="$out/corpus-$name" seeds=("fuzz/corpus/$name")
  [[ -d tests/data/fuzz-regressions/$name ]] && seeds+=("tests/data/fuzz-regressions/$name")
  if [[ $name == glb ]]; then
    limit=(-runs="$glb_runs" -max_total_time="$runs_cap")
  elif [[ $name == bus ]]; then
    limit=(-max_total_time="$bus_seconds")
  elif [[ $name == client ]]; then
    limit=(-max_total_time="$client_seconds")
  elif [[ $name == draco || $name == meshopt ]]; then
    limit=(-max_total_time="$decoder_seconds")
  else
    limit=(-max_total_time="$seconds")
  fi
  local timeout=25
  mkdir -p "$work"
  t0=$(date +%s)
  local dict
  dict=$(dict_of "$name")
  "$build/fuzz/${name}_fuzzer" -max_len=4096 ${dict:+-dict="$dict"} -timeout="$timeout" \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$out/$name-" "${limit[@]}" \
    "$work" "${seeds[@]}" >"$out/$name.log" 2>&1 &
  echo $! >"$out/$name.pid"
  wait $!
  echo $? >"$out/$name.status"
  echo $(($(date +%s) - t0)) >"$out/$name.seconds"
  rm -f "$out/$name.pid"
}

# Stopped early (Ctrl-C, CI's time limit): stop the fuzzers this run started, by their ids.
stop_fuzzers() {
  local f
  for f in "$out"/*.pid; do [[ -f $f ]] && kill "$(cat "$f")" 2>/dev/null; done
}
trap 'stop_fuzzers; exit 130' INT
trap 'stop_fuzzers; exit 143' TERM
running=0
for name in "${targets[@]}"; do
  if ((running >= jobs)); then
    wait -n
    running=$((running - 1))
  fi
  echo "fuzz: $name: started"
  run_target "$name" &
  running=$((running + 1))
done
wait
trap - INT TERM

passed=0
failed=0
total_units=0
for name in "${targets[@]}"; do
  log="$out/$name.log"
  status=$(cat "$out/$name.status" 2>/dev/null || echo 1)
  secs=$(cat "$out/$name.seconds" 2>/dev/null || echo 0)
  units=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  [[ -n $units ]] || units=$(grep -oE '^#[0-9]+' "$log" | tail -1 | tr -d '#')
  [[ -n $units ]] || units=0
  cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+ corp: [0-9]+' "$log" | tail -1)
  total_units=$((total_units + units))
  rate=$((units / (secs > 0 ? secs : 1)))
  if [[ $status == 0 ]]; then
    passed=$((passed + 1))
    echo "fuzz: $name: ok, $units executions in $secs s ($rate/s), ${cov:-no coverage line}"
  else
    failed=$((failed + 1))
    echo "fuzz: $name: FAILED (exit $status) after $units executions in $secs s, ${cov:-no coverage line}"
    grep -m3 -E '^==[0-9]+==ERROR|ERROR: libFuzzer|runtime error|what\(\)|rdtf fuzz:' "$log" |
      sed "s/^/fuzz: $name:   /"
    grep -E '^ +#[0-9]+ .* in rdtf::' "$log" | head -8 | sed -E "s/^ +/fuzz: $name:     /"
    reproducer=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -1)
    if [[ -n $reproducer && -f $reproducer ]]; then
      echo "fuzz: $name: reproducer $reproducer ($(stat -c %s "$reproducer") bytes), base64:"
      base64 -w 100 "$reproducer" | sed "s/^/fuzz: $name:   /"
      echo "fuzz: $name: replay: $build/fuzz/${name}_fuzzer $reproducer; add it to" \
        "tests/data/fuzz-regressions/$name/ and expected.json"
    else
      echo "fuzz: $name: no reproducer written; log: $log"
    fi
  fi
done

elapsed=$(($(date +%s) - start))
echo "fuzz: $total_units executions in all, $elapsed s including the build;" \
  "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
if ((min_executions > 0)); then
  if ((total_units >= min_executions)); then
    passed=$((passed + 1))
    echo "fuzz: executions floor: ok, $total_units >= $min_executions"
  else
    failed=$((failed + 1))
    echo "fuzz: executions floor: FAILED, $total_units < $min_executions" \
      "(a target failed early, or this machine is too slow for the budgets: see FUZZ_GLB_RUNS, FUZZ_RUNS_MAX_SECONDS)"
  fi
fi
echo "fuzz: $passed passed, $failed failed"
((failed == 0))
