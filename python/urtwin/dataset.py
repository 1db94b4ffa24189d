# SPDX-License-Identifier: Apache-2.0
"""python -m urtwin.dataset SWEEP.yaml --out DIR [--workers N] [--address ADDR] [--no-ray]

A dataset sweep: trajectories × payloads × seeds (the unit: sensor-noise seed and excitation
seed), each combination one run of the twin (urtwin.run), written as one Parquet file with
RTDE record.py column names for what a UR reports, the drives' internal channels and per-sample
labels, plus a JSON sidecar; then an index Parquet of every run. Runs are Ray tasks on a local
Ray (loopback only) or, with --address, on a running cluster reached over loopback.

Resumable: a run whose sidecar exists is skipped. A run is written to a temporary name and
renamed (Parquet first, the sidecar last), so a killed sweep leaves no half-written run; what a
killed run left as a temporary file is removed on the next start. The same sweep gives the same
bytes: nothing in a run's files or the index depends on the wall clock or the machine.

The sweep file (every key but trajectories and seeds optional; unknown keys are errors):

    config: ../config/ur5.yaml          # relative to the sweep file; default config/ur5.yaml
    overlays: [overlay.yaml]
    overrides: {sensors.noise: true}    # urt_sim's --set
    rate: 20000                         # physics rate [Hz] (default: the config's)
    output_rate: 500                    # samples written per second [Hz]; rate/output_rate
                                        # must be a whole number (default 500)
    duration: 10.0                      # [s] per run (default: each trajectory's own)
    trajectories:                       # a built-in's name, or {name, csv: record.py CSV}
      - excitation                      #   (the excitation is drawn from the run's seed)
      - pickplace
      - {name: hold, kind: hold}
      - {name: recorded, csv: rec.csv}
    payloads:                           # default [{name: none, mass: 0}]
      - {name: none, mass: 0}
      - {name: p3kg, mass: 3.0, cog: [0, 0, 0.1]}    # inertia optional (6 values)
    seeds: [1, 2, 3]                    # or {start: 1, count: 10}
    splits: {train: 0.6, val: 0.2, test: 0.2}   # by unit (seed), ../shared/docs/faults.md §2;
                                        # or explicit lists {train: [1, 2], test: [3]}

    faults:                             # default [healthy]: one fault case a run, per seed
      - healthy                         #   no fault
      - {name: stiff, file: stiff.yaml} #   a scenario file (core/include/urt/faults.h), as is
      - name: demag                     #   or the scenario inline (its `faults:` list)
        faults: [{class: demagnetisation, joint: 1, severity: 0.1, unit: "1",
                  profile: {kind: step, onset: 1.0}}]
        severities: [0.05, 0.1, 0.2]    #   one run per value, each replacing the severity of
                                        #   every fault of the scenario
        test_severities: [0.2]          #   these runs go to split "test" whatever their seed:
                                        #   severities the other splits never see (faults.md §2)

Every run's labels are the truth channels urtwin.run records (fault_active_<class>,
severity_<class>, health_index); its sidecar holds the fault specs it ran (after the severity
override). Exit status: 0 done, 1 a run failed, 2 a bad sweep file or options (nothing is
written then).

Where it is: this file has the command line and the sweep's course (main); the sweep file is
read, checked and expanded into runs in urtwin/dataset_sweep.py; a run is simulated and its
files written in urtwin/dataset_run.py.
"""

import argparse
import ipaddress
import json
import os
import socket
import sys
import time
from pathlib import Path

import urtwin

# the names urtwin.dataset had before the sweep file and the run moved to their own modules
# (tools/dataset_demo.py uses load_sweep, model_for and trajectory_for)
from urtwin.dataset_run import (INTERNAL_COLUMNS, NJ, RTDE_COLUMNS,  # noqa: F401
                                column_units, config_hash, run_one, spec_hash, table_of,
                                write_index)
from urtwin.dataset_sweep import (BUILTIN, KNOWN_KEYS, SweepError, _fault_cases,  # noqa: F401
                                  _fault_keys, _key_lines, _sanitize, _splits, case_id,
                                  load_sweep, model_for, plan, scenario_yaml, trajectory_for)


# ---- running the sweep ---------------------------------------------------------------------

def _check_loopback(address):
    """Ray stays on loopback: a cluster address must be 127.0.0.0/8 (or a name for it)."""
    if address in ("auto", "local"):
        return
    host = address.split("://")[-1].rsplit(":", 1)[0].strip("[]")
    try:
        ips = {ai[4][0] for ai in socket.getaddrinfo(host, None, socket.AF_INET)}
    except OSError:
        raise SweepError(f"--address {address}: cannot resolve {host}") from None
    for ip in ips:
        if not ipaddress.ip_address(ip) in ipaddress.ip_network("127.0.0.0/8"):
            raise SweepError(f"--address {address}: {ip} is outside 127.0.0.0/8; this build "
                             f"keeps Ray on loopback")


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m urtwin.dataset",
                                 description="Run a dataset sweep of the urtwin twin.")
    ap.add_argument("sweep", help="the sweep file (YAML)")
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                    help="runs at once (local Ray: its CPUs; default: this machine's cores)")
    ap.add_argument("--address", help="join a running Ray cluster (loopback only)")
    ap.add_argument("--no-ray", action="store_true",
                    help="run in this process, one run after the other (same files)")
    ap.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    a = ap.parse_args(argv)
    try:
        if a.workers < 1:
            raise SweepError(f"--workers: expected an integer >= 1, got {a.workers}")
        if a.address:
            if a.no_ray:
                raise SweepError("--address and --no-ray exclude each other")
            _check_loopback(a.address)
        s = load_sweep(a.sweep)
        out = Path(a.out)
        if out.exists() and not out.is_dir():
            raise SweepError(f"--out {out}: not a directory")
    except SweepError as e:
        print(f"urtwin.dataset: {e}", file=sys.stderr)
        return 2

    runs_dir = out / "runs"
    try:
        for rid, t, p, seed, case in plan(s):
            f = runs_dir / f"{rid}.json"
            if f.exists() and json.loads(f.read_text()).get("spec_hash") != \
                    spec_hash(s, t, p, seed, case):
                raise SweepError(f"{f}: a run of another sweep (its settings differ from "
                                 f"{a.sweep}'s): use another --out")
    except (OSError, ValueError) as e:
        print(f"urtwin.dataset: {out}: cannot read a finished run: {e}", file=sys.stderr)
        return 2
    except SweepError as e:
        print(f"urtwin.dataset: {e}", file=sys.stderr)
        return 2
    runs_dir.mkdir(parents=True, exist_ok=True)
    for stale in runs_dir.glob(".*.tmp*"):   # what a killed run left
        stale.unlink()
    for stale in out.glob(".index.parquet.tmp*"):
        stale.unlink()
    todo = [r for r in plan(s) if not (runs_dir / f"{r[0]}.json").exists()]
    total = len(plan(s))

    from tqdm import tqdm

    bar = tqdm(total=total, initial=total - len(todo), unit="run", disable=a.quiet,
               desc=s["name"])
    stats, failed = [], []
    # the sweep's wall time runs from when its runs can start to when the last one is back: a
    # local Ray's start-up and shutdown (seconds each, whatever the sweep's size) are reported
    # beside it, not spread over the runs
    wall0 = time.perf_counter()
    wall_end = None
    ray_start = ray_stop = 0.0
    if a.no_ray:
        for rid, t, p, seed, case in todo:
            try:
                stats.append(run_one(s, rid, t, p, seed, case, out))
            except (RuntimeError, ValueError) as e:
                failed.append((rid, str(e)))
            bar.update(1)
    elif todo:
        # nothing leaves the machine: no usage report to Ray's servers
        os.environ["RAY_USAGE_STATS_ENABLED"] = "0"
        # Ray starts its workers at nice 15; the runs are the sweep's work, not background
        # (on a busy machine nice 15 gave them a fraction of a core)
        os.environ.setdefault("RAY_worker_niceness", "0")
        import ray

        # the workers import this package from where this process found it
        pkg_parent = str(Path(urtwin.__file__).resolve().parents[1])
        os.environ["PYTHONPATH"] = os.pathsep.join(
            [pkg_parent] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])
        init = dict(include_dashboard=False, log_to_driver=False, configure_logging=False)
        if a.address:
            # a cluster's workers were not started from this process: tell them where the
            # package is
            ray.init(address=a.address, runtime_env={"env_vars": {"PYTHONPATH": pkg_parent}},
                     **init)
        else:
            ray.init(num_cpus=a.workers, _node_ip_address="127.0.0.1", **init)
        ray_start = time.perf_counter() - wall0
        wall0 += ray_start
        try:
            task = ray.remote(num_cpus=1, max_retries=0)(run_one)
            pending, queue = {}, list(todo)
            while queue or pending:
                while queue and len(pending) < a.workers:
                    rid, t, p, seed, case = queue.pop(0)
                    pending[task.remote(s, rid, t, p, seed, case, str(out.resolve()))] = rid
                done, _ = ray.wait(list(pending), num_returns=1)
                for ref in done:
                    rid = pending.pop(ref)
                    try:
                        stats.append(ray.get(ref))
                    except Exception as e:   # a run's RuntimeError comes back wrapped
                        failed.append((rid, str(getattr(e, "cause", e)).strip()))
                    bar.update(1)
            wall_end = time.perf_counter()
        finally:
            t_stop = time.perf_counter()
            ray.shutdown()
            ray_stop = time.perf_counter() - t_stop
    bar.close()
    wall = (wall_end if wall_end is not None else time.perf_counter()) - wall0

    for rid, msg in failed:
        print(f"urtwin.dataset: {rid}: {msg}", file=sys.stderr)
    if failed:
        return 1
    write_index(s, out)
    if stats:
        sim = sum(x[1] for x in stats)
        summary = {
            "runs": len(stats), "already_done": total - len(todo), "workers": a.workers,
            "ray": not a.no_ray, "ray_start_s": ray_start, "ray_stop_s": ray_stop,
            "simulated_s": sim, "wall_s": wall,
            "sim_per_wall": sim / wall,
            "sim_per_loop_wall": sim / sum(x[2] for x in stats),
            "sim_per_loop_cpu": sim / sum(x[3] for x in stats),
            "sim_per_run_wall": sim / sum(x[4] for x in stats),
            "sim_per_run_cpu": sim / sum(x[5] for x in stats),
            "loadavg_1min": os.getloadavg()[0],
        }
        # timings change from run to run: beside the dataset, never in its files
        (out / "last_sweep_timing.json").write_text(json.dumps(summary, indent=1) + "\n")
        if not a.quiet:
            print(f"{len(stats)} runs ({total - len(todo)} already done), {sim:.3g} s "
                  f"simulated in {wall:.3g} s wall: {summary['sim_per_wall']:.3g} sim s per "
                  f"wall s overall; per worker {summary['sim_per_run_wall']:.3g} per wall s "
                  f"({summary['sim_per_run_cpu']:.3g} per CPU s) for whole runs, "
                  f"{summary['sim_per_loop_cpu']:.3g} per CPU s in the stepping loops"
                  + (f"; Ray's start-up {ray_start:.3g} s before, its shutdown {ray_stop:.3g} s "
                     "after" if not a.no_ray else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
