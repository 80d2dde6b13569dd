#!/usr/bin/env bash
# -DRDTF_CORE_ONLY=ON configures librdtf alone: with CLI11 and Java made unfindable
# (CMAKE_DISABLE_FIND_PACKAGE_*), it must configure, look for no LCM piece, and plan librdtf and
# its install rules but no daemon, client or test. (Configure only: building core/ is what the
# main build does already; README, "Install", says how to build it.)
# Usage: core_only_test.sh SOURCE_DIR
set -euo pipefail

source_dir=$1
fail() { echo "FAIL: $*" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmake -S "$source_dir" -B "$work/build" -G Ninja -DRDTF_CORE_ONLY=ON \
  -DCMAKE_DISABLE_FIND_PACKAGE_CLI11=ON -DCMAKE_DISABLE_FIND_PACKAGE_Java=ON -DCMAKE_DISABLE_FIND_PACKAGE_GTest=ON \
  >"$work/configure.log" 2>&1 || { cat "$work/configure.log"; fail "core-only configure failed"; }
if grep -E '^(LCM_|RDTF_LCM|Java_|CLI11_DIR|GTest)' "$work/build/CMakeCache.txt"; then
  fail "the core-only configure looked for the pieces above"
fi
targets=$(ninja -C "$work/build" -t targets all)
for wanted in core/librdtf.a install; do
  grep -q "^$wanted:" <<<"$targets" || fail "no $wanted target"
done
for unwanted in daemon/rdtfd clients/rdtf/rdtf tests/rdtf_tests lcmtypes/rdtf_lcmtypes.jar; do
  if grep -q "^$unwanted:" <<<"$targets"; then fail "core-only plans $unwanted"; fi
done
echo "PASS: core-only configure needs no LCM, CLI11, Java or GTest and builds librdtf only"
