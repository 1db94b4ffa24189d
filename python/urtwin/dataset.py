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
"""

import argparse
import hashlib
import ipaddress
import json
import math
import os
import re
import socket
import sys
import time
from pathlib import Path

import numpy as np
import yaml

import urtwin

NJ = urtwin.NJ
KNOWN_KEYS = {"config", "overlays", "overrides", "rate", "output_rate", "duration",
              "trajectories", "payloads", "seeds", "splits", "faults", "sweep"}
BUILTIN = ("excitation", "pickplace", "hold")

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


class SweepError(Exception):
    """A bad sweep file or option: message, exit status 2."""


# ---- the sweep file ------------------------------------------------------------------------

def _key_lines(path, text):
    """{top-level key: line} of the sweep file, for messages."""
    try:
        node = yaml.compose(text)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        line = f"{mark.line + 1}:" if mark else ""
        raise SweepError(f"{path}:{line} syntax error: {getattr(e, 'problem', e)}") from None
    lines = {}
    if isinstance(node, yaml.MappingNode):
        for k, _ in node.value:
            lines[k.value] = k.start_mark.line + 1
    return lines


def _sanitize(name):
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", str(name)).strip("-") or "x"


def load_sweep(path):
    """The sweep as a dict of checked values; SweepError with file:line: key: reason."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as e:
        raise SweepError(f"{path}: cannot open: {e.strerror}") from None
    lines = _key_lines(path, text)
    doc = yaml.safe_load(text)
    if not isinstance(doc, dict):
        raise SweepError(f"{path}: expected a mapping of sweep keys")

    def err(key, reason):
        return SweepError(f"{path}:{lines.get(key, 1)}: {key}: {reason}")

    for k in doc:
        if k not in KNOWN_KEYS:
            raise err(k, f"unknown key (known: {', '.join(sorted(KNOWN_KEYS))})")
    base = path.resolve().parent

    def rel(p):
        p = Path(str(p))
        return p if p.is_absolute() else base / p

    s = {"path": str(path), "name": str(doc.get("sweep", path.stem))}
    s["config"] = str(rel(doc["config"])) if "config" in doc else urtwin.default_config()
    if not Path(s["config"]).is_file():
        raise err("config", f"{s['config']}: no such file")
    ov = doc.get("overlays", [])
    if not isinstance(ov, list):
        raise err("overlays", "expected a list of files")
    s["overlays"] = [str(rel(p)) for p in ov]
    for p in s["overlays"]:
        if not Path(p).is_file():
            raise err("overlays", f"{p}: no such file")
    o = doc.get("overrides", {})
    if not isinstance(o, dict):
        raise err("overrides", "expected a mapping key: value")
    s["overrides"] = urtwin._override_list(o)

    def number(key, default, lo, hi):
        v = doc.get(key, default)
        if v is None:
            return None
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                or not lo < v <= hi:
            raise err(key, f"expected a number in ({lo}, {hi}], got {v!r}")
        return float(v)

    s["rate"] = number("rate", None, 0, 1e6)
    s["output_rate"] = number("output_rate", 500.0, 0, 1e6)
    s["duration"] = number("duration", None, 0, 1e5)

    trajs = doc.get("trajectories")
    if not isinstance(trajs, list) or not trajs:
        raise err("trajectories", "expected a non-empty list (excitation, pickplace, hold or "
                                  "{name, csv: FILE})")
    s["trajectories"] = []
    for t in trajs:
        if isinstance(t, str):
            t = {"name": t, "kind": t}
        if not isinstance(t, dict) or "name" not in t:
            raise err("trajectories", f"expected a built-in's name or {{name, kind|csv}}, "
                                      f"got {t!r}")
        unknown = set(t) - {"name", "kind", "csv"}
        if unknown:
            raise err("trajectories", f"{t['name']}: unknown key {sorted(unknown)[0]!r}")
        if "csv" in t:
            p = rel(t["csv"])
            if not p.is_file():
                raise err("trajectories", f"{t['name']}: {p}: no such file")
            try:
                urtwin.read_record_csv(p)
            except ValueError as e:
                raise err("trajectories", f"{t['name']}: {e}") from None
            entry = {"name": str(t["name"]), "kind": "csv", "csv": str(p),
                     "csv_sha256": hashlib.sha256(p.read_bytes()).hexdigest()}
        else:
            kind = t.get("kind", t["name"])
            if kind not in BUILTIN:
                raise err("trajectories", f"{t['name']}: expected one of {', '.join(BUILTIN)} "
                                          f"or a csv, got {kind!r}")
            entry = {"name": str(t["name"]), "kind": kind}
        s["trajectories"].append(entry)
    names = [t["name"] for t in s["trajectories"]]
    if len(set(map(_sanitize, names))) != len(names):
        raise err("trajectories", "names must be distinct")

    pays = doc.get("payloads", [{"name": "none", "mass": 0.0}])
    if not isinstance(pays, list) or not pays:
        raise err("payloads", "expected a non-empty list of {name, mass, cog, inertia}")
    s["payloads"] = []
    for p in pays:
        if isinstance(p, (int, float)) and not isinstance(p, bool):
            p = {"name": f"{p:g}kg", "mass": p}
        if not isinstance(p, dict) or "name" not in p or "mass" not in p:
            raise err("payloads", f"expected {{name, mass[, cog, inertia]}}, got {p!r}")
        unknown = set(p) - {"name", "mass", "cog", "inertia"}
        if unknown:
            raise err("payloads", f"{p['name']}: unknown key {sorted(unknown)[0]!r}")
        entry = {"name": str(p["name"]), "mass": float(p["mass"]),
                 "cog": [float(x) for x in p.get("cog", [0.0, 0.0, 0.0])],
                 "inertia": [float(x) for x in p.get("inertia", [0.0] * 6)]}
        s["payloads"].append(entry)
    if len({_sanitize(p["name"]) for p in s["payloads"]}) != len(s["payloads"]):
        raise err("payloads", "names must be distinct")

    seeds = doc.get("seeds")
    if isinstance(seeds, dict) and set(seeds) == {"start", "count"}:
        seeds = list(range(int(seeds["start"]), int(seeds["start"]) + int(seeds["count"])))
    if not isinstance(seeds, list) or not seeds or not all(
            isinstance(x, int) and not isinstance(x, bool) and 0 <= x < 2**63 for x in seeds):
        raise err("seeds", "expected a list of unsigned integers or {start, count}")
    if len(set(seeds)) != len(seeds):
        raise err("seeds", "seeds must be distinct")
    s["seeds"] = seeds
    s["splits"] = _splits(doc.get("splits", {"train": 1.0}), seeds, err)
    s["faults"] = _fault_cases(doc.get("faults", ["healthy"]), rel, err)

    # every model and every trajectory now, so that a bad one stops the sweep before it writes
    s["decimate"] = {}
    try:
        urtwin.Model(s["config"], s["overlays"], s["overrides"], s["rate"])
    except ValueError as e:
        key = "overrides" if ":override:" in str(e) else (
            "overlays" if any(str(e).startswith(o) for o in s["overlays"]) else "config")
        raise err(key, str(e)) from None
    for p in s["payloads"]:
        try:
            m = model_for(s, p)
        except ValueError as e:
            raise err("payloads", f"{p['name']}: {e}") from None
        ratio = 1.0 / (m.dt * s["output_rate"])
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise err("output_rate", f"the physics rate {1 / m.dt:g} Hz is not a whole "
                                     f"multiple of {s['output_rate']:g} Hz")
        s["decimate"][p["name"]] = int(round(ratio))
        for case in s["faults"]:
            try:
                fault_yaml = scenario_yaml(case)
                if case["specs"] is not None:
                    urtwin._urtwin.faults_check(m._m, None, fault_yaml, f"<{case['name']}>")
                elif case["file"] is not None:
                    urtwin._urtwin.faults_check(m._m, case["file"], None, case["file"])
            except ValueError as e:
                raise err("faults", f"{case['name']} (payload {p['name']}): {e}") from None
        for t in s["trajectories"]:
            for seed in seeds if t["kind"] == "excitation" else seeds[:1]:
                try:
                    trajectory_for(m, t, seed, s["duration"])
                except ValueError as e:
                    raise err("trajectories", f"{t['name']} (payload {p['name']}, seed "
                                              f"{seed}): {e}") from None
    return s


def _fault_cases(spec, rel, err):
    """The faults axis: [{name, file, specs, severity, split}], one entry a run per seed. specs
    is the scenario's list of fault dicts (None for a file run as is, or for healthy)."""
    if not isinstance(spec, list) or not spec:
        raise err("faults", "expected a non-empty list of healthy, {name, file} or "
                            "{name, faults: [...]} (with severities, test_severities)")
    out = []
    for c in spec:
        if c in ("healthy", None):
            out.append({"name": "healthy", "file": None, "specs": None, "severity": None,
                        "split": None})
            continue
        if not isinstance(c, dict) or "name" not in c or ("file" in c) == ("faults" in c):
            raise err("faults", f"expected healthy or {{name, file | faults}}, got {c!r}")
        unknown = set(c) - {"name", "file", "faults", "severities", "test_severities"}
        if unknown:
            raise err("faults", f"{c['name']}: unknown key {sorted(unknown)[0]!r}")
        name = str(c["name"])
        fname, specs = None, None
        if "file" in c:
            fname = str(rel(c["file"]))
            if not Path(fname).is_file():
                raise err("faults", f"{name}: {fname}: no such file")
        else:
            specs = _fault_keys(c["faults"])
            if not isinstance(specs, list) or not all(isinstance(f, dict) for f in specs):
                raise err("faults", f"{name}: faults: expected a list of fault specs")
        sev = c.get("severities")
        held = c.get("test_severities", [])
        if sev is None:
            if held:
                raise err("faults", f"{name}: test_severities needs severities")
            out.append({"name": name, "file": fname, "specs": specs, "severity": None,
                        "split": None})
            continue
        if not isinstance(sev, list) or not sev or not all(
                isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                for x in sev) or len(set(sev)) != len(sev):
            raise err("faults", f"{name}: severities: expected a list of distinct numbers")
        if not isinstance(held, list) or any(x not in sev for x in held):
            raise err("faults", f"{name}: test_severities: expected values of severities")
        if fname is not None:
            # the override needs the specs: the file's own text, parsed as the loader will
            specs = _fault_keys(yaml.safe_load(Path(fname).read_text())).get("faults")
            if not isinstance(specs, list):
                raise err("faults", f"{name}: {fname}: no faults list")
        for x in sev:
            out.append({"name": name, "file": fname,
                        "specs": [dict(f, severity=float(x)) for f in specs],
                        "severity": float(x), "split": "test" if x in held else None})
    keys = [case_id(c) for c in out]
    if len(set(keys)) != len(keys):
        raise err("faults", "fault case names (with their severities) must be distinct")
    return out


_fault_keys = urtwin._fault_keys


def case_id(case):
    """The fault case's part of a run id: "" for healthy (a sweep without faults keeps its
    ids), else __<name>[_sev<severity>]."""
    if case["name"] == "healthy" and case["specs"] is None and case["file"] is None:
        return ""
    sev = "" if case["severity"] is None else f"_sev{case['severity']:g}"
    return f"__{_sanitize(case['name'])}{sev}"


def scenario_yaml(case):
    """The YAML text urtwin.run parses for an inline (or severity-overridden) case, else None."""
    if case["specs"] is None:
        return None
    return yaml.safe_dump({"faults": case["specs"]}, sort_keys=False, default_flow_style=False)


def _splits(spec, seeds, err):
    """{seed: split name}: explicit lists, or fractions over the sorted seeds in order."""
    if not isinstance(spec, dict) or not spec:
        raise err("splits", "expected {name: fraction} or {name: [seeds]}")
    out = {}
    if all(isinstance(v, list) for v in spec.values()):
        for name, lst in spec.items():
            for x in lst:
                if x not in seeds:
                    raise err("splits", f"{name}: seed {x} is not in seeds")
                if x in out:
                    raise err("splits", f"seed {x} is in two splits")
                out[x] = str(name)
        missing = [x for x in seeds if x not in out]
        if missing:
            raise err("splits", f"seeds in no split: {missing}")
        return out
    fr = list(spec.items())
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and v >= 0
               for _, v in fr) or abs(sum(v for _, v in fr) - 1.0) > 1e-9:
        raise err("splits", "fractions must be numbers >= 0 that add up to 1")
    order = sorted(seeds)
    n, acc, start = len(order), 0.0, 0
    for i, (name, f) in enumerate(fr):
        acc += f
        end = n if i == len(fr) - 1 else int(round(acc * n))
        for x in order[start:end]:
            out[x] = str(name)
        start = end
    return out


# ---- one run -------------------------------------------------------------------------------

def model_for(s, payload):
    sets = list(s["overrides"]) + [
        f"payload.mass={payload['mass']!r}",
        "payload.cog=[" + ", ".join(repr(x) for x in payload["cog"]) + "]",
        "payload.inertia=[" + ", ".join(repr(x) for x in payload["inertia"]) + "]",
    ]
    return urtwin.Model(s["config"], s["overlays"], sets, s["rate"])


def trajectory_for(model, t, seed, duration):
    if t["kind"] == "excitation":
        return urtwin.excitation(model, seed)
    if t["kind"] == "pickplace":
        return urtwin.pickplace(model)
    if t["kind"] == "hold":
        return urtwin.hold(model, duration if duration is not None else 1.0)
    return urtwin.from_record_csv(t["csv"])


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


def plan(s):
    """Every run of the sweep, in a fixed order: [(run_id, trajectory, payload, seed, fault
    case)]."""
    runs = []
    for t in s["trajectories"]:
        for p in s["payloads"]:
            for case in s["faults"]:
                for seed in s["seeds"]:
                    rid = f"{_sanitize(t['name'])}__{_sanitize(p['name'])}{case_id(case)}" \
                          f"__s{seed}"
                    runs.append((rid, t, p, seed, case))
    return runs


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
