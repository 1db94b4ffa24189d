# SPDX-License-Identifier: Apache-2.0
"""The sweep file of python -m urtwin.dataset: read and check it (load_sweep), and expand it
into the sweep's runs (plan), each with its model and trajectory (model_for, trajectory_for).

The format is in urtwin/dataset.py's docstring. Everything is checked here, before a sweep
writes anything: an unknown key, a missing file, a model, fault scenario or trajectory the
core refuses raises SweepError "file:line: key: reason" (exit status 2). load_sweep builds
every model and trajectory once to check it, with the same model_for and trajectory_for that
the runs (urtwin.dataset_run) and tools/dataset_demo.py build them with.
"""

import hashlib
import math
import re
from pathlib import Path

import yaml

import urtwin

KNOWN_KEYS = {"config", "overlays", "overrides", "rate", "output_rate", "duration",
              "trajectories", "payloads", "seeds", "splits", "faults", "sweep"}
BUILTIN = ("excitation", "pickplace", "hold")


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


# ---- the sweep's runs ----------------------------------------------------------------------

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
