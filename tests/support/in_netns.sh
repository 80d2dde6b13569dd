#!/usr/bin/env bash
# Runs a command in a new network namespace with only loopback, multicast enabled on it, so LCM's
# UDP multicast stays inside: unshare -n, lo up with multicast, a route for 224.0.0.0/4.
# Also a private mount namespace (-m, propagation private): a test may mount a small tmpfs (a
# disk that fills up) and nothing outside sees it; it goes away with the namespace.
# Needs root (or user namespaces): CI and the test command run as root.
set -euo pipefail
exec unshare -n -m --propagation private -- bash -c '
  ip link set lo up multicast on
  ip route add 224.0.0.0/4 dev lo
  exec "$@"' in_netns "$@"
