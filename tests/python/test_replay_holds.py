# SPDX-License-Identifier: Apache-2.0
"""tools/replay_holds.py, the standstill check on replay traces: holds are found per joint and
for the whole arm, drifts are measured over sliding windows, and the verdict compares the twin's
drift with the measured one plus the margin. Synthetic traces, no simulation."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "replay_holds.py"
NJ = 6


def trace(path, t, qd, real, twin):
    """A replay trace in urt_sim --replay --out's layout (the columns the tool reads)."""
    q = np.cumsum(qd, axis=0) * 0.008
    names = ["timestamp"] + [f"{c}_{j}" for c in ("target_q", "target_qd", "actual_current",
                                                  "twin_current") for j in range(NJ)]
    np.savetxt(path, np.hstack([t[:, None], q, qd, real, twin]), fmt="%.9g",
               header=" ".join(names), comments="")
    return path


def run(*args):
    return subprocess.run([sys.executable, str(TOOL), *map(str, args)], capture_output=True,
                          text=True, timeout=60)


def make(tmp_path, creep):
    """Joint 0 moves until 1 s, then the arm holds for 7 s; the twin's wrist 1 current creeps
    by `creep` A over the hold while the measured one stays flat."""
    t = np.round(np.arange(0.0, 8.0, 0.008), 6)
    n = len(t)
    qd = np.zeros((n, NJ))
    qd[t < 1.0, 0] = 0.5
    real = np.ones((n, NJ))
    twin = np.ones((n, NJ))
    twin[:, 3] += creep * np.clip(t - 1.0, 0.0, None) / 7.0
    return trace(tmp_path / "tr.txt", t, qd, real, twin)


def test_replay_holds__flat_twin_passes(tmp_path):
    res = run(make(tmp_path, creep=0.02), "--json", tmp_path / "h.json")
    assert res.returncode == 0, res.stdout + res.stderr
    holds = json.loads((tmp_path / "h.json").read_text())
    arm = [h for h in holds if h["who"] == "arm"]
    assert len(arm) == 1 and not arm[0]["short"]
    assert arm[0]["start"] == 1.0 and arm[0]["window"] == 5.0
    w1 = [r for r in arm[0]["joints"] if r["joint"] == 3][0]
    assert 0.01 < w1["twin"] < 0.02 and w1["real"] == 0.0 and w1["ok"]


def test_replay_holds__creep_over_the_margin_fails(tmp_path):
    res = run(make(tmp_path, creep=0.4))
    assert res.returncode == 1
    assert "FAIL" in res.stdout
    # 0.4 A over 7 s: a 5 s window (after the 0.5 s settle) sees about 0.26 A
    line = [s for s in res.stdout.splitlines() if "arm hold" in s and "joint 3" in s][0]
    twin = float(line.split("twin ")[1].split(" A")[0])
    assert 0.2 < twin < 0.3


def test_replay_holds__a_short_hold_is_listed_but_not_judged(tmp_path):
    res = run(make(tmp_path, creep=0.4), "--window", "8")
    assert res.returncode == 0
    assert "short" in res.stdout and "0 full 8 s windows" in res.stdout


def test_replay_holds__bad_trace_is_exit_2(tmp_path):
    p = tmp_path / "x.txt"
    p.write_text("timestamp a\n0 1\n0.1 2\n")
    res = run(p)
    assert res.returncode == 2 and "not a replay trace" in res.stderr
