#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/plot_replay.py — plot a replay trace (`urt_sim --replay REC.csv --out TRACE`) the way
the paper's Figs. 8–9 compare model and robot.

    plot_replay.py TRACE --out DIR

Writes into DIR one PNG per joint, current_<j>_<name>.png: above, the measured motor current,
the twin's and UR's own target_current (when the recording has it) against time [A]; below,
the residuals twin − measured and target_current − measured [A]. `urt_sim --plot DIR` runs it.
"""

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: no display on build machines
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

NJ = 6
JOINT_NAMES = ["base", "shoulder", "elbow", "wrist1", "wrist2", "wrist3"]


def read_trace(path):
    """The trace's columns by name (space-separated, one header line)."""
    with open(path) as f:
        header = f.readline().split()
    data = np.loadtxt(path, skiprows=1, ndmin=2)
    if data.shape[1] != len(header):
        raise ValueError(f"{path}: {data.shape[1]} columns, header has {len(header)}")
    return {name: data[:, i] for i, name in enumerate(header)}


def plot_joint(cols, j, out):
    t = cols["timestamp"]
    meas = cols[f"actual_current_{j}"]
    twin = cols[f"twin_current_{j}"]
    ur = cols.get(f"target_current_{j}")
    fig, (ax, ax_r) = plt.subplots(2, 1, sharex=True, figsize=(10, 6),
                                   gridspec_kw={"height_ratios": [2, 1]})
    ax.plot(t, meas, color="black", lw=0.8, label="measured")
    ax.plot(t, twin, color="tab:blue", lw=0.8, label="urtwin")
    if ur is not None:
        ax.plot(t, ur, color="tab:orange", lw=0.8, ls="--", label="UR target_current")
    ax.set_ylabel("motor current [A]")
    ax.set_title(f"joint {j} ({JOINT_NAMES[j]})")
    ax.legend(loc="upper right", fontsize="small")
    ax.grid(alpha=0.3)
    ax_r.plot(t, twin - meas, color="tab:blue", lw=0.8, label="urtwin − measured")
    if ur is not None:
        ax_r.plot(t, ur - meas, color="tab:orange", lw=0.8, ls="--",
                  label="target_current − measured")
    ax_r.axhline(0.0, color="black", lw=0.5)
    ax_r.set_ylabel("residual [A]")
    ax_r.set_xlabel("t [s]")
    ax_r.legend(loc="upper right", fontsize="small")
    ax_r.grid(alpha=0.3)
    fig.tight_layout()
    path = out / f"current_{j}_{JOINT_NAMES[j]}.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("trace", help="urt_sim --replay --out trace")
    ap.add_argument("--out", required=True, help="directory for the PNGs")
    a = ap.parse_args(argv)
    try:
        cols = read_trace(a.trace)
        missing = [c for j in range(NJ) for c in (f"actual_current_{j}", f"twin_current_{j}")
                   if c not in cols]
        if "timestamp" not in cols or missing:
            raise ValueError(f"{a.trace}: not a replay trace (missing "
                             f"{', '.join(missing) or 'timestamp'})")
    except (OSError, ValueError) as e:
        print(f"plot_replay: {e}", file=sys.stderr)
        return 2
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    for j in range(NJ):
        print(plot_joint(cols, j, out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
