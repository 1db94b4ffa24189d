# SPDX-License-Identifier: Apache-2.0
"""urt_sim's own CSV as a recording in RTDE record.py's layout: the synthetic "real robot" of
the calibration and replay tests (urtwin's run with known parameters, replayed or fitted)."""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
import urt_recording  # noqa: E402


def to_record_layout(sim_csv, out, every=8):
    """urt_sim's CSV (1 kHz) → record.py layout at 125 Hz; q̇, q̈ of the set-point by central
    differences on the 1 kHz grid (the excitation is a smooth Fourier series)."""
    header = sim_csv.read_text().split("\n", 1)[0].split(",")
    d = np.loadtxt(sim_csv, delimiter=",", skiprows=1)
    t = d[:, 0]
    col = lambda n: np.stack([d[:, header.index(f"{n}_{j + 1}")] for j in range(6)], axis=1)
    q = col("q_set")
    qd = np.gradient(q, t[1] - t[0], axis=0, edge_order=2)
    qdd = np.gradient(qd, t[1] - t[0], axis=0, edge_order=2)
    s = slice(0, None, every)
    urt_recording.write_recording(out, t[s], {"target_q": q[s], "target_qd": qd[s],
                                              "target_qdd": qdd[s],
                                              "actual_current": col("i_meas")[s]})
    return out
