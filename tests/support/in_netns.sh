#!/usr/bin/env bash
# Runs a command in a new network namespace with only loopback, multicast enabled on it, so LCM's
# UDP multicast stays inside: unshare -n, lo up with multicast, a route for 224.0.0.0/4.
# Also a private mount namespace (-m, propagation private): a test may mount a small tmpfs (a
# disk that fills up) and nothing outside sees it; it goes away with the namespace.
# And a PID namespace (--pid --fork --kill-child, its own /proc): when ctest stops a test at its
# timeout it kills unshare, the kernel then kills the namespace's first process and with it every
# process the test started (rdtfd, rdtf-view, chromium). Before, those outlived the test, kept
# simulating and drawing, and slowed every test after them. bash stays the namespace's first
# process (no exec) to reap the processes orphaned inside it.
# Needs root (or user namespaces): CI and the test command run as root.
set -euo pipefail
exec unshare -n -m --propagation private --pid --fork --kill-child --mount-proc -- bash -c '
  ip link set lo up multicast on
  ip route add 224.0.0.0/4 dev lo
  "$@"
  exit $?' in_netns "$@"
