# SPDX-License-Identifier: Apache-2.0
"""tools/plot_run.py on a small synthetic urt_sim trace: every PNG appears, k_t and τ are read
from urt_config's JSON when no option gives them, and the 10 Hz filter behaves like one."""

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
PLOT_RUN = ROOT / "tools" / "plot_run.py"
COLS = ("q_set", "q", "qd", "qm", "qdm", "i", "i_meas", "v", "tcs", "tf")
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def load_module():
    spec = importlib.util.spec_from_file_location("plot_run", PLOT_RUN)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def write_trace(path, rate=2000.0, seconds=1.0, lag=0.0):
    """A trace in urt_sim's column layout: slow sines followed with a small lag."""
    t = np.arange(0.0, seconds, 1.0 / rate)
    cols = [t]
    names = ["t"]
    for j in range(1, 7):
        q_set = 0.3 * np.sin(2 * np.pi * 0.5 * t + j)
        q = 0.3 * np.sin(2 * np.pi * 0.5 * (t - lag - 1e-3 * j) + j)
        i = 0.5 * np.cos(2 * np.pi * 0.5 * t + j) + 0.05 * np.sin(2 * np.pi * 300 * t)
        values = {"q_set": q_set, "q": q, "qd": np.gradient(q, t), "qm": 101 * q,
                  "qdm": 101 * np.gradient(q, t), "i": i, "i_meas": i + 0.01, "v": 2 * i,
                  "tcs": 10 * i, "tf": 0.1 * np.sign(np.gradient(q, t))}
        for c in COLS:
            names.append(f"{c}_{j}")
            cols.append(values[c])
    for c in ("tcp_x", "tcp_y", "tcp_z", "tcp_rx", "tcp_ry", "tcp_rz"):
        names.append(c)
        cols.append(np.full_like(t, 0.1))
    data = np.column_stack(cols)
    with open(path, "w", encoding="ascii") as f:
        f.write(",".join(names) + "\n")
        np.savetxt(f, data, delimiter=",", fmt="%.17g")


def run_plot(*args):
    res = subprocess.run([sys.executable, str(PLOT_RUN), *map(str, args)], capture_output=True,
                         text=True, check=False)
    assert res.returncode == 0, res.stderr
    return res


def assert_pngs(out, names):
    for n in names:
        p = out / n
        assert p.is_file(), f"{p} missing"
        assert p.stat().st_size > 10000
        assert p.read_bytes()[:8] == PNG_MAGIC


def test_plot_run__writes_the_three_figures(tmp_path):
    csv = tmp_path / "run.csv"
    write_trace(csv)
    out = tmp_path / "plots"
    run_plot(csv, "--out", out, "--kt", "0.1", "--ratio", "101")
    assert_pngs(out, ["positions.png", "tracking_error.png", "torque.png"])
    assert not (out / "compare.png").exists()


def test_plot_run__compares_against_a_reference_trace(tmp_path):
    run, ref = tmp_path / "fixed.csv", tmp_path / "reference.csv"
    write_trace(run, lag=2e-4)
    write_trace(ref)
    out = tmp_path / "plots"
    run_plot(run, "--ref", ref, "--out", out, "--kt", "0.1,0.1,0.1,0.09,0.09,0.09",
             "--ratio", "101", "--lpf", "0")
    assert_pngs(out, ["positions.png", "tracking_error.png", "torque.png", "compare.png"])


def test_plot_run__reads_kt_and_ratio_from_urt_config_json(tmp_path):
    # a stand-in for build/tools/urt_config that records its arguments
    model = {"joints": [{"motor": {"kt": 0.11 + 0.01 * j}, "gear": {"ratio": 100.0 + j}}
                        for j in range(6)]}
    fake = tmp_path / "urt_config"
    argfile = tmp_path / "args.json"
    fake.write_text(f"#!{sys.executable}\nimport json, sys\n"
                    f"json.dump(sys.argv[1:], open({str(argfile)!r}, 'w'))\n"
                    f"print({json.dumps(json.dumps(model))})\n")
    fake.chmod(0o755)
    mod = load_module()
    args = mod.argparse.Namespace(kt=None, ratio=None, urt_config=str(fake), config="my.yaml")
    kt, ratio = mod.drive_constants(args)
    assert kt == pytest.approx([0.11, 0.12, 0.13, 0.14, 0.15, 0.16])
    assert ratio == pytest.approx([100, 101, 102, 103, 104, 105])
    assert json.loads(argfile.read_text()) == ["--print", "--json", "my.yaml"]

    # an explicit option wins over the model
    args.kt = "0.2"
    kt, ratio = mod.drive_constants(args)
    assert kt == [0.2] * 6 and ratio[5] == pytest.approx(105)


def test_plot_run__lowpass_keeps_dc_and_removes_fast_ripple():
    mod = load_module()
    fs = 2000.0
    t = np.arange(0.0, 2.0, 1.0 / fs)
    y = mod.butter2_lowpass(np.full_like(t, 3.0), 10.0, fs)
    assert np.max(np.abs(y - 3.0)) < 1e-12  # starts in steady state: no transient
    y = mod.butter2_lowpass(np.sin(2 * np.pi * 300 * t), 10.0, fs)
    assert np.max(np.abs(y[len(t) // 2:])) < 2e-3  # (10/300)² ≈ 1.1e-3
    y = mod.butter2_lowpass(np.sin(2 * np.pi * 10 * t), 10.0, fs)
    assert np.max(np.abs(y[len(t) // 2:])) == pytest.approx(1 / np.sqrt(2), rel=0.02)  # -3 dB

    ts, xs = mod.sample_at(t, t, 125.0)
    assert len(ts) == 250 and np.allclose(np.diff(ts), 1 / 125.0)
    assert np.all(xs <= ts + 1e-12) and np.all(ts - xs < 1 / fs)  # the latest sample, held


def test_plot_run__refuses_a_file_that_is_not_a_trace(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,x\n0,1\n1,2\n")
    res = subprocess.run([sys.executable, str(PLOT_RUN), str(bad), "--out", str(tmp_path / "o")],
                         capture_output=True, text=True, check=False)
    assert res.returncode != 0
    assert "missing columns" in res.stderr
