#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/bench_physics_worst.py — the physics thread's worst time per controller period, for
`make bench`.

Starts build/tools/urtwin (20 kHz physics, tick pacing, e-Series 500 Hz) twice for --seconds
each (default 20): once idle, once under what costs the physics thread most:
  - a URScript program looping movel (the linear motion's inverse kinematics runs on the
    physics thread, every tick),
  - RTDE inputs at 10 kHz from another process (tests/python/rtde_input_client.py) and
    dashboard queries as fast as they are answered (every command goes through the rings the
    physics thread drains),
  - a refined step (urt_step's path for an implausible step: the macro step undone and redone
    as n_sub fine steps, about 11 steps' work) in every controller period. Healthy runs take
    that path rarely or never (session 13's loaded runs: 0), so it is forced with
    simulation.refine_every=40 (every 40th of the 20 kHz steps: one per 2 ms period; counted:
    "refined steps").
It then reads the emulator's own figures at its exit (urtwin prints the per-period quantiles of
its physics thread, wall clock and thread CPU time: core/exec_hist.h) and reports p50/p99/
p99.9/max, each also as a share of the 2 ms period. The wall figures include the time another
process held the core (the machine is shared); the CPU figures are the thread's own work.
As root (or --rt on) both runs are repeated with urtwin as deployed for hard real time
(--rt-priority 80 --lock-memory): no process of this machine then preempts the physics thread,
so its wall figures are its own work plus what the hypervisor takes (a VM's steal shows there
and nowhere else; the thread-CPU figures of a Firecracker guest have been seen above the wall
ones and are not a bound). Nothing here asserts a time.

    URT_BUILD=build .venv/bin/python tools/bench_physics_worst.py --out build/bench_physics_worst.json
"""

import argparse
import json
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "python"))
from urtwin_proc import RtReader  # noqa: E402  (the 30003 decoder the tests use)
FLOOD = ROOT / "tests" / "python" / "rtde_input_client.py"

# moves the TCP 15 cm along base x and back, forever: each movel's IK runs on the physics thread
MOVEL_LOOP = """def bench_movel():
  p0 = get_actual_tcp_pose()
  p1 = pose_add(p0, p[0.15, 0, 0, 0, 0, 0])
  while True:
    movel(p1, a=1.2, v=0.4)
    movel(p0, a=1.2, v=0.4)
  end
end
"""

# one forced refined step per 2 ms controller period at 20 kHz (config/README.md)
REFINE_EVERY = 40

LINE = re.compile(
    r"physics per period: wall p50 (\d+) us p99 (\d+) us p99\.9 (\d+) us max (\d+) us "
    r"\(max [\d.]+ % of (\d+) us\); cpu p50 (\d+) us p99 (\d+) us p99\.9 (\d+) us max (\d+) us "
    r"\(max [\d.]+ %\); refined steps (\d+); periods at half the period or more: wall (\d+) "
    r"cpu (\d+) of (\d+)")


def wait_port(host, port, timeout=5.0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        try:
            socket.create_connection((host, port), timeout=0.5).close()
            return True
        except OSError:
            time.sleep(0.05)
    return False


def dashboard_flood(host, seconds):
    """Dashboard queries back to back for `seconds`; returns how many were answered."""
    n = 0
    with socket.create_connection((host, 29999), timeout=2) as s:
        f = s.makefile("rb")
        f.readline()  # the greeting
        t0 = time.monotonic()
        while time.monotonic() - t0 < seconds:
            s.sendall(b"robotmode\n")
            if not f.readline():
                break
            n += 1
    return n


def tcp_x_travel(host, stop, out):
    """Range of the actual TCP x [m] on 30003 until `stop` is set: shows that movel ran."""
    lo, hi = float("inf"), float("-inf")
    with RtReader(host) as rt:
        while not stop.is_set():
            x = rt.read_decoded()["tool_vector_actual"][0]
            lo, hi = min(lo, x), max(hi, x)
    out.append(hi - lo)


def steal_seconds():
    """The machine's stolen time so far (/proc/stat: time the hypervisor ran something else
    while a vCPU had work), summed over CPUs [s]; None where it is not reported."""
    try:
        fields = Path("/proc/stat").read_text().split("\n", 1)[0].split()
        return int(fields[8]) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return None


def run_once(build, host, seconds, loaded, rt):
    emu = subprocess.Popen(
        [str(build / "tools" / "urtwin"), "--config", str(ROOT / "config" / "ur5.yaml"),
         "--bind", host, "--pacing", "tick", "--rate", "20000", "--stats-every", "0"]
        + (["--set", f"simulation.refine_every={REFINE_EVERY}"] if loaded else [])
        + (["--rt-priority", "80", "--lock-memory"] if rt else []),
        stderr=subprocess.PIPE, text=True)
    flood = None
    answered = 0
    steal0 = steal_seconds()
    try:
        if not all(wait_port(host, p) for p in (29999, 30002, 30004)):
            raise RuntimeError("urtwin did not open its ports")
        stop, travel = threading.Event(), []
        watcher = threading.Thread(target=tcp_x_travel, args=(host, stop, travel))
        watcher.start()
        if loaded:
            with socket.create_connection((host, 30002), timeout=2) as s:
                s.sendall(MOVEL_LOOP.encode())
            flood = subprocess.Popen([sys.executable, str(FLOOD), host, "10000", str(seconds)],
                                     stdout=subprocess.PIPE, text=True, cwd=FLOOD.parent)
            answered = dashboard_flood(host, seconds)
            sent = json.loads(flood.communicate(timeout=seconds + 30)[0])
        else:
            time.sleep(seconds)
            sent = None
        stop.set()
        watcher.join(timeout=5)
    finally:
        if flood and flood.poll() is None:
            flood.kill()
        emu.send_signal(signal.SIGINT)
        try:
            _, err = emu.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            emu.kill()
            _, err = emu.communicate()
    steal1 = steal_seconds()
    m = LINE.findall(err)
    if not m:
        raise RuntimeError("urtwin printed no per-period figures:\n" + err[-2000:])
    v = [int(x) for x in m[-1]]
    period_us = v[4]
    res = {"period_us": period_us,
           "wall_us": dict(zip(("p50", "p99", "p999", "max"), v[0:4])),
           "cpu_us": dict(zip(("p50", "p99", "p999", "max"), v[5:9])),
           "refined_steps": v[9], "tcp_x_travel_m": travel[0] if travel else None,
           "periods": v[12], "wall_over_half": v[10], "cpu_over_half": v[11],
           "steal_s": None if steal0 is None or steal1 is None else steal1 - steal0}
    res["wall_share"] = {k: x / period_us for k, x in res["wall_us"].items()}
    res["cpu_share"] = {k: x / period_us for k, x in res["cpu_us"].items()}
    if loaded:
        res["rtde_inputs_per_s"] = sent["rate"] if sent else None
        res["dashboard_answered"] = answered
        res["script_errors"] = re.findall(r"urtwin: .*(?:error|Error).*", err)[:5]
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--host", default="127.0.0.78")
    ap.add_argument("--out", help="write the results as JSON")
    ap.add_argument("--rt", choices=("auto", "on", "off"), default="auto",
                    help="also run urtwin as deployed for hard real time (--rt-priority 80 "
                         "--lock-memory; needs root): auto = when root")
    a = ap.parse_args(argv)
    assert a.host.startswith("127."), "loopback only"
    build = Path(os.environ.get("URT_BUILD", ROOT / "build"))
    results = {"seconds": a.seconds, "load_average": os.getloadavg()}
    rt = a.rt == "on" or (a.rt == "auto" and os.geteuid() == 0)
    cases = [("idle", False, False), ("loaded", True, False)]
    if rt:  # the physics thread at SCHED_FIFO: no other process of this machine preempts it
        cases += [("idle_rt", False, True), ("loaded_rt", True, True)]
    for name, loaded, rt_case in cases:
        r = run_once(build, a.host, a.seconds, loaded, rt_case)
        results[name] = r
        extra = ""
        stolen = "n/a" if r["steal_s"] is None else f"{r['steal_s']:.2f} s"
        if loaded:
            extra = (f"; RTDE inputs {r['rtde_inputs_per_s']:.0f}/s, dashboard "
                     f"{r['dashboard_answered']} answered")
        print(f"[{name}] physics thread per {r['period_us']} us period: "
              f"cpu p50 {r['cpu_us']['p50']} p99 {r['cpu_us']['p99']} p99.9 {r['cpu_us']['p999']} "
              f"max {r['cpu_us']['max']} us (max {100 * r['cpu_share']['max']:.1f} %); "
              f"wall p99 {r['wall_us']['p99']} max {r['wall_us']['max']} us "
              f"(max {100 * r['wall_share']['max']:.1f} %); refined steps "
              f"{r['refined_steps']}; periods at >= 50 %: wall {r['wall_over_half']} cpu "
              f"{r['cpu_over_half']} of {r['periods']}; TCP x travel "
              f"{r['tcp_x_travel_m']:.3f} m; stolen {stolen}{extra}")
        for e in r.get("script_errors") or []:
            print(f"[{name}] {e}")
    print(f"load average during the runs: {results['load_average'][0]:.1f}")
    if a.out:
        Path(a.out).write_text(json.dumps(results, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
