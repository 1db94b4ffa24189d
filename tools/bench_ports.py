#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/bench_ports.py — the running emulator under load, for `make bench`.

Starts build/tools/urtwin (20 kHz physics, tick pacing, e-Series 500 Hz) twice — as a plain
process, then with --rt-priority 80 --lock-memory (SCHED_FIFO + mlockall, when permitted) —
connects 8 clients to port 30003 with build/tools/urt_rtprobe for --seconds (default 60), then
9 RTDE clients at 500 Hz (one measured, 8 others: all are timed) for as long, and reports:
  - the inter-packet period the clients see (p50/p99/p99.9/max over all 8 clients),
  - packets received and gaps in the controller timestamps,
  - physics overruns and missed periods the emulator counted over its whole run,
  - the emulator's resident memory (VmRSS) while serving them.
Nothing here asserts a time: the machine is shared and noisy.

    URT_BUILD=build .venv/bin/python tools/bench_ports.py --out build/bench_ports.json
"""

import argparse
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def vm_rss_kib(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return None


def chrt_prefix():
    """['chrt', '-f', '70'] when this process may run a SCHED_FIFO client, else []."""
    try:
        ok = subprocess.run(["chrt", "-f", "70", "true"], capture_output=True).returncode == 0
    except OSError:
        ok = False
    return ["chrt", "-f", "70"] if ok else []


def run_once(args, build, extra, client_prefix):
    """One emulator run under load; returns the result dict or None."""
    emu = subprocess.Popen(
        [str(build / "tools" / "urtwin"), "--config", str(ROOT / "config" / "ur5.yaml"),
         "--bind", args.host, "--port-offset", str(args.port_offset), "--pacing", "tick",
         "--rate", "20000", "--stats-every", "0", *extra],
        stderr=subprocess.PIPE, text=True)
    try:
        port = 30003 + args.port_offset
        t0 = time.monotonic()
        probe = None
        while time.monotonic() - t0 < 5:
            probe = subprocess.Popen(
                [*client_prefix, str(build / "tools" / "urt_rtprobe"), "--host", args.host, "--port", str(port),
                 "--clients", str(args.clients), "--seconds", str(args.seconds)],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            time.sleep(0.3)
            if probe.poll() is None:
                break
            probe = None
        if probe is None:
            print("bench_ports.py: urtwin did not open its ports", file=sys.stderr)
            return None
        time.sleep(min(5.0, args.seconds / 2))
        rss = vm_rss_kib(emu.pid)
        out, err = probe.communicate(timeout=args.seconds + 30)
        if probe.returncode != 0:
            print(f"bench_ports.py: urt_rtprobe failed: {err}", file=sys.stderr)
            return None
        seen = json.loads(out)
        # then RTDE: one client measured with 8 others connected (9 streams, all timed)
        rtde = subprocess.run(
            [*client_prefix, str(build / "tools" / "urt_rtprobe"), "--host", args.host, "--rtde",
             "--port", str(30004 + args.port_offset), "--clients", str(args.clients + 1),
             "--seconds", str(args.seconds)],
            capture_output=True, text=True, timeout=args.seconds + 30)
        if rtde.returncode != 0:
            print(f"bench_ports.py: urt_rtprobe --rtde failed: {rtde.stderr}", file=sys.stderr)
            return None
        seen_rtde = json.loads(rtde.stdout)
    finally:
        emu.send_signal(signal.SIGTERM)
        _, emu_err = emu.communicate(timeout=10)
    m = re.search(r"stopped after (\d+) ticks, (\d+) overruns, (\d+) missed periods", emu_err)
    return {
        "options": extra,
        "client": " ".join(client_prefix) or "SCHED_OTHER",
        "warnings": [l for l in emu_err.splitlines() if "warning" in l],
        "rt_clients": seen,
        "rtde_clients": seen_rtde,
        "emulator": {
            "ticks": int(m.group(1)) if m else None,
            "overruns": int(m.group(2)) if m else None,
            "missed_periods": int(m.group(3)) if m else None,
            "vm_rss_kib": rss,
        },
        "loadavg_end": list(os.getloadavg()),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default=os.environ.get("URT_BUILD", str(ROOT / "build")))
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--clients", type=int, default=8)
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port-offset", type=int, default=1000)
    ap.add_argument("--out", default="build/bench_ports.json")
    args = ap.parse_args(argv)
    build = Path(args.build)
    runs = {}
    # plain: everything SCHED_OTHER; then the emulator at SCHED_FIFO 80 (I/O thread 79) with
    # locked memory and the measuring clients at SCHED_FIFO 70, as a real-time client would be
    fifo = chrt_prefix()
    for name, extra, prefix in (("plain", [], []),
                                ("sched_fifo_mlock", ["--rt-priority", "80", "--lock-memory"], fifo)):
        res = run_once(args, build, extra, prefix)
        if res is None:
            return 1
        runs[name] = res
        seen, e, iv = res["rt_clients"], res["emulator"], res["rt_clients"]["interval_us"]
        print(f"[{name}] clients {res['client']}")
        print(f"[{name}] 30003 with {seen['clients']} clients for {args.seconds:.0f} s: "
              f"{seen['packets']} packets, {seen['timestamp_gaps']} timestamp gaps; inter-packet "
              f"period p50 {iv['p50']:.0f} us, p99 {iv['p99']:.0f} us, p99.9 {iv['p99_9']:.0f} us, "
              f"max {iv['max']:.0f} us")
        sr, ivr = res["rtde_clients"], res["rtde_clients"]["interval_us"]
        print(f"[{name}] RTDE 500 Hz with {sr['clients']} clients for {args.seconds:.0f} s: "
              f"{sr['packets']} packages, {sr['timestamp_gaps']} timestamp gaps; inter-package "
              f"period p50 {ivr['p50']:.0f} us, p99 {ivr['p99']:.0f} us, p99.9 "
              f"{ivr['p99_9']:.0f} us, max {ivr['max']:.0f} us")
        print(f"[{name}] urtwin: {e['ticks']} ticks, {e['overruns']} physics overruns, "
              f"{e['missed_periods']} missed periods; resident {e['vm_rss_kib'] / 1024:.1f} MiB"
              + "".join(f"; {w}" for w in res["warnings"]))
    out = {"settings": {"physics_hz": 20000, "controller_hz": 500, "pacing": "tick",
                        "seconds": args.seconds, "clients": args.clients}, "runs": runs}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(out, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
