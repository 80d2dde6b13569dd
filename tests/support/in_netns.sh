#!/usr/bin/env bash
# Runs a command in a new network namespace with only loopback, multicast enabled on it, so LCM's
# UDP multicast stays inside: unshare -n, lo up with multicast, a route for 224.0.0.0/4.
# Needs root (or user namespaces): CI and the test command run as root.
set -euo pipefail
exec unshare -n -- bash -c '
  ip link set lo up multicast on
  ip route add 224.0.0.0/4 dev lo
  exec "$@"' in_netns "$@"
