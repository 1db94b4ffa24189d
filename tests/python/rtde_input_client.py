# SPDX-License-Identifier: Apache-2.0
"""An RTDE client that floods inputs, run as its own process (its pacing loop must not take the
test's interpreter lock):

    python rtde_input_client.py HOST RATE SECONDS

sets up an input recipe (speed slider and standard digital outputs), then sends input packages
at RATE per second for SECONDS (on an absolute schedule, catching up in bursts when it wakes
late), each with the next digital-output pattern, and prints one JSON line: packages sent, the
rate reached, and the last pattern sent. Loopback only."""

import json
import socket
import sys
import time

from rtde_client import RtdeClient, encode_inputs


def main():
    host, rate, seconds = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
    assert host.startswith("127."), "loopback only"
    names = ["speed_slider_mask", "speed_slider_fraction", "standard_digital_output_mask",
             "standard_digital_output"]
    with RtdeClient(host).connect() as c:
        c.negotiate_protocol_version(2)
        recipe = c.setup_inputs(names)
        sock = c.sock
        sock.setblocking(False)
        sent, k, pattern = 0, 0, 0
        t0 = time.monotonic()
        while True:
            now = time.monotonic()
            if now - t0 >= seconds:
                break
            due = int((now - t0) * rate)
            burst = bytearray()
            while k < due:
                pattern = k % 251  # every bit pattern of the 8 outputs, in turn
                burst += encode_inputs(recipe.id, recipe.types,
                                       [1, 0.5 + 0.5 * ((k // 1000) % 2), 0xFF, pattern])
                k += 1
            if burst:
                sock.setblocking(True)
                sock.sendall(bytes(burst))
                sock.setblocking(False)
                sent = k
            try:
                sock.recv(65536)  # whatever the server says (nothing, unless refused): drained
            except (BlockingIOError, socket.timeout):
                pass
            time.sleep(0.0005)
        took = time.monotonic() - t0
        time.sleep(0.1)
    print(json.dumps({"sent": sent, "seconds": took, "rate": sent / took, "last_pattern": pattern,
                      "last_slider": 0.5 + 0.5 * (((k - 1) // 1000) % 2)}), flush=True)


if __name__ == "__main__":
    main()
