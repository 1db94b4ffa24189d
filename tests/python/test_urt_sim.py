# SPDX-License-Identifier: Apache-2.0
"""tools/urt_sim: the CSV layout, bit-identical output for a seed, decimation, the exit status of
configuration and trajectory errors, and --compare's files. Short runs only (tens of ms)."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import built

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("URT_BUILD", ROOT / "build"))
URT_SIM = BUILD / "tools" / "urt_sim"
CONFIG = ROOT / "config" / "ur5.yaml"
COLS = ("q_set", "q", "qd", "qm", "qdm", "i", "i_meas", "v", "tcs", "tf")

built.require(URT_SIM)


def sim(*args, ok=True):
    res = subprocess.run([str(URT_SIM), "--config", str(CONFIG), "--quiet", *map(str, args)],
                         capture_output=True, text=True, check=False, cwd=ROOT)
    if ok:
        assert res.returncode == 0, res.stderr
    return res


def read(path):
    header = path.read_text().split("\n", 1)[0].split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def test_urt_sim__writes_the_documented_columns(tmp_path):
    out = tmp_path / "hold.csv"
    sim("--traj", "hold", "--duration", "0.01", "--out", out)
    header, data = read(out)
    expect = ["t"] + [f"{c}_{j}" for j in range(1, 7) for c in COLS] + \
        ["tcp_x", "tcp_y", "tcp_z", "tcp_rx", "tcp_ry", "tcp_rz"]
    assert header == expect
    assert data.shape == (201, len(expect))  # t = 0 .. 0.01 s at 20 kHz, both ends
    assert np.allclose(np.diff(data[:, 0]), 5e-5)
    assert np.all(np.isfinite(data))


def test_urt_sim__same_seed_gives_identical_bytes(tmp_path):
    a, b, c = tmp_path / "a.csv", tmp_path / "b.csv", tmp_path / "c.csv"
    sim("--traj", "excitation", "--seed", "3", "--duration", "0.02", "--out", a)
    sim("--traj", "excitation", "--seed", "3", "--duration", "0.02", "--out", b)
    sim("--traj", "excitation", "--seed", "4", "--duration", "0.02", "--out", c)
    assert a.read_bytes() == b.read_bytes()
    assert a.read_bytes() != c.read_bytes()


def test_urt_sim__decimate_keeps_every_nth_row(tmp_path):
    full, dec = tmp_path / "full.csv", tmp_path / "dec.csv"
    sim("--traj", "excitation", "--duration", "0.01", "--out", full)
    sim("--traj", "excitation", "--duration", "0.01", "--decimate", "7", "--out", dec)
    rows = full.read_text().splitlines()
    want = [rows[0]] + rows[1::7]
    if (len(rows) - 2) % 7:
        want.append(rows[-1])  # the last step is always written
    assert dec.read_text().splitlines() == want


def test_urt_sim__config_errors_exit_2_with_the_loader_message(tmp_path):
    res = sim("--config", tmp_path / "missing.yaml", ok=False)
    assert res.returncode == 2 and "missing.yaml" in res.stderr
    res = sim("--set", "no.such.key=1", ok=False)
    assert res.returncode == 2 and "override" in res.stderr  # "file:override: key: reason"


def test_urt_sim__refuses_a_trajectory_the_model_would_refuse():
    # the stress stop needs 2500°/s² = 43.6 rad/s² on wrist 2
    res = sim("--traj", "pickplace", "--set", "joints.4.qdd_max=40", ok=False)
    assert res.returncode == 2
    assert "joint 5" in res.stderr and "peak acceleration" in res.stderr
    sim("--traj", "pickplace", "--set", "joints.4.qdd_max=50", "--duration", "0.005")


def test_urt_sim__bad_options_exit_2():
    for args in (["--traj", "dance"], ["--rate", "-5"], ["--decimate", "0"],
                 ["--reference", "--compare"], ["--realtime", "--compare"], ["stray"]):
        assert sim(*args, ok=False).returncode == 2, args


def test_urt_sim__compare_writes_both_traces_and_a_summary(tmp_path):
    res = sim("--traj", "excitation", "--duration", "0.002", "--compare", "--out",
              tmp_path / "cmp")
    for name in ("fixed.csv", "reference.csv", "summary.txt"):
        assert (tmp_path / "cmp" / name).is_file()
    hf, f = read(tmp_path / "cmp" / "fixed.csv")
    hr, r = read(tmp_path / "cmp" / "reference.csv")
    assert hf == hr and f.shape == r.shape
    assert np.array_equal(f[:, 0], r[:, 0])
    assert "max|dq| [rad]" in res.stdout and "shoulder" in res.stdout

    # PATH.csv names the two traces after it
    sim("--traj", "hold", "--duration", "0.001", "--compare", "--out", tmp_path / "x.csv")
    assert (tmp_path / "x.fixed.csv").is_file() and (tmp_path / "x.reference.csv").is_file()


def test_urt_sim__trace_feeds_plot_run(tmp_path):
    out = tmp_path / "run.csv"
    sim("--traj", "excitation", "--duration", "0.05", "--decimate", "5", "--out", out)
    res = subprocess.run([sys.executable, str(ROOT / "tools" / "plot_run.py"), str(out), "--out",
                          str(tmp_path / "plots"), "--kt", "0.1", "--ratio", "101"],
                         capture_output=True, text=True, check=False)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "plots" / "torque.png").is_file()
