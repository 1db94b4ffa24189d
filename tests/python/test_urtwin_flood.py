# SPDX-License-Identifier: Apache-2.0
"""Hostile load on every port of a real urtwin (net/server/emulator.c, tcp.c): 2000 connection
attempts per port with garbage on each, from a separate process, while a good ur_rtde receive
client, a clean-room RTDE client reading every package and a 30003 reader run.

Asserted (counts, not timings): the good RTDE stream has no off-period timestamp (every package
one period after the previous, ur_rtde's samples on the period grid and still connected), the
30003 reader's stream has no gap, resident memory stays under 64 MiB, every port accepts and
answers again once the flood is gone, and the connections beyond the caps or the descriptor
table were refused (counted by the emulator's log). The I/O thread's CPU share while the flood
holds its connections open is printed as a measurement (pytest -s): the machine is shared."""

import json
import os
import re
import socket
import subprocess
import sys
import threading
import time

import pytest

import built

from rtde_client import RtdeClient
from urtwin_proc import URTWIN, Emulator, RtReader

built.require(URTWIN)
import rtde_receive

PORTS = (30001, 30002, 30003, 30011, 30012, 30013, 30004, 29999)
PERIOD = 0.002
FLOOD = os.path.join(os.path.dirname(__file__), "flood_client.py")


def vm_rss_kib(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


def io_thread_cpu_s(pid):
    """CPU seconds (user + system) of the emulator's I/O thread, found by its name."""
    tck = os.sysconf("SC_CLK_TCK")
    for tid in os.listdir(f"/proc/{pid}/task"):
        with open(f"/proc/{pid}/task/{tid}/comm") as f:
            if f.read().strip() != "urt-io":
                continue
        with open(f"/proc/{pid}/task/{tid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / tck
    raise AssertionError("no thread named urt-io")


class Sampler(threading.Thread):
    """The emulator's largest resident memory, sampled every 50 ms."""

    def __init__(self, pid):
        super().__init__(daemon=True)
        self.pid, self.max_kib, self.stop = pid, 0, threading.Event()
        self.start()

    def run(self):
        while not self.stop.is_set():
            self.max_kib = max(self.max_kib, vm_rss_kib(self.pid))
            time.sleep(0.05)


class Readers:
    """The good clients: ur_rtde's receive interface (polled), a clean-room RTDE client that
    reads every package, and a 30003 reader; each on its own thread."""

    def __init__(self, host):
        self.stop = threading.Event()
        self.wire, self.rt, self.ur = [], [], []
        self.ur_rtde = rtde_receive.RTDEReceiveInterface(host, 500.0)
        self.rtde = RtdeClient(host).connect()
        self.rtde.negotiate_protocol_version(2)
        self.rtde.setup_outputs(["timestamp", "actual_q"], frequency=500)
        self.rtde.start()
        self.rt_reader = RtReader(host)
        self.threads = [threading.Thread(target=f, daemon=True)
                        for f in (self._read_rtde, self._read_rt, self._poll_ur_rtde)]
        for t in self.threads:
            t.start()

    def _read_rtde(self):
        while not self.stop.is_set():
            self.wire.append(self.rtde.receive().values["timestamp"])

    def _read_rt(self):
        while not self.stop.is_set():
            self.rt.append(self.rt_reader.read_decoded()["time"])

    def _poll_ur_rtde(self):
        while not self.stop.is_set():
            self.ur.append(self.ur_rtde.getTimestamp())
            time.sleep(0.01)

    def close(self):
        self.stop.set()
        for t in self.threads:
            t.join(timeout=3)
        self.connected = self.ur_rtde.isConnected()
        self.ur_rtde.disconnect()
        self.rtde.close()
        self.rt_reader.close()

    @staticmethod
    def off_period(times):
        return sum(1 for a, b in zip(times, times[1:]) if round((b - a) / PERIOD) != 1)


def answers(host, port, timeout=1.0):
    """True when a fresh connection to the port gets what that port sends first."""
    try:
        with socket.create_connection((host, port), timeout=timeout) as s:
            if port == 30004:
                s.sendall(bytes([0, 5, ord("V"), 0, 2]))  # request protocol version 2
            data = s.recv(64)
            if port == 29999:
                return data.startswith(b"Connected: Universal Robots Dashboard Server")
            if port == 30004:
                return len(data) >= 4 and data[2] == ord("V") and data[3] == 1
            return len(data) >= 4
    except OSError:
        return False


def all_accept_again(host, deadline_s=10.0):
    t_end = time.monotonic() + deadline_s
    pending = set(PORTS)
    while pending and time.monotonic() < t_end:
        pending = {p for p in pending if not answers(host, p)}
        if pending:
            time.sleep(0.1)
    return sorted(pending)


@pytest.mark.parametrize("nofile,hold", [
    (1024, 200),  # the 1024-descriptor limit: the caps refuse (8 × 32 < 1024)
    (128, 200),   # a table too small for the caps: accept meets EMFILE, the reserve drains it
])
def test_flood_on_every_port_leaves_the_good_clients_and_memory_intact(nofile, hold):
    with Emulator(nofile=nofile) as emu:
        readers = Readers(emu.host)
        sampler = Sampler(emu.proc.pid)
        time.sleep(0.5)
        flood = subprocess.Popen([sys.executable, FLOOD, emu.host, "2000", str(hold),
                                  *map(str, PORTS)], stdin=subprocess.PIPE,
                                 stdout=subprocess.PIPE, text=True)
        try:
            summary = json.loads(flood.stdout.readline())
            # settled: no new attempts, the flood's connections still open
            time.sleep(1.0)
            cpu0, t0 = io_thread_cpu_s(emu.proc.pid), time.monotonic()
            time.sleep(3.0)
            io_share = (io_thread_cpu_s(emu.proc.pid) - cpu0) / (time.monotonic() - t0)
            rss_held = vm_rss_kib(emu.proc.pid)
        finally:
            flood.communicate("release\n", timeout=30)
        not_again = all_accept_again(emu.host)
        time.sleep(1.0)
        readers.close()
        sampler.stop.set()
        sampler.join()
        alive = emu.alive()
    log = emu.err.decode(errors="replace")
    refused_cap = sum(int(n) for n in re.findall(r"(\d+) connection\(s\) refused, \d+ clients", log))
    refused_fds = sum(int(n) for n in re.findall(r"(\d+) connection\(s\) refused: no file", log))
    connected = sum(c["connected"] for c in summary["ports"].values())
    failed = sum(c["failed"] for c in summary["ports"].values())
    wire_off, rt_off = Readers.off_period(readers.wire), Readers.off_period(readers.rt)
    ur_off_grid = sum(1 for t in readers.ur if abs(t / PERIOD - round(t / PERIOD)) > 1e-6)
    ur_advanced = len(readers.ur) > 1 and readers.ur[-1] - readers.ur[0] > 5.0
    print(f"\nnofile {nofile}: flood {connected} connections, {failed} attempts unanswered in "
          f"{summary['seconds']:.1f} s, {summary['held']} held; urtwin refused {refused_cap} at "
          f"the caps, {refused_fds} for descriptors; I/O thread {100 * io_share:.1f} % of a core "
          f"over 3 s with the flood held; resident max {sampler.max_kib / 1024:.1f} MiB "
          f"(held {rss_held / 1024:.1f} MiB); good RTDE {len(readers.wire)} packages, "
          f"{wire_off} off-period; 30003 {len(readers.rt)} packets, {rt_off} off-period; "
          f"ur_rtde {len(readers.ur)} samples, {ur_off_grid} off the grid, connected "
          f"{readers.connected}; ports not accepting again: {not_again}")
    assert alive
    assert connected + failed == 2000 * len(PORTS)
    assert refused_cap + refused_fds > 0  # the flood did meet the limits
    if nofile == 128:
        assert refused_fds > 0
    assert wire_off == 0 and len(readers.wire) > 2000
    assert rt_off == 0 and len(readers.rt) > 2000
    assert ur_off_grid == 0 and ur_advanced and readers.connected
    assert sampler.max_kib < 64 * 1024
    assert not_again == []
