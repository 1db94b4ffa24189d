# SPDX-License-Identifier: Apache-2.0
"""A hostile client for the flood tests, run as its own process so that its work does not take
the test's readers' interpreter lock:

    python flood_client.py HOST ATTEMPTS HOLD PORT...

makes ATTEMPTS connection attempts to each PORT (round robin, each bounded by a 0.5 s timeout),
sends garbage on every connection it gets, keeps at most HOLD of them open per port (closing the
oldest first), prints one JSON line of counts, then holds what is open until a line arrives on
stdin (the test measures the emulator meanwhile), closes everything and exits. Loopback only."""

import collections
import json
import random
import socket
import sys
import time


def main():
    host, attempts, hold = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    ports = [int(p) for p in sys.argv[4:]]
    assert host.startswith("127."), "loopback only"
    rng = random.Random(13)
    held = {p: collections.deque() for p in ports}
    counts = {p: {"connected": 0, "failed": 0} for p in ports}
    t0 = time.monotonic()
    for _ in range(attempts):
        for p in ports:
            try:
                s = socket.create_connection((host, p), timeout=0.5)
            except OSError:
                counts[p]["failed"] += 1
                continue
            counts[p]["connected"] += 1
            s.setblocking(False)
            try:
                # garbage: binary, a half RTDE header, an overlong line, lines of noise
                junk = bytes(rng.getrandbits(8) for _ in range(rng.randint(16, 256)))
                s.send(rng.choice([junk, b"\xff\xffU" + junk, b"x" * 4000 + b"\n",
                                   b"fly away\n\x00\x01" + junk]))
            except OSError:
                pass  # already closed by the server (at its cap): that is fine
            held[p].append(s)
            if len(held[p]) > hold:
                held[p].popleft().close()
    took = time.monotonic() - t0
    print(json.dumps({"seconds": took, "held": sum(len(q) for q in held.values()),
                      "ports": {str(p): c for p, c in counts.items()}}), flush=True)
    sys.stdin.readline()
    for q in held.values():
        for s in q:
            s.close()


if __name__ == "__main__":
    main()
