#!/usr/bin/env bash
# The main job: installs the dependencies, builds, and runs rdtfd on the bundled example models
# (examples/models) with LCM's default URL, and rdtf-view beside it (the models in a browser at
# the URL it prints), until Ctrl-C. Outputs go to build/rdtf-output.
# Usage (from any folder): `bash scripts/run.sh` as root, or `sudo bash scripts/run.sh`.
# Extra arguments go to rdtfd, e.g. `bash scripts/run.sh --settle-ms 100`.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
targets=(rdtfd rdtf rdtf-echo rdtf-pd-controller rdtf-view)
# The jar that lets lcm-spy decode every channel exists where javac does (lcmtypes/CMakeLists.txt).
if cmake --build build --target help | grep -q '^rdtf_lcmtypes_jar: '; then targets+=(rdtf_lcmtypes_jar); fi
cmake --build build -j2 --target "${targets[@]}"
# rdtf-view (the models in a browser) runs beside rdtfd and stops with it.
build/clients/view/rdtf-view &
view_pid=$!
trap 'kill "$view_pid" 2>/dev/null || true' EXIT
echo "run.sh: rdtfd is watching examples/models; open http://127.0.0.1:8765/ (rdtf-view) to see them."
echo "run.sh: in another shell try:"
echo "  build/clients/echo/rdtf-echo --omit-documents      # every message as a JSON line"
echo "  scripts/rdtf-spy                                     # lcm-spy decoding every channel, if a display is available"
build/daemon/rdtfd --config config/rdtfd.json "$@"
