# SPDX-License-Identifier: Apache-2.0
"""tools/urt_replay_judge.py, the twin's judgement behind urt_identify --holdout,
--leave-one-out and --relax: the replay table's verdict counts only the joints that move, and
the relaxation rates reach urt_sim as one --set per joint. (The replays themselves run through
urt_sim in test_urt_identify.py.)"""

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))

import urt_replay_judge as judge  # noqa: E402


def summary(twin, ur):
    return {"joints": [{"rms_meas": 1.0, "rms_err_twin": t, "rms_err_ur": u, "ratio_twin": t,
                        "ratio_ur": u, "corr_twin": 0.9} for t, u in zip(twin, ur)]}


def test_replay_judge__the_verdict_counts_moving_joints_only():
    moving = np.array([True, True, False, False, False, False])
    twin = [0.3, 0.4, 0.9, 0.1, 0.1, 0.1]
    ur = [0.5, 0.5, 0.5, 0.5, 0.5, 0.5]
    table, ok = judge.replay_table(Path("r.csv"), summary(twin, ur), moving, "overlay o.yaml")
    assert ok  # the elbow is worse than UR but does not move
    rows = table.splitlines()
    assert rows[0] == "r.csv (overlay o.yaml): RMS current [A]"
    assert rows[5].startswith("| elbow | no |") and rows[5].endswith("| - |")
    twin[1] = 0.51
    table, ok = judge.replay_table(Path("r.csv"), summary(twin, ur), moving, "x")
    assert not ok and table.splitlines()[4].endswith("| NO |")
    # a recording without target_current: nothing to compare, nothing fails
    _, ok = judge.replay_table(Path("r.csv"), summary(twin, [None] * 6), moving, "x")
    assert ok


def test_replay_judge__relax_rates_are_one_set_per_joint_and_moving_is_a_range():
    assert judge.relax_sets(300) == [f"joints.{j}.friction.relax=300" for j in range(6)]
    assert judge.relax_sets([0, 100, 1000, 0, 1e3, 0.5])[1:3] == [
        "joints.1.friction.relax=100", "joints.2.friction.relax=1000"]
    q = np.zeros((10, 6))
    q[:, 2] = np.linspace(0.0, 0.051, 10)
    q[:, 4] = np.linspace(0.0, 0.049, 10)
    assert judge.moving_joints({"target_q": q}).tolist() == [False, False, True, False, False,
                                                              False]
