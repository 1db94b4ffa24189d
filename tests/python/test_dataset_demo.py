# SPDX-License-Identifier: Apache-2.0
"""tools/dataset_demo.py on a tiny healthy dataset (four 0.6 s runs, in-process): the residual
against the noise-free healthy twin is of the noise's order (the same motion and model), the
table has a row per trajectory and split, and the signature plot is written. And on a tiny
faulted one (four 0.6 s runs): a current-sensor offset far above the noise is detected in both
splits, and the per-class signature plot is written."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
if not list((ROOT / "python" / "urtwin").glob("_urtwin*.so")):
    pytest.fail("python/urtwin/_urtwin*.so is not built: run make build", pytrace=False)


def sweep_and_demo(tmp_path):
    """The sweep tmp_path/s.yaml in-process, then tools/dataset_demo.py on it: its table."""
    env = dict(os.environ, PYTHONPATH=str(ROOT / "python"))
    res = subprocess.run([sys.executable, "-m", "urtwin.dataset", tmp_path / "s.yaml", "--out",
                          tmp_path / "data", "--no-ray", "--quiet"], env=env,
                         capture_output=True, text=True, check=False, timeout=300)
    assert res.returncode == 0, res.stderr
    res = subprocess.run([sys.executable, ROOT / "tools" / "dataset_demo.py", tmp_path / "data",
                          "--sweep", tmp_path / "s.yaml", "--out", tmp_path / "demo"], env=env,
                         capture_output=True, text=True, check=False, timeout=300)
    assert res.returncode == 0, res.stderr
    return (tmp_path / "demo" / "detector.md").read_text()


def test_demo_on_a_tiny_dataset(tmp_path):
    (tmp_path / "s.yaml").write_text(
        "duration: 0.6\ntrajectories: [excitation]\nseeds: [1, 2, 3, 4]\n"
        "splits: {train: [1, 2], test: [3, 4]}\n")
    table = sweep_and_demo(tmp_path)
    # the train runs set the threshold, so none of them is above 1.2 times it
    assert re.search(r"\| excitation \| train \| healthy \| - \| 0 / 2 \|", table), table
    assert re.search(r"\| excitation \| test \| healthy \| - \| [0-2] / 2 \|", table), table
    # the twin follows the same motion: the thresholds are the noise's order (0.1–0.25 A here),
    # where a twin of another excitation or payload would be amperes off
    thr = [float(x) for x in re.search(r"threshold excitation \[A\]: (.*)", table)[1].split()]
    assert len(thr) == 6 and all(0 < x < 0.5 for x in thr), thr
    assert (tmp_path / "demo" / "signatures.png").stat().st_size > 10000


def test_demo_on_a_tiny_faulted_dataset(tmp_path):
    # two units, healthy and a current-sensor offset of 0.5 A on the shoulder (the catalogue's
    # 5 % of i_max): the residual is the offset itself, several times the noise's thresholds
    (tmp_path / "s.yaml").write_text(
        "duration: 0.6\ntrajectories: [excitation]\nseeds: [1, 2]\n"
        "splits: {train: [1], test: [2]}\nfaults:\n  - healthy\n"
        "  - {name: current_offset, faults: [{class: current_offset, joint: 1, severity: 0.5,"
        " unit: A, profile: {kind: step, onset: 0.0}}], severities: [0.5]}\n")
    table = sweep_and_demo(tmp_path)
    assert re.search(r"\| excitation \| train \| healthy \| - \| 0 / 1 \|", table), table
    for split in ("train", "test"):
        assert re.search(rf"\| excitation \| {split} \| current_offset \| 0\.5 \| 1 / 1 \|",
                         table), table
    assert (tmp_path / "demo" / "faults.png").stat().st_size > 10000
