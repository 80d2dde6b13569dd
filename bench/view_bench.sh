#!/usr/bin/env bash
# rdtf-view's benchmarks (docs/benchmarks.md, "rdtf-view"): save -> pixels latency, frame rate
# under SwiftShader, memory with 100 models. Runs rdtfd, rdtf-view and headless chromium in a
# network namespace of its own (tests/support/in_netns.sh), so LCM stays on its loopback.
# Usage: bash bench/view_bench.sh [--saves N] [--big] [--models N] [--no-validate] [--msaa on|off] [--after-settle]
#        [--robot NAME] [--web-dir DIR]   (after building rdtfd and rdtf-view in build/)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
exec tests/support/in_netns.sh node tools/view-test/bench_view.mjs "$PWD/build" "$PWD" "$@"
