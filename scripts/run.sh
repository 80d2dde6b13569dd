#!/usr/bin/env bash
# The main job: installs the dependencies, builds, and runs rdtfd on the bundled example models
# (examples/models) with LCM's default URL, until Ctrl-C. Outputs go to build/rdtf-output.
# Usage (from any folder): `bash scripts/run.sh` as root, or `sudo bash scripts/run.sh`.
# Extra arguments go to rdtfd, e.g. `bash scripts/run.sh --settle-ms 100`.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
targets=(rdtfd rdtf rdtf-echo rdtf-pd-controller)
# The jar that lets lcm-spy decode every channel exists where javac does (lcmtypes/CMakeLists.txt).
if cmake --build build --target help | grep -q '^rdtf_lcmtypes_jar: '; then targets+=(rdtf_lcmtypes_jar); fi
cmake --build build -j2 --target "${targets[@]}"
echo "run.sh: rdtfd is watching examples/models; in another shell try:"
echo "  build/clients/echo/rdtf-echo --omit-documents      # every message as a JSON line"
echo "  CLASSPATH=build/lcmtypes/rdtf_lcmtypes.jar lcm-spy   # if a display is available"
exec build/daemon/rdtfd --config config/rdtfd.json "$@"
