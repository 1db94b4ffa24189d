#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/bench_dataset.py — dataset throughput for `make bench` (issue 11): simulated seconds
per wall second of a sweep (python -m urtwin.dataset: 20 kHz physics, 500 Hz output, Parquet
out) per worker, against the bare urt_step rate measured in the same run (urt_bench, 20 kHz,
healthy), and a local Ray with 2 workers against 1.

The sweep: the excitation, 4 seeds, healthy and gear stiffness -50 % on the shoulder, 10 s each
(8 runs, 80 simulated s). The sweep's wall time runs from after Ray's start-up to the last
run's return, before Ray's shutdown (both reported apart: each is paid once, whatever the
sweep's size). The 1-worker figure per worker is the sweep's simulated seconds over its wall
time; the 2-worker one is the same over twice its wall time; the per-run one is a run's
simulated seconds over its own wall time (model, stepping, Parquet). The bare rate is measured
before and after the sweeps and the faster one is used. The sweep is also set against its own
stepping loops (urt_step and the set-point on these trajectories and faults, rows at 500 Hz):
what the dataset machinery costs around the physics.
Ray runs inside tools/loopback_only.sh (a network namespace with only `lo`), as in
`make dataset-demo`. Nothing here asserts a rate.

    URT_BUILD=build .venv/bin/python tools/bench_dataset.py --out build/bench_dataset.json
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

SWEEP = """sweep: bench
config: {config}
duration: {duration}
output_rate: 500
rate: 20000
trajectories: [excitation]
seeds: {{start: 1, count: {seeds}}}
splits: {{train: 0.5, test: 0.5}}
faults:
  - healthy
  - name: gear_stiffness
    faults: [{{class: gear_stiffness, joint: 1, severity: 0.5, unit: "1",
              profile: {{kind: step, onset: 1.0}}}}]
"""


def bare_rate(build):
    """urt_step's real-time factor at 20 kHz, healthy, moving set-point (urt_bench's median)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "urt_bench.json"
        subprocess.run([str(build / "tools" / "urt_bench"), "--skip-mujoco", "--dt", "5e-5",
                        "--steps", "20000", "--quiet", "--json", str(out)],
                       check=True, cwd=ROOT, timeout=600)
        runs = json.loads(out.read_text())["urt"]["runs"]
    run = next(r for r in runs if r["rate_hz"] == 20000 and r["faults"] == 0)
    return run["rtf"], run["median_us"]


def sweep(sweep_file, out, workers):
    cmd = [str(ROOT / "tools" / "loopback_only.sh"), sys.executable, "-m", "urtwin.dataset",
           str(sweep_file), "--out", str(out), "--workers", str(workers), "--quiet"]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=1800)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: exit {proc.returncode}: {proc.stderr[-2000:]}")
    return json.loads((out / "last_sweep_timing.json").read_text())


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", help="write the results as JSON")
    ap.add_argument("--quick", action="store_true", help="1 s runs (a smoke test)")
    a = ap.parse_args(argv)
    build = Path(os.environ.get("URT_BUILD", ROOT / "build"))
    before = bare_rate(build)
    res = {}
    duration, seeds = (1.0, 2) if a.quick else (10.0, 4)
    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "sweep.yaml"
        f.write_text(SWEEP.format(config=ROOT / "config" / "ur5.yaml", duration=duration,
                                  seeds=seeds))
        for w in (1, 2):
            t = sweep(f, Path(tmp) / f"w{w}", w)
            res[f"workers_{w}"] = t
            print(f"dataset sweep, {w} Ray worker(s): {t['runs']} runs, {t['simulated_s']:.0f} "
                  f"simulated s in {t['wall_s']:.2f} wall s ({t['sim_per_wall']:.2f} sim s per "
                  f"wall s; Ray's start-up {t['ray_start_s']:.1f} s before it, its shutdown "
                  f"{t['ray_stop_s']:.1f} s after); per run {t['sim_per_run_wall']:.2f} sim s per "
                  f"wall s; the stepping loops {t['sim_per_loop_cpu']:.2f} sim s per CPU s")
    # measured before and after the sweeps (a shared VM's pace drifts): the faster one, which
    # makes the per-worker ratio the stricter
    after = bare_rate(build)
    rtf, step_us = max(before, after)
    res.update({"bare_urt_step_rtf": rtf, "bare_urt_step_median_us": step_us,
                "bare_urt_step_rtf_before_after": [before[0], after[0]]})
    w1, w2 = res["workers_1"], res["workers_2"]
    res["per_worker_over_bare"] = w1["sim_per_wall"] / rtf
    res["per_worker_over_bare_2"] = w2["sim_per_wall"] / 2 / rtf
    res["scaling_2_over_1"] = w2["sim_per_wall"] / w1["sim_per_wall"]
    res["load_average"] = os.getloadavg()
    print(f"bare urt_step at 20 kHz: {rtf:.2f} x real time (median {step_us:.3f} us; the faster "
          f"of {before[0]:.2f} before and {after[0]:.2f} after the sweeps)")
    res["per_run_over_bare"] = w1["sim_per_run_wall"] / rtf
    # the same sweep against its own stepping loops (urt_step, the set-point, a row every 40
    # steps: the physics of these trajectories and faults, which cost more per step than
    # urt_bench's sine), i.e. what the dataset machinery around the physics costs
    res["per_worker_over_loops"] = w1["sim_per_wall"] / w1["sim_per_loop_cpu"]
    res["loops_over_bare"] = w1["sim_per_loop_cpu"] / rtf
    print(f"ratio: 1 worker's sweep rate / bare urt_step rate = {res['per_worker_over_bare']:.2f}"
          f"; 2 workers' rate per worker / bare = {res['per_worker_over_bare_2']:.2f}"
          f"; one run while it runs / bare = {res['per_run_over_bare']:.2f} (target: within "
          "20 %, not asserted)")
    print(f"ratio: 1 worker's sweep rate / its own stepping loops' rate = "
          f"{res['per_worker_over_loops']:.2f} (Parquet, model loads, Ray's tasks); the loops / "
          f"bare urt_step = {res['loops_over_bare']:.2f} (these trajectories' physics)")
    print(f"ratio: 2 workers / 1 worker = {res['scaling_2_over_1']:.2f} (target >= 1.7, not "
          f"asserted); load average {res['load_average'][0]:.1f}")
    if a.out:
        Path(a.out).write_text(json.dumps(res, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
