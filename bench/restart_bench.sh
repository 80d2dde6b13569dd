#!/usr/bin/env bash
# rdtfd started over a tree of models, timed from launch to its Nth "converted" log line (each
# model's revision applied and its messages queued), VmRSS then and 3 s later; then a clean stop
# (SIGINT). Run it twice on the same output folder: the second start is a restart over unchanged
# models (result cache, docs/daemon.md). Run inside a network namespace of its own:
#   tests/support/in_netns.sh bench/restart_bench.sh RDTFD MODELS OUTPUT COUNT [rdtfd options...]
set -euo pipefail
rdtfd=$1 models=$2 out=$3 count=$4
shift 4
rm -f "$out.log"  # A log of an earlier run must not count.
start=$(date +%s.%N)
"$rdtfd" -w "$models" -o "$out" --republish-ms 0 "$@" 2> "$out.log" &
pid=$!
for _ in $(seq 1 6000); do
  [ -f "$out.log" ] && [ "$(grep -c "converted " "$out.log")" -ge "$count" ] && break
  sleep 0.1
done
end=$(date +%s.%N)
rss=$(grep VmRSS /proc/$pid/status)
sleep 3
echo "$*: $(echo "$end - $start" | bc) s; from the cache $(grep -c 'from the result cache' "$out.log");" \
     "$rss; 3 s later $(grep -E 'VmRSS|VmHWM' /proc/$pid/status | tr '\n' ' ')"
grep -E "leftovers|stopped cleanly|result cache /|rescan \(start" "$out.log" || true
kill -INT $pid
wait $pid
