# SPDX-License-Identifier: Apache-2.0
"""urtwin.run(..., faults=...) (python/src/run.cpp, ext.cpp): the same bits as
`urt_sim --faults` for the same scenario and seed, the truth included (urt_sim writes it per
fault, the package per class: each class here has one fault, so the two must agree); the
health index from the class ranges the loader enforces; a scenario as a dict or list equals
its file; a bad scenario raises ValueError with urt_sim's file:line: key: reason. 0.2 s runs."""

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import built

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("URT_BUILD", ROOT / "build"))
URT_SIM = BUILD / "tools" / "urt_sim"
CONFIG = ROOT / "config" / "ur5.yaml"
built.require(URT_SIM)

sys.path.insert(0, str(ROOT / "python"))
if not list((ROOT / "python" / "urtwin").glob("_urtwin*.so")):
    pytest.fail("python/urtwin/_urtwin*.so is not built: run make build", pytrace=False)
import urtwin  # noqa: E402

# one fault per class, several profiles, two with their own random streams
SPECS = [
    {"class": "demagnetisation", "joint": 1, "severity": 0.2, "unit": "1",
     "profile": {"kind": "linear", "onset": 0.02, "ramp": 0.1}},
    {"class": "encoder_noise", "joint": 2, "component": "motor", "severity": 0.01,
     "unit": "rad/s", "seed": 5, "profile": {"kind": "step", "onset": 0.05}},
    {"class": "lubricant", "joint": 2, "severity": 0.5, "unit": "1",
     "profile": {"kind": "random_walk", "onset": 0.0, "sigma": 0.05, "seed": 3}},
    {"class": "current_offset", "joint": 0, "severity": 0.05, "unit": "A",
     "profile": {"kind": "intermittent", "onset": 0.01, "on": 0.03, "off": 0.02}},
    {"class": "crack", "joint": 3, "severity": 0.3, "unit": "1",
     "profile": {"kind": "step", "onset": 0.1}},
]


def write_scenario(tmp_path, specs):
    p = tmp_path / "scenario.yaml"
    p.write_text(yaml.safe_dump({"faults": specs}, sort_keys=False))
    return p


def urt_sim(tmp_path, *args):
    out = tmp_path / "run.csv"
    res = subprocess.run([str(URT_SIM), "--config", str(CONFIG), "--quiet", "--out", str(out),
                          *map(str, args)], capture_output=True, text=True, check=False,
                         cwd=ROOT)
    return res, out


def test_faulted_run_has_urt_sims_bits_and_truth(tmp_path):
    sc = write_scenario(tmp_path, SPECS)
    res, out = urt_sim(tmp_path, "--traj", "excitation", "--duration", "0.2", "--decimate",
                       "20", "--set", "simulation.seed=77", "--faults", sc)
    assert res.returncode == 0, res.stderr
    ref = np.genfromtxt(out, delimiter=",", names=True)
    r = urtwin.run(urtwin.Model(CONFIG), "excitation", duration=0.2, decimate=20, seed=77,
                   faults=sc)
    cols = r.csv_columns()
    assert len(r) == ref.shape[0]
    differ = [k for k, v in cols.items() if not np.array_equal(v, ref[k])]
    assert not differ, f"columns that differ from urt_sim's: {differ}"
    for k, f in enumerate(SPECS):
        c = f["class"]
        assert np.array_equal(r[f"fault_active_{c}"], ref[f"fault{k}_{c}_active"]), c
        assert np.array_equal(r[f"severity_{c}"], ref[f"fault{k}_{c}_severity"]), c
        assert r[f"fault_active_{c}"].any() and not r[f"fault_active_{c}"].all() or \
            f["profile"]["onset"] == 0.0, c
    # classes without a fault are all zero
    for c in urtwin.FAULT_CLASSES:
        if c not in [f["class"] for f in SPECS]:
            assert not r[f"fault_active_{c}"].any() and not r[f"severity_{c}"].any(), c
    # and the faults act: the healthy run's true current differs
    healthy = urtwin.run(urtwin.Model(CONFIG), "excitation", duration=0.2, decimate=20, seed=77)
    assert not np.array_equal(healthy["i"], r["i"])
    assert np.all(healthy["health_index"] == 1.0)


def range_bound(spec):
    # the loader's message for an out-of-range severity names the range: "must be in [lo, hi]"
    # (printed with %g: six digits)
    bad = dict(spec, severity=1e9)
    with pytest.raises(ValueError) as e:
        urtwin.run(urtwin.Model(CONFIG), "hold", duration=0.01, faults=[bad])
    m = re.search(r"\[([-0-9.e+]+), ([-0-9.e+]+)\]", str(e.value))
    assert m, str(e.value)
    return max(abs(float(m.group(1))), abs(float(m.group(2))))


def test_health_index_is_one_less_the_worst_relative_severity():
    specs = [SPECS[0], SPECS[3], SPECS[4]]
    r = urtwin.run(urtwin.Model(CONFIG), "hold", duration=0.2, decimate=10, faults=specs)
    rel = np.zeros(len(r))
    for f in specs:
        c = f["class"]
        s = np.abs(r[f"severity_{c}"]) * r[f"fault_active_{c}"]
        rel = np.maximum(rel, s / range_bound(f))
    assert np.allclose(r["health_index"], 1.0 - rel, rtol=0, atol=1e-5)
    assert r["health_index"][0] == 1.0 and r["health_index"].min() < 0.9


def test_two_faults_of_one_class_take_the_larger_severity():
    a = {"class": "brake_drag", "joint": 0, "severity": 0.5, "unit": "N m",
         "profile": {"kind": "step", "onset": 0.0}}
    b = dict(a, joint=4, severity=1.5, profile={"kind": "step", "onset": 0.05})
    r = urtwin.run(urtwin.Model(CONFIG), "hold", duration=0.1, decimate=100, faults=[a, b])
    t = r.t
    assert np.array_equal(r["severity_brake_drag"], np.where(t >= 0.05, 1.5, 0.5))
    assert np.all(r["fault_active_brake_drag"] == 1.0)


def test_dict_list_text_and_file_are_the_same_scenario(tmp_path):
    sc = write_scenario(tmp_path, SPECS[:2])
    m = urtwin.Model(CONFIG)
    runs = [urtwin.run(m, "excitation", duration=0.05, decimate=50, faults=f)
            for f in (sc, str(sc), sc.read_text(), {"faults": SPECS[:2]}, SPECS[:2])]
    for r in runs[1:]:
        assert np.array_equal(r.data, runs[0].data)


def test_bad_scenario_raises_value_error_with_file_line(tmp_path):
    bad = [dict(SPECS[4], colour="red")]
    sc = write_scenario(tmp_path, bad)
    res, _ = urt_sim(tmp_path, "--duration", "0.01", "--faults", sc)
    assert res.returncode == 2
    m = urtwin.Model(CONFIG)
    with pytest.raises(ValueError) as e:
        urtwin.run(m, "hold", duration=0.01, faults=sc)
    assert str(e.value) == res.stderr.strip()
    assert re.match(r".*scenario\.yaml:\d+: faults\[0\]\.colour: unknown key$", str(e.value))
    # inline: the same text with <faults> for the file's name
    with pytest.raises(ValueError) as e:
        urtwin.run(m, "hold", duration=0.01, faults=bad)
    assert str(e.value) == res.stderr.strip().replace(str(sc), "<faults>")
    with pytest.raises(ValueError, match=r"^<faults>:\d+: faults\[0\]\.class: "):
        urtwin.run(m, "hold", duration=0.01, faults=[dict(SPECS[0], **{"class": "gremlin"})])
    with pytest.raises(ValueError, match="no_such_file"):
        urtwin.run(m, "hold", duration=0.01, faults=tmp_path / "no_such_file.yaml")
    with pytest.raises(TypeError):
        urtwin.run(m, "hold", duration=0.01, faults=3)
