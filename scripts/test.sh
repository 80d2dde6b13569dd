#!/usr/bin/env bash
# Runs every test: installs the dependencies, configures, builds and runs ctest.
# Usage (from any folder): `bash scripts/test.sh` as root, or `sudo bash scripts/test.sh`.
# Environment:
#   RDTF_BUILD_DIR   build folder, relative to the repository root (default: build)
#   RDTF_BUILD_TYPE  CMAKE_BUILD_TYPE (default: RelWithDebInfo)
#   RDTF_CMAKE_ARGS  extra arguments for cmake's configure step, split on spaces
#                    (they come last, so they override the defaults above)
#   RDTF_JOBS        build and test jobs (default: 2)
# Exits with ctest's exit code (or the failing step's, when configure or build fails).
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."

build_dir=${RDTF_BUILD_DIR:-build}
build_type=${RDTF_BUILD_TYPE:-RelWithDebInfo}
jobs=${RDTF_JOBS:-2}
read -r -a extra_args <<<"${RDTF_CMAKE_ARGS:-}"

say() { printf 'test.sh: %s\n' "$*"; }
now() { date +%s; }
t0=$(now)

bash scripts/install-deps.sh
say "dependencies ready ($(($(now) - t0)) s)"

# A build folder configured earlier with another generator cannot be reused as it is.
if [[ -f $build_dir/CMakeCache.txt ]] && ! grep -qx 'CMAKE_GENERATOR:INTERNAL=Ninja' "$build_dir/CMakeCache.txt"; then
  say "$build_dir was configured with another generator: clearing its CMake cache"
  rm -rf "$build_dir/CMakeCache.txt" "$build_dir/CMakeFiles"
fi

t=$(now)
say "configure: cmake -S . -B $build_dir -G Ninja -DCMAKE_BUILD_TYPE=$build_type ${extra_args[*]}"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="$build_type" "${extra_args[@]}"
say "configure done ($(($(now) - t)) s)"

t=$(now)
say "build: cmake --build $build_dir -j$jobs"
cmake --build "$build_dir" -j"$jobs"
say "build done ($(($(now) - t)) s)"

t=$(now)
say "test: ctest --test-dir $build_dir --output-on-failure -j$jobs --no-tests=error"
rc=0
ctest --test-dir "$build_dir" --output-on-failure -j"$jobs" --no-tests=error || rc=$?
say "ctest exited $rc ($(($(now) - t)) s; whole script $(($(now) - t0)) s)"

# A digest of each failed test (its failure lines from ctest's log) in $build_dir/failed-tests.txt,
# which .ci/run prints again at its very end, where a truncated CI log still shows it.
digest="$build_dir/failed-tests.txt"
rm -f "$digest"
if [[ $rc -ne 0 && -f $build_dir/Testing/Temporary/LastTestsFailed.log ]]; then
  while IFS= read -r line; do
    name=${line#*:}
    output=$(awk -v name="$name" '
        $0 ~ "^[0-9]+/[0-9]+ Test: " && index($0, name) { inside = 1; next }
        inside && /^<end of output>/ { exit }
        inside' "$build_dir/Testing/Temporary/LastTest.log")
    failure=$(grep -E -A6 'Failure|FAILED|ERROR|error:|runtime error|Timeout|what\(\)' <<<"$output" | head -n 40)
    {
      echo "--- $name"
      # A test stopped at ctest's timeout printed no failure line: its last lines show where it was.
      if [[ -n $failure ]]; then echo "$failure"; else echo "(no failure line; its last lines:)"; tail -n 15 <<<"$output"; fi
    } | cut -c1-1000 >>"$digest"  # a dumped page state is one line of many kilobytes
  done <"$build_dir/Testing/Temporary/LastTestsFailed.log"
fi
exit "$rc"
