# SPDX-License-Identifier: Apache-2.0
"""One run of a python -m urtwin.dataset sweep: simulate it and write its Parquet file and
JSON sidecar (run_one, the sweep's Ray task), and then the sweep's index (write_index).

A run's columns are RTDE record.py names for what a UR reports, the drives' internal channels
and the fault truth labels. Nothing in a run's files or the index depends on the wall clock or
the machine, so the same sweep gives the same bytes; spec_hash, in the sidecar, says what a run
is made of, so that a resumed sweep skips a finished run only when it is the same run. run_one
lives in this module, which Ray's workers import from where the sweep's process found urtwin.
"""

import hashlib
import json
import os
import time
from pathlib import Path

import numpy as np
import yaml

import urtwin
from urtwin.dataset_sweep import (_fault_keys, case_id, model_for, plan, scenario_yaml,
                                  trajectory_for)

NJ = urtwin.NJ

# RTDE record.py names for what a UR reports (per joint _0 … _5), from the run's channels
RTDE_COLUMNS = [
    ("actual_q", "q_meas"),             # joint encoder
    ("actual_qd", "qd_meas"),           # motor encoder speed / gear ratio
    ("actual_current", "i_meas"),       # measured motor current
    ("target_q", "q_set"),
    ("target_qd", "qd_set"),
    ("target_qdd", "qdd_set"),
    ("target_current", "i_target"),
    ("actual_joint_voltage", "v"),
    ("joint_temperatures", "temperature"),
]
# internal channels no UR reports, named for what they are
INTERNAL_COLUMNS = [
    ("motor_speed", "qdm"),
    ("motor_angle", "qm"),
    ("gear_torque", "tcs"),
    ("gear_input_torque", "tin"),
    ("friction_torque", "tf"),
    ("motor_current_true", "i"),
    ("current_reference", "i_ref"),
    ("q_true", "q"),
    ("qd_true", "qd"),
    ("bristle_z", "z"),
]


def config_hash(model):
    """sha256 of the fully resolved model's parameters (not the file's path)."""
    doc = json.loads(model.print(json=True))
    doc.pop("source", None)
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def spec_hash(s, t, p, seed, case):
    """What a run is made of (the sweep's settings, its trajectory, payload and seed), hashed:
    a resumed sweep skips a finished run only when this matches its sidecar's."""
    keep = {k: s[k] for k in ("config", "overlays", "overrides", "rate", "output_rate",
                              "duration", "splits")}
    keep["splits"] = {str(k): v for k, v in keep["splits"].items()}
    doc = {"sweep": keep, "trajectory": t, "payload": p, "seed": seed,
           "urtwin_version": urtwin.__version__}
    if case_id(case):
        # a healthy run's hash stays what it was before the faults axis
        doc["faults"] = {"case": case, "file_sha256": hashlib.sha256(
            Path(case["file"]).read_bytes()).hexdigest() if case["file"] else None}
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def table_of(result):
    """The run's samples as a pyarrow Table: RTDE names, internal channels, labels."""
    import pyarrow as pa

    cols = {"timestamp": result.t}
    for out, ch in RTDE_COLUMNS + INTERNAL_COLUMNS:
        a = result[ch]
        for j in range(NJ):
            cols[f"{out}_{j}"] = np.ascontiguousarray(a[:, j])
    tcp = result["tcp"]
    for k in range(6):
        cols[f"tcp_pose_{k}"] = np.ascontiguousarray(tcp[:, k])
    # labels: the run's fault truth channels (fault_active_<class>, severity_<class>,
    # health_index: urt_faults_truth, python/src/run.cpp); every run records them
    truth = [c for c in result.keys()
             if c.startswith(("fault_active_", "severity_")) or c == "health_index"]
    for c in truth:
        cols[c] = np.ascontiguousarray(result[c])
    if "health_index" not in truth:
        cols["health_index"] = np.ones(len(result))
    cols["protective_stop"] = result["pstop"].astype(np.uint32)
    return pa.table(cols)


def column_units():
    """{column or column stem (per joint _0 … _5): unit} of a run's Parquet file."""
    unit = {c: u for c, u, _ in urtwin.CHANNELS}
    out = {"timestamp": "s"}
    out.update({name: unit[ch] for name, ch in RTDE_COLUMNS + INTERNAL_COLUMNS})
    out.update({"tcp_pose": "m (0-2), rad (3-5)", "health_index": "-",
                "protective_stop": "URT_PSTOP_* bits"})
    return out


def run_one(s, rid, t, p, seed, case, out_dir):
    """Simulate one run and write DIR/runs/<rid>.parquet and .json (temp name, then rename).
    Returns (rid, simulated seconds, loop wall seconds, loop CPU seconds, the whole run's
    wall and CPU seconds)."""
    import pyarrow.parquet as pq

    wall0, cpu0 = time.perf_counter(), time.thread_time()
    runs = Path(out_dir) / "runs"
    m = model_for(s, p)
    tr = trajectory_for(m, t, seed, s["duration"])
    faults = scenario_yaml(case) or case["file"]
    r = urtwin.run(m, tr, duration=s["duration"], seed=seed, decimate=s["decimate"][p["name"]],
                   faults=faults)
    table = table_of(r)
    tmp = runs / f".{rid}.parquet.tmp{os.getpid()}"
    # no dictionary pages: a run's columns are floats that seldom repeat (and constant labels,
    # which zstd takes as well); with them the write cost 2.2x as long and 20 % more bytes
    # (43 against 19 ms and 4.9 against 4.1 MiB for a 10 s run at 500 Hz)
    pq.write_table(table, tmp, compression="zstd", use_dictionary=False)
    os.replace(tmp, runs / f"{rid}.parquet")
    side = {
        "run_id": rid,
        "file": f"runs/{rid}.parquet",
        "seed": seed,
        "unit": seed,
        "split": case["split"] or s["splits"][seed],
        "trajectory": {k: v for k, v in t.items() if k != "csv"} | (
            {"csv": os.path.basename(t["csv"])} if "csv" in t else {}),
        "payload": p,
        "duration": float(r.t[-1]),
        "rate": 1.0 / m.dt,
        "output_rate": s["output_rate"],
        "decimate": s["decimate"][p["name"]],
        "rows": len(r),
        "config": {"file": os.path.basename(s["config"]),
                   "overlays": [os.path.basename(o) for o in s["overlays"]],
                   "overrides": s["overrides"], "hash": config_hash(m)},
        "urtwin_version": urtwin.__version__,
        "spec_hash": spec_hash(s, t, p, seed, case),
        "fault_case": case["name"],
        "severity_override": case["severity"],
        "faults": case["specs"] if case["specs"] is not None else (
            _fault_keys(yaml.safe_load(Path(case["file"]).read_text()))["faults"]
            if case["file"] else []),
        "faults_file": os.path.basename(case["file"]) if case["file"] else None,
        "units": column_units(),
    }
    tmp = runs / f".{rid}.json.tmp{os.getpid()}"
    tmp.write_text(json.dumps(side, indent=1, sort_keys=True) + "\n")
    os.replace(tmp, runs / f"{rid}.json")
    return (rid, float(r.t[-1]), float(r.info["wall_s"]), float(r.info["cpu_s"]),
            time.perf_counter() - wall0, time.thread_time() - cpu0)


def write_index(s, out_dir):
    import pyarrow as pa
    import pyarrow.parquet as pq

    rows = []
    for rid, *_ in plan(s):
        side = json.loads((Path(out_dir) / "runs" / f"{rid}.json").read_text())
        rows.append({
            "run_id": rid, "file": side["file"], "split": side["split"],
            "unit": side["unit"], "seed": side["seed"],
            "trajectory": side["trajectory"]["name"],
            "trajectory_kind": side["trajectory"]["kind"],
            "payload": side["payload"]["name"], "payload_mass": side["payload"]["mass"],
            "duration": side["duration"], "rate": side["rate"],
            "output_rate": side["output_rate"], "rows": side["rows"],
            "config_hash": side["config"]["hash"], "urtwin_version": side["urtwin_version"],
            "fault_case": side["fault_case"],
            "severity_override": side["severity_override"],
            "fault_classes": ",".join(sorted({f["class"] for f in side["faults"]})),
            "faults": json.dumps(side["faults"], sort_keys=True),
        })
    table = pa.Table.from_pylist(rows)
    tmp = Path(out_dir) / f".index.parquet.tmp{os.getpid()}"
    pq.write_table(table, tmp, compression="zstd")
    os.replace(tmp, Path(out_dir) / "index.parquet")
