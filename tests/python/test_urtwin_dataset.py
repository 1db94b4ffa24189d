# SPDX-License-Identifier: Apache-2.0
"""python -m urtwin.dataset: one tiny sweep (six 0.2 s runs) in this process, on a local Ray
with two workers, and killed after its first run then resumed; all three give the same bytes.
A tiny faulted sweep (six 0.2 s holds): labels from the truth, sidecars, unseen severities.
The files' columns and labels, the index and its splits by unit, a record.py CSV as a
trajectory, and bad sweeps refused with exit 2 and nothing written."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python"))
if not list((ROOT / "python" / "urtwin").glob("_urtwin*.so")):
    pytest.fail("python/urtwin/_urtwin*.so is not built: run make build", pytrace=False)
import urtwin  # noqa: E402

SWEEP = """\
sweep: tiny
duration: 0.2
trajectories: [excitation, {name: still, kind: hold}]
payloads: [{name: none, mass: 0}]
seeds: [1, 2, 3]
splits: {train: [1, 2], test: [3]}
"""


def sweep(*args, wait=True, loopback_only=False):
    env = dict(os.environ, PYTHONPATH=str(ROOT / "python"))
    cmd = [sys.executable, "-m", "urtwin.dataset", *map(str, args)]
    if loopback_only:
        cmd = [str(ROOT / "tools" / "loopback_only.sh"), *cmd]
    if not wait:
        return subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True)
    return subprocess.run(cmd, env=env, capture_output=True, text=True, check=False,
                          timeout=600)


def files(d):
    """The dataset's files (not last_sweep_timing.json, the wall-clock report beside it)."""
    return {p.relative_to(d): p.read_bytes() for p in sorted(Path(d).rglob("*"))
            if p.is_file() and p.name != "last_sweep_timing.json"}


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory):
    p = tmp_path_factory.mktemp("sweep") / "tiny.yaml"
    p.write_text(SWEEP)
    return p


@pytest.fixture(scope="module")
def serial(sweep_file, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial")
    res = sweep(sweep_file, "--out", out, "--no-ray")
    assert res.returncode == 0, res.stderr
    return out


def test_files_columns_and_labels(serial):
    idx = pq.read_table(serial / "index.parquet").to_pylist()
    assert [r["run_id"] for r in idx] == [f"{t}__none__s{s}" for t in ("excitation", "still")
                                          for s in (1, 2, 3)]
    assert {r["unit"]: r["split"] for r in idx} == {1: "train", 2: "train", 3: "test"}
    assert all(r["rows"] == 101 and r["rate"] == 20000 and r["faults"] == "[]" for r in idx)
    t = pq.read_table(serial / "runs" / "excitation__none__s2.parquet")
    names = t.column_names
    for stem in ("actual_q", "actual_qd", "actual_current", "target_q", "target_current",
                 "motor_speed", "gear_torque", "friction_torque", "actual_joint_voltage",
                 "joint_temperatures"):
        assert all(f"{stem}_{j}" in names for j in range(6)), stem
    assert names[0] == "timestamp" and "health_index" in names
    # the run's data are urtwin.run's for the same unit: seed 2 drives noise and excitation
    r = urtwin.run(urtwin.Model(), "excitation", traj_seed=2, seed=2, duration=0.2,
                   decimate=40)
    for j in range(6):
        assert np.array_equal(t[f"actual_current_{j}"].to_numpy(), r["i_meas"][:, j])
        assert np.array_equal(t[f"target_q_{j}"].to_numpy(), r["q_set"][:, j])
    side = json.loads((serial / "runs" / "excitation__none__s2.json").read_text())
    assert side["seed"] == 2 and side["split"] == "train" and side["faults"] == []
    assert side["urtwin_version"] == urtwin.__version__ and len(side["config"]["hash"]) == 64
    assert side["units"]["actual_current"] == "A"


def test_ray_gives_the_same_bytes(sweep_file, serial, tmp_path):
    # a local Ray listens on every interface (its GCS, raylet and workers): the sweep runs in a
    # network namespace with only the loopback (tools/loopback_only.sh), so the test keeps to
    # this machine whatever Ray binds
    res = sweep(sweep_file, "--out", tmp_path, "--workers", "2", loopback_only=True)
    assert res.returncode == 0, res.stderr
    assert files(tmp_path) == files(serial)


def test_killed_and_resumed_gives_the_same_bytes(sweep_file, serial, tmp_path):
    p = sweep(sweep_file, "--out", tmp_path, "--no-ray", wait=False)
    runs = tmp_path / "runs"
    deadline = time.monotonic() + 300
    while not list(runs.glob("*.json")) and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.005)
    p.send_signal(signal.SIGKILL)
    p.communicate()
    done = list(runs.glob("*.json"))
    assert 1 <= len(done) < 6, "the sweep was not killed midway"
    assert not (tmp_path / "index.parquet").exists()
    # what is there under its final name is whole
    for f in runs.glob("*.parquet"):
        assert f.read_bytes() == (serial / "runs" / f.name).read_bytes()
    res = sweep(sweep_file, "--out", tmp_path, "--no-ray")
    assert res.returncode == 0, res.stderr
    assert f"({len(done)} already done)" in res.stdout
    assert files(tmp_path) == files(serial)


def test_resume_refuses_another_sweeps_runs(sweep_file, serial, tmp_path):
    import shutil
    shutil.copytree(serial, tmp_path / "d")
    other = tmp_path / "other.yaml"
    other.write_text(SWEEP.replace("duration: 0.2", "duration: 0.4"))
    before = files(tmp_path / "d")
    res = sweep(other, "--out", tmp_path / "d", "--no-ray")
    assert res.returncode == 2
    assert "a run of another sweep" in res.stderr
    assert files(tmp_path / "d") == before


def test_record_csv_trajectory(tmp_path):
    m = urtwin.Model(overrides={"sensors.noise": False})
    ref = urtwin.run(m, "excitation", traj_seed=4, duration=0.2, decimate=40)
    cols = ["timestamp"] + [f"{n}_{j}" for n in ("target_q", "target_qd", "actual_current")
                            for j in range(6)]
    np.savetxt(tmp_path / "rec.csv", np.column_stack([ref.t, ref["q_set"], ref["qd_set"],
                                                      ref["i_meas"]]),
               header=" ".join(cols), comments="", fmt="%.17g")
    (tmp_path / "s.yaml").write_text("overrides: {sensors.noise: false}\n"
                                     "trajectories: [{name: rec, csv: rec.csv}]\nseeds: [5]\n")
    res = sweep(tmp_path / "s.yaml", "--out", tmp_path / "out", "--no-ray")
    assert res.returncode == 0, res.stderr
    t = pq.read_table(tmp_path / "out" / "runs" / "rec__none__s5.parquet")
    assert np.max(np.abs(t["target_q_1"].to_numpy() - ref["q_set"][:, 1])) < 1e-7


@pytest.mark.parametrize("text,args,message", [
    ("trajectorys: [hold]\nseeds: [1]\n", [], r"s\.yaml:1: trajectorys: unknown key"),
    ("seeds: [1]\ntrajectories: [{name: r, csv: missing.csv}]\n", [],
     r"s\.yaml:2: trajectories: r: .*missing\.csv: no such file"),
    ("trajectories: [hold]\nseeds: [1]\nfaults: [{class: backlash}]\n", [],
     r"s\.yaml:3: faults: expected healthy or \{name, file \| faults\}"),
    ("trajectories: [hold]\nseeds: [1]\nfaults: [{name: d, faults: [{class: demagnetisation, "
     "joint: 1, severity: 0.1, unit: '1', profile: {kind: step, onset: 0}}], "
     "severities: [0.1, 0.5]}]\n", [],
     r"s\.yaml:3: faults: d \(payload none\): <d>:\d+: faults\[0\]\.severity: must be in"),
    ("trajectories: [hold]\nseeds: [1]\nfaults: [{name: d, file: nofile.yaml}]\n", [],
     r"s\.yaml:3: faults: d: .*nofile\.yaml: no such file"),
    ("trajectories: [hold]\nseeds: [1]\noutput_rate: 700\n", [],
     r"output_rate: the physics rate 20000 Hz is not a whole multiple of 700 Hz"),
    ("trajectories: [hold]\nseeds: [1]\noverrides: {sensors.nosie: false}\n", [],
     r"s\.yaml:3: overrides: .*override: sensors\.nosie"),
    ("trajectories: [hold]\nseeds: [1]\n", ["--address", "10.1.2.3:6379"],
     r"10\.1\.2\.3 is outside 127\.0\.0\.0/8"),
])
def test_bad_sweeps_write_nothing(tmp_path, text, args, message):
    (tmp_path / "s.yaml").write_text(text)
    res = sweep(tmp_path / "s.yaml", "--out", tmp_path / "out", *args)
    assert res.returncode == 2, res.stderr
    import re
    assert re.search(message, res.stderr), res.stderr
    assert not (tmp_path / "out").exists()


FAULT_SWEEP = """\
sweep: faulty
duration: 0.2
overrides: {sensors.noise: false}
trajectories: [{name: still, kind: hold}]
seeds: [1, 2]
splits: {train: [1], test: [2]}
faults:
  - healthy
  - name: demag
    faults: [{class: demagnetisation, joint: 1, severity: 0.1, unit: "1",
              profile: {kind: step, onset: 0.1}}]
    severities: [0.1, 0.2]
    test_severities: [0.2]
  - {name: pulses, file: pulses.yaml}
"""
PULSES = """\
faults:
  - class: current_offset
    joint: 0
    severity: 0.05
    unit: A
    profile: {kind: intermittent, onset: 0.02, on: 0.03, off: 0.05}
"""


def test_faulted_sweep_labels_sidecars_and_unseen_severities(tmp_path):
    (tmp_path / "f.yaml").write_text(FAULT_SWEEP)
    (tmp_path / "pulses.yaml").write_text(PULSES)
    res = sweep(tmp_path / "f.yaml", "--out", tmp_path / "out", "--no-ray")
    assert res.returncode == 0, res.stderr
    idx = {r["run_id"]: r for r in pq.read_table(tmp_path / "out" / "index.parquet").to_pylist()}
    assert sorted(idx) == sorted(f"still__none{c}__s{s}" for s in (1, 2)
                                 for c in ("", "__demag_sev0.1", "__demag_sev0.2", "__pulses"))
    # by unit, except the held-out severity: test only, whatever the seed
    assert {k: r["split"] for k, r in idx.items()} == {
        "still__none__s1": "train", "still__none__s2": "test",
        "still__none__demag_sev0.1__s1": "train", "still__none__demag_sev0.1__s2": "test",
        "still__none__demag_sev0.2__s1": "test", "still__none__demag_sev0.2__s2": "test",
        "still__none__pulses__s1": "train", "still__none__pulses__s2": "test"}
    assert idx["still__none__demag_sev0.2__s1"]["fault_classes"] == "demagnetisation"
    assert idx["still__none__s1"]["fault_classes"] == ""
    assert idx["still__none__s1"]["faults"] == "[]"
    runs = tmp_path / "out" / "runs"
    side = json.loads((runs / "still__none__demag_sev0.2__s1.json").read_text())
    assert side["severity_override"] == 0.2 and side["fault_case"] == "demag"
    assert side["faults"][0]["severity"] == 0.2 and side["faults"][0]["joint"] == 1
    t = pq.read_table(runs / "still__none__demag_sev0.2__s1.parquet")
    ts = t["timestamp"].to_numpy()
    on = ts >= 0.1 - 1e-12
    assert np.array_equal(t["fault_active_demagnetisation"].to_numpy(), on.astype(float))
    assert np.array_equal(t["severity_demagnetisation"].to_numpy(), np.where(on, 0.2, 0.0))
    # demagnetisation's range is [0, 0.3]: health 1 - 0.2 / 0.3 once it is on
    assert np.allclose(t["health_index"].to_numpy(), np.where(on, 1 - 0.2 / 0.3, 1.0),
                       rtol=0, atol=1e-12)
    assert not t["fault_active_crack"].to_numpy().any()
    # a scenario file run as is: its specs in the sidecar (on/off as the file spells them), the
    # truth follows its on/off windows
    side = json.loads((runs / "still__none__pulses__s1.json").read_text())
    assert side["faults_file"] == "pulses.yaml" and side["severity_override"] is None
    assert side["faults"][0]["profile"] == {"kind": "intermittent", "onset": 0.02, "on": 0.03,
                                            "off": 0.05}
    p = pq.read_table(runs / "still__none__pulses__s1.parquet")
    ph = ((p["timestamp"].to_numpy() - 0.02) % 0.08 < 0.03 - 1e-9) & \
        (p["timestamp"].to_numpy() >= 0.02 - 1e-12)
    assert np.array_equal(p["fault_active_current_offset"].to_numpy() == 1.0, ph)
    h = pq.read_table(runs / "still__none__s1.parquet")
    assert h.column_names == t.column_names and np.all(h["health_index"].to_numpy() == 1.0)
    # the fault acts: the shoulder's current grows once the magnets weaken
    assert not np.array_equal(h["actual_current_1"].to_numpy()[on],
                              t["actual_current_1"].to_numpy()[on])
