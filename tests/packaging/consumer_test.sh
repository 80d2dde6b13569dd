#!/usr/bin/env bash
# librdtf as another CMake project meets it: installs the build's dev component (librdtf, headers,
# CMake package config) into a scratch prefix, configures and builds tests/packaging/consumer with
# find_package(rdtf) against that prefix only, and runs it on Box.gltf (it checks the mass
# properties). Also checks that the installed CMake files and headers name no file of the build or
# source tree (the library's debug information may).
# Usage: consumer_test.sh BUILD_DIR BOX_GLTF [CXX_COMPILER [CXX_FLAGS]]
#   (the build's compiler and sanitizer flags, which a sanitized librdtf.a needs)
set -euo pipefail

build=$(cd "$1" && pwd) box=$2 cxx=${3:-c++} cxx_flags=${4:-}
here=$(cd "$(dirname "$0")" && pwd)
source_dir=$(cd "$here/../.." && pwd)
fail() { echo "FAIL: $*" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmake --install "$build" --prefix "$work/prefix" --component dev >"$work/install.log"
echo "--- installed"; (cd "$work/prefix" && find . -type f | sort | grep -v '/include/rdtf/' ; ls include/rdtf | wc -l | sed 's/^/headers: /')
if grep -rl -e "$build" -e "$source_dir" "$work/prefix/lib/cmake" "$work/prefix/include"; then
  fail "the installed package files above name the build or source tree"
fi
for absent in urdf.h dynamics.h; do
  [[ ! -e $work/prefix/include/rdtf/$absent ]] || fail "include/rdtf/$absent installed without its library"
done

cmake -S "$here/consumer" -B "$work/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_CXX_FLAGS="$cxx_flags" -DCMAKE_EXE_LINKER_FLAGS="$cxx_flags" \
  -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF >"$work/configure.log" ||
  { cat "$work/configure.log"; fail "the consumer project did not configure"; }
grep -q "rdtf_DIR:PATH=$work/prefix/" "$work/consumer/CMakeCache.txt" ||
  fail "find_package(rdtf) found another rdtf: $(grep rdtf_DIR "$work/consumer/CMakeCache.txt")"
cmake --build "$work/consumer" -j2 >"$work/build.log" || { cat "$work/build.log"; fail "the consumer did not build"; }
"$work/consumer/rdtf_consumer" "$box"
echo "PASS: a project built against the installed librdtf computed Box.gltf's mass properties"
