#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# tools/loopback_only.sh CMD [ARG]... — run CMD in a network namespace of its own whose only
# interface is the loopback: whatever it starts is reachable from nowhere but itself, even a
# server that listens on every interface (a local Ray's GCS, raylet and workers do: Ray 2.60 has
# no loopback-only listen option). Needs root, or unprivileged user namespaces (then it maps
# the caller to root inside). Exit status: CMD's, or 125 when no namespace can be made.
set -e
if [ "$#" -eq 0 ]; then
  echo "usage: tools/loopback_only.sh CMD [ARG]..." >&2
  exit 2
fi
if [ "$(id -u)" = 0 ]; then
  flags=-n
else
  flags=-rn
fi
if ! unshare $flags true 2>/dev/null; then
  echo "tools/loopback_only.sh: cannot create a network namespace (unshare $flags): run as root" >&2
  exit 125
fi
exec unshare $flags sh -c 'ip link set lo up && exec "$@"' loopback_only "$@"
