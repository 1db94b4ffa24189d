#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/bench_dds.py — the DDS bridge under load, for `make bench`.

Runs build/tools/urtwin (20 kHz physics, tick pacing, e-Series 500 Hz; --rt-priority 80 when
permitted, as for timing work) twice in one run, each for --seconds (default 20), with 8
subscriber processes (build/tools/urt_ddsprobe, C, one reader of rt/joint_states each) started
first: without --dds (the probes idle), then with --dds. Reports:
  - latency from controller tick to subscriber, p50/p99/max per probe and the median of those:
    the wall time the probe took the sample minus its DDS source timestamp, which urtwin sets
    to the wall time its physics thread published the tick (CLOCK_REALTIME, same host),
  - samples each probe received and gaps in their header stamps (one stamp per tick),
  - physics overruns and missed periods the emulator counted, DDS off vs on.
Everything on config/cyclonedds-lo.xml (loopback) in a random domain. Nothing here asserts a
time: the machine is shared and noisy.

    URT_BUILD=build .venv/bin/python tools/bench_dds.py --out build/bench_dds.json
"""

import argparse
import json
import os
import random
import re
import signal
import statistics
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CONFIG = ROOT / "config" / "cyclonedds-lo.xml"


def rt_args():
    try:
        ok = subprocess.run(["chrt", "-f", "1", "true"], capture_output=True).returncode == 0
    except OSError:
        ok = False
    return ["--rt-priority", "80"] if ok else []


def run(build, host, seconds, domain, dds, n_probes):
    args = [str(build / "tools" / "urtwin"), "--config", str(ROOT / "config" / "ur5.yaml"),
            "--bind", host, "--pacing", "tick", "--rate", "20000", "--stats-every", "0",
            *rt_args()]
    if dds:
        args += ["--dds", "--dds-domain", str(domain), "--dds-config", str(CONFIG)]
    probes = [subprocess.Popen([str(build / "tools" / "urt_ddsprobe"), str(domain), str(CONFIG),
                                str(seconds + 2.0)], stdout=subprocess.PIPE, text=True)
              for _ in range(n_probes)]
    time.sleep(0.5)
    emu = subprocess.Popen(args, stderr=subprocess.PIPE, text=True, cwd=ROOT)
    try:
        time.sleep(seconds)
    finally:
        emu.send_signal(signal.SIGTERM)
        _, err = emu.communicate(timeout=20)
        results = []
        for p in probes:
            out, _ = p.communicate(timeout=30)
            results.append(json.loads(out.strip().splitlines()[-1]))
    m = re.search(r"stopped after (\d+) ticks, (\d+) overruns, (\d+) missed periods", err)
    d = re.findall(r"urtwin: dds: .*", err)
    got = [r for r in results if r["samples"] > 0]
    return {
        "dds": dds, "probes": n_probes, "rt_priority": bool(rt_args()),
        "ticks": int(m.group(1)) if m else None,
        "overruns": int(m.group(2)) if m else None,
        "missed_periods": int(m.group(3)) if m else None,
        "per_probe": results,
        "latency_us": {k: statistics.median(r[k] for r in got) for k in ("p50_us", "p99_us")}
        if got else None,
        "latency_max_us": max(r["max_us"] for r in got) if got else None,
        "dds_stats": d[-1] if d else None,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--probes", type=int, default=8)
    ap.add_argument("--host", default="127.0.0.61")
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    build = Path(os.environ.get("URT_BUILD", ROOT / "build"))
    domain = random.randint(1, 200)
    off = run(build, a.host, a.seconds, domain, False, a.probes)
    on = run(build, a.host, a.seconds, domain, True, a.probes)
    for name, r in (("DDS off", off), ("DDS on", on)):
        line = (f"[{name}] urtwin: {r['ticks']} ticks, {r['overruns']} physics overruns, "
                f"{r['missed_periods']} missed periods, {r['probes']} subscribers")
        if r["latency_us"]:
            lu = r["latency_us"]
            line += (f"; samples {[p['samples'] for p in r['per_probe']]}, gaps "
                     f"{[p['gaps'] for p in r['per_probe']]}; tick->subscriber latency "
                     f"p50 {lu['p50_us']:.0f} us, p99 {lu['p99_us']:.0f} us (medians over the "
                     f"subscribers), max {r['latency_max_us']:.0f} us")
        print(line)
    if a.out:
        Path(a.out).write_text(json.dumps({"off": off, "on": on}, indent=2))


if __name__ == "__main__":
    main()
