#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/bench_urcl_vm.py — the URScript VM's cost per controller tick while it runs URCL's
external-control script in SERVOJ mode, and the physics thread's overruns beside it, for
`make bench` (issue 9).

Two runs of build/tools/urtwin (e-Series 5.19 on 127.0.0.2, 20 kHz physics, 500 Hz ticks), each
--seconds long (default 20): one idle, one driven by tests/urcl/ros2_driver_pattern (URCL's
UrDriver, headless, servoj at the 500 Hz RTDE cadence: the script as URCL uploads it, run by the
VM). At each exit urtwin prints the VM's CPU time per tick (net/include/urt/net/urscript.h:
urt_runner_tick_stats) and the physics thread's overruns and time per period; this reports both
runs side by side. Runs in a network namespace with only a loopback (tools/loopback_only.sh):
URCL's servers bind 0.0.0.0 on fixed ports. Nothing here asserts a time.

Needs URCL built (`make urcl`, from ../shared); without it, prints SKIPPED and writes that.

    .venv/bin/python tools/bench_urcl_vm.py --out build/bench_urcl_vm.json
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
sys.path.insert(0, str(ROOT / "tests" / "urcl"))
from urcl_urtwin import realtime_permitted, wait_port  # noqa: E402  (the URCL runner's, the same start)
HOST = "127.0.0.2"
URCL_DIR = Path("shared") / "clients" / "Universal_Robots_Client_Library-2.14.0"

VM = re.compile(r"urscript per tick: cpu p50 ([\d.]+) us p99 ([\d.]+) us p99\.9 ([\d.]+) us "
                r"max ([\d.]+) us over (\d+) ticks")
STOPPED = re.compile(r"stopped after (\d+) ticks, (\d+) overruns, (\d+) missed periods")
PHYS = re.compile(r"physics per period: wall p50 (\d+) us p99 (\d+) us p99\.9 (\d+) us max (\d+) us")


def urcl_src():
    for up in (ROOT.parent, ROOT.parent.parent):
        if (up / URCL_DIR).is_dir():
            return up / URCL_DIR
    return None


def run(build, seconds, driver=None, script=None):
    """One urtwin run; with driver, the ROS 2 pattern drives it for `seconds` of servoj."""
    args = [str(build / "tools" / "urtwin"), "--config", str(ROOT / "config" / "ur5.yaml"),
            "--bind", HOST, "--controller-version", "5.19", "--stats-every", "0",
            "--set", "sensors.noise=false"]
    # as in the URCL runs (tests/urcl/run_urcl.py): urtwin real-time where permitted, and the
    # client's control loop at SCHED_FIFO 50 as ros2_control runs it on a real robot (its 10 ms
    # receive timeout ends the program when the client is descheduled that long)
    rt = realtime_permitted()
    if rt:
        args += ["--rt-priority", "80"]
    emu = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        if not wait_port(HOST, 30004, 10.0):
            raise SystemExit("urtwin did not open its ports")
        client, client_rc = "", None
        if driver:
            r = subprocess.run([*(["chrt", "-f", "50"] if rt else []), str(driver), HOST,
                                str(script), str(seconds)], capture_output=True, text=True,
                               timeout=seconds * 3 + 60)
            client = r.stdout + r.stderr
            client_rc = r.returncode
        else:
            time.sleep(seconds)
    finally:
        emu.send_signal(signal.SIGINT)
        err = emu.communicate(timeout=30)[1]
    vm, st, ph = VM.search(err), STOPPED.search(err), PHYS.search(err)
    if not (vm and st and ph):
        raise SystemExit(f"urtwin's exit figures not found:\n{err[-2000:]}")
    out = {"ticks": int(st.group(1)), "overruns": int(st.group(2)),
           "missed_periods": int(st.group(3)),
           "physics_wall_us": dict(zip(("p50", "p99", "p99.9", "max"), map(int, ph.groups()))),
           "vm_cpu_us": dict(zip(("p50", "p99", "p99.9", "max"), map(float, vm.groups()[:4]))),
           "vm_ticks": int(vm.group(5))}
    out["realtime"] = rt
    if driver:
        out["client_exit"] = client_rc
        out["client"] = [l for l in client.splitlines() if re.match(r"(servo|tracking|ros2_)", l)]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "build" / "bench_urcl_vm.json"))
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    build = Path(os.environ.get("URT_BUILD", ROOT / "build"))
    driver = build / "urcl" / "ours" / "ros2_driver_pattern"
    src = urcl_src()
    if src is None or not driver.exists():
        msg = ("SKIPPED: URCL is not built (../shared absent, or run make urcl): the VM's cost "
               "under URCL's script was not measured")
        print(msg)
        Path(a.out).write_text(json.dumps({"skipped": msg}, indent=1))
        return 0
    if not a.inside:
        # again inside a namespace with only a loopback
        cmd = [str(ROOT / "tools" / "loopback_only.sh"), sys.executable, __file__, "--inside",
               "--out", a.out, "--seconds", str(a.seconds)]
        return subprocess.run(cmd, env={**os.environ, "URT_BUILD": str(build)}).returncode
    idle = run(build, a.seconds)
    servo = run(build, a.seconds, driver, src / "resources" / "external_control.urscript")
    res = {"tool": "tools/bench_urcl_vm.py", "period_us": 2000, "seconds": a.seconds,
           "load_average": os.getloadavg()[0], "idle": idle, "urcl_servoj": servo}
    Path(a.out).write_text(json.dumps(res, indent=1))
    v = servo["vm_cpu_us"]
    print(f"URScript VM per tick running URCL's external_control.urscript in SERVOJ mode "
          f"(ros2_driver_pattern, {servo['vm_ticks']} ticks): cpu median {v['p50']:.1f} us, "
          f"p99 {v['p99']:.1f} us, max {v['max']:.1f} us of a 2000 us period")
    for name, r in (("idle", idle), ("URCL servoj", servo)):
        p = r["physics_wall_us"]
        print(f"physics, {name}: {r['overruns']} overruns in {r['ticks']} ticks, missed periods "
              f"{r['missed_periods']}; wall p50 {p['p50']} us p99 {p['p99']} us max {p['max']} us")
    if servo["client_exit"] != 0:
        print(f"the URCL client failed (exit {servo['client_exit']}): {servo['client'][-1:]}; "
              "the VM figures cover the ticks it ran")
    print(f"load average {res['load_average']:.1f}; real-time priorities "
          f"{'on' if servo['realtime'] else 'off (not permitted)'}; {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
