#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# tools/lcm_loopback_route.sh — make LCM's udpm multicast work on a host with no route for it
# (no default route, e.g. a container with only lo), as LCM's docs describe:
#   ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo
# Does nothing when a route for the group already exists (a default route via a MULTICAST
# interface is enough: with ttl=0 the kernel loops packets back and never puts them on the
# wire). Changes routes only as root; otherwise prints the commands and exits 1.
#   usage: tools/lcm_loopback_route.sh [group]      (default 239.255.76.67)
set -eu
group=${1:-239.255.76.67}

if ip route get "$group" >/dev/null 2>&1; then
  echo "lcm: multicast route for $group exists: $(ip route get "$group" | head -n 1)"
  exit 0
fi

if [ "$(id -u)" != 0 ]; then
  echo "lcm: no multicast route for $group; as root run:" >&2
  echo "  ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo" >&2
  exit 1
fi

ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
echo "lcm: added 224.0.0.0/4 dev lo (multicast on lo)"
