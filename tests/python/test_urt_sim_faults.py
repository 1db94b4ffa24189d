# SPDX-License-Identifier: Apache-2.0
"""tools/urt_sim --faults: the ground-truth columns follow the scenario (a linear ramp's
severity and its onset, per physics step), the fault acts in the physics (a demagnetised
shoulder draws more current than the healthy run), and a bad scenario exits 2 with the
loader's file:line: key: reason. Short runs only."""

import os
import subprocess
from pathlib import Path

import numpy as np

import built

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("URT_BUILD", ROOT / "build"))
URT_SIM = BUILD / "tools" / "urt_sim"
URTWIN = BUILD / "tools" / "urtwin"
CONFIG = ROOT / "config" / "ur5.yaml"

built.require(URT_SIM)
built.require(URTWIN)

SCENARIO = """faults:
  - class: demagnetisation
    joint: 1
    severity: 0.2
    unit: "1"
    profile: {kind: linear, onset: 0.01, ramp: 0.02}
  - class: encoder_bias
    joint: 4
    component: joint
    severity: 0.001
    unit: rad
    profile: {kind: step, onset: 0.03}
"""


def sim(*args):
    # frictionless: at rest LuGre's stiction would carry what the weaker motor lacks
    return subprocess.run([str(URT_SIM), "--config", str(CONFIG), "--quiet",
                           "--set", "sensors.noise=false",
                           "--set", "friction_common.enabled=false", *map(str, args)],
                          capture_output=True, text=True, check=False, cwd=ROOT)


def test_urt_sim_faults__truth_columns_follow_the_scenario(tmp_path):
    sc = tmp_path / "f.yaml"
    sc.write_text(SCENARIO)
    out = tmp_path / "run.csv"
    res = sim("--traj", "hold", "--duration", "0.05", "--faults", sc, "--out", out)
    assert res.returncode == 0, res.stderr
    header = out.read_text().split("\n", 1)[0].split(",")
    data = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)
    assert header[-4:] == ["fault0_demagnetisation_active", "fault0_demagnetisation_severity",
                           "fault1_encoder_bias_active", "fault1_encoder_bias_severity"]
    t = data[:, 0]
    want = 0.2 * np.clip((t - 0.01) / 0.02, 0.0, 1.0)
    assert np.max(np.abs(data[:, -3] - want)) < 1e-12
    assert np.array_equal(data[:, -4], (t >= 0.01 - 1e-12).astype(float))
    assert np.array_equal(data[:, -2], (t >= 0.03 - 1e-12).astype(float))
    assert np.all(data[:, -1] == np.where(t >= 0.03 - 1e-12, 0.001, 0.0))

    # the physics felt it: the shoulder's current grows towards 1/(1 - 0.2) of the healthy run's
    healthy = tmp_path / "healthy.csv"
    assert sim("--traj", "hold", "--duration", "0.05", "--out", healthy).returncode == 0
    h = np.loadtxt(healthy, delimiter=",", skiprows=1, ndmin=2)
    col = header.index("i_2")
    ratio = abs(data[-1, col]) / abs(h[-1, col])
    assert 1.1 < ratio < 1.3, ratio


def test_urt_sim_faults__bad_scenario_exits_2_with_file_line_key_reason(tmp_path):
    sc = tmp_path / "bad.yaml"
    sc.write_text(SCENARIO.replace("severity: 0.2", "severity: 0.5"))
    for tool in (URT_SIM, URTWIN):
        res = subprocess.run([str(tool), "--config", str(CONFIG), "--faults", str(sc)],
                             capture_output=True, text=True, check=False, cwd=ROOT, timeout=30)
        assert res.returncode == 2, (tool, res.stderr)
        assert f"{sc}:4: faults[0].severity: must be in [0, 0.3] (got 0.5)" in res.stderr
    sc.write_text(SCENARIO.replace("class: demagnetisation", "class: gremlins"))
    res = sim("--faults", sc)
    assert res.returncode == 2
    assert f"{sc}:2: faults[0].class: unknown fault class 'gremlins'" in res.stderr
