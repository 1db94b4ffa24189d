#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/plot_run.py — plot an urt_sim CSV trace the way the paper's Figs. 7–12 do.

    plot_run.py RUN.csv --out DIR [--ref REF.csv] [--kt K] [--ratio R] [--lpf HZ] [--show-rate HZ]

Writes into DIR:
  positions.png       q_set and q per joint [deg] against time (Figs. 7, 10)
  tracking_error.png  q_set − q per joint [deg] (Figs. 8, 11)
  torque.png          T = i_meas · k_t · τ per joint [N m]: the raw trace, and the same after a
                      10 Hz low-pass sampled at 125 Hz as in the paper (Figs. 9, 12)
  compare.png         with --ref: q − q_ref [deg] and i − i_ref [A] per joint (e.g. the fixed-step
                      and CVODE traces of `urt_sim --compare --out DIR`)

k_t and τ come from --kt/--ratio if given, else from `urt_config --json CONFIG` (the fully resolved
model: joints[j].motor.kt and joints[j].gear.ratio), else from the paper's Table 2 and τ = 101
with a note on stderr. The 10 Hz filter is a causal 2nd-order Butterworth (the paper does not say
which filter it used).
"""

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: no display on build machines
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

NJ = 6
ROOT = Path(__file__).resolve().parents[1]
JOINT_NAMES = ["base", "shoulder", "elbow", "wrist 1", "wrist 2", "wrist 3"]
# paper Table 2 and τ = Z_CS/(Z_CS − Z_FS) = 101: only the last resort
PAPER_KT = [0.1350, 0.1361, 0.1355, 0.0957, 0.0865, 0.0893]
PAPER_RATIO = 101.0


# ---- input ------------------------------------------------------------------------------------

def read_run(path):
    """The CSV as a dict of column name -> 1-D array."""
    with open(path, encoding="ascii") as f:
        header = f.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if data.shape[1] != len(header):
        raise SystemExit(f"{path}: {data.shape[1]} columns but {len(header)} names in the header")
    need = ["t"] + [f"{c}_{j}" for j in range(1, NJ + 1) for c in ("q_set", "q", "i", "i_meas")]
    missing = [c for c in need if c not in header]
    if missing:
        raise SystemExit(f"{path}: missing columns {', '.join(missing)} (not an urt_sim trace?)")
    return {name: data[:, k] for k, name in enumerate(header)}


def per_joint(text, what):
    """'0.1' or '0.1,0.2,...' (six values) -> list of six floats."""
    vals = [float(v) for v in text.split(",")]
    if len(vals) == 1:
        vals *= NJ
    if len(vals) != NJ:
        raise SystemExit(f"--{what}: expected 1 or {NJ} comma-separated values, got {len(vals)}")
    return vals


def urt_config_path(explicit):
    if explicit:
        return Path(explicit)
    build = Path(os.environ.get("URT_BUILD", ROOT / "build"))
    return build / "tools" / "urt_config"


def drive_constants(args):
    """(kt[6], ratio[6]) from the options, the resolved model, or the paper."""
    kt = per_joint(args.kt, "kt") if args.kt else None
    ratio = per_joint(args.ratio, "ratio") if args.ratio else None
    if kt and ratio:
        return kt, ratio

    tool = urt_config_path(args.urt_config)
    if os.access(tool, os.X_OK):
        cmd = [str(tool), "--print", "--json", str(args.config)]
        res = subprocess.run(cmd, capture_output=True, text=True, check=False)
        if res.returncode == 0:
            joints = json.loads(res.stdout)["joints"]
            kt = kt or [float(j["motor"]["kt"]) for j in joints]
            ratio = ratio or [float(j["gear"]["ratio"]) for j in joints]
            return kt, ratio
        print(f"plot_run: {' '.join(cmd)} failed: {res.stderr.strip()}", file=sys.stderr)

    print("plot_run: k_t and ratio not given and urt_config not usable; using the paper's "
          "Table 2 k_t and ratio 101", file=sys.stderr)
    return kt or PAPER_KT, ratio or [PAPER_RATIO] * NJ


# ---- signal processing ------------------------------------------------------------------------

def butter2_lowpass(x, fc, fs):
    """Causal 2nd-order Butterworth low-pass (bilinear transform, prewarped), started at rest
    on x[0] so that a constant signal passes unchanged. Pure numpy: scipy is not a dependency."""
    k = np.tan(np.pi * fc / fs)
    q = np.sqrt(2.0)
    norm = 1.0 / (1.0 + q * k + k * k)
    b0 = k * k * norm
    b1, b2 = 2.0 * b0, b0
    a1 = 2.0 * (k * k - 1.0) * norm
    a2 = (1.0 - q * k + k * k) * norm
    y = np.empty_like(x, dtype=float)
    # direct form II transposed; the state starts at the DC steady state of x[0]
    x0 = float(x[0])
    z1 = x0 * (1.0 - b0)
    z2 = x0 * (b2 - a2)
    for n, xn in enumerate(x.tolist()):
        yn = b0 * xn + z1
        z1 = b1 * xn - a1 * yn + z2
        z2 = b2 * xn - a2 * yn
        y[n] = yn
    return y


def sample_at(t, x, rate):
    """x sampled and held at t[0] + k/rate within t's span, like the paper's 125 Hz logger:
    returns the logger's instants and the latest value of x at each."""
    n = int(np.floor((t[-1] - t[0]) * rate + 1e-9)) + 1
    ts = t[0] + np.arange(n) / rate
    idx = np.clip(np.searchsorted(t, ts + 1e-12, side="right") - 1, 0, len(t) - 1)
    return ts, x[idx]


# ---- figures ----------------------------------------------------------------------------------

def joint_grid(title):
    fig, axes = plt.subplots(3, 2, figsize=(12, 9), sharex=True)
    fig.suptitle(title)
    axes = axes.T.ravel()  # column-major: joints 1–3 left, 4–6 right, as in the paper
    for j, ax in enumerate(axes):
        ax.set_title(f"joint {j + 1} ({JOINT_NAMES[j]})", fontsize=10)
        ax.grid(True, alpha=0.3)
    for ax in (axes[2], axes[5]):
        ax.set_xlabel("t [s]")
    return fig, axes


def save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(path)


def plot_positions(run, out, name):
    fig, axes = joint_grid(f"{name}: set-point and joint position")
    t = run["t"]
    for j, ax in enumerate(axes, start=1):
        ax.plot(t, np.degrees(run[f"q_set_{j}"]), "k--", lw=1.0, label="q_set")
        ax.plot(t, np.degrees(run[f"q_{j}"]), "C0", lw=0.8, label="q (model)")
        ax.set_ylabel("[deg]")
    axes[0].legend(fontsize=8)
    save(fig, out / "positions.png")


def plot_tracking(run, out, name):
    fig, axes = joint_grid(f"{name}: tracking error q_set − q")
    t = run["t"]
    for j, ax in enumerate(axes, start=1):
        e = np.degrees(run[f"q_set_{j}"] - run[f"q_{j}"])
        ax.plot(t, e, "C3", lw=0.8)
        ax.set_ylabel("[deg]")
        peak = np.max(np.abs(e)) if e.size else 0.0
        ax.text(0.99, 0.95, f"max |e| = {peak:.4f}°", transform=ax.transAxes, ha="right",
                va="top", fontsize=8)
    save(fig, out / "tracking_error.png")


def plot_torque(run, out, name, kt, ratio, lpf, show_rate):
    fig, axes = joint_grid(f"{name}: joint torque T = i_meas · k_t · τ")
    t = run["t"]
    fs = (len(t) - 1) / (t[-1] - t[0]) if len(t) > 1 and t[-1] > t[0] else 0.0
    for j, ax in enumerate(axes, start=1):
        T = run[f"i_meas_{j}"] * kt[j - 1] * ratio[j - 1]
        ax.plot(t, T, color="0.75", lw=0.5, label="raw")
        label = []
        Tf = T
        if lpf > 0 and fs > 2 * lpf:
            Tf = butter2_lowpass(T, lpf, fs)
            label.append(f"{lpf:g} Hz low-pass")
        tf = t
        if show_rate > 0 and fs > show_rate:
            tf, Tf = sample_at(t, Tf, show_rate)
            label.append(f"at {show_rate:g} Hz")
        if label:
            ax.plot(tf, Tf, "C0", lw=1.0, label=", ".join(label))
        ax.set_ylabel("[N m]")
    axes[0].legend(fontsize=8)
    save(fig, out / "torque.png")


def plot_compare(run, ref, out, name):
    n = min(len(run["t"]), len(ref["t"]))
    if n == 0:
        return
    t = run["t"][:n]
    if not np.allclose(t, ref["t"][:n], rtol=0, atol=1e-9):
        raise SystemExit("--ref: the two traces are not sampled at the same times")
    fig, axes = joint_grid(f"{name} against the reference: q − q_ref (deg, left axis), "
                           "i − i_ref (A, right axis)")
    for j, ax in enumerate(axes, start=1):
        ax.plot(t, np.degrees(run[f"q_{j}"][:n] - ref[f"q_{j}"][:n]), "C0", lw=0.8)
        ax.set_ylabel("Δq [deg]", color="C0")
        ax2 = ax.twinx()
        ax2.plot(t, run[f"i_{j}"][:n] - ref[f"i_{j}"][:n], "C1", lw=0.5)
        ax2.set_ylabel("Δi [A]", color="C1")
    save(fig, out / "compare.png")


# ---- main -------------------------------------------------------------------------------------

def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv", help="urt_sim trace (urt_sim --out RUN.csv)")
    ap.add_argument("--out", required=True, help="directory for the PNG files")
    ap.add_argument("--ref", help="a second trace to difference against (e.g. the CVODE one)")
    ap.add_argument("--kt", help="torque constant [N m/A]: one value or six, comma-separated")
    ap.add_argument("--ratio", help="gear ratio τ: one value or six, comma-separated")
    ap.add_argument("--config", default=str(ROOT / "config" / "ur5.yaml"),
                    help="robot parameter file for urt_config (default config/ur5.yaml)")
    ap.add_argument("--urt-config", help="urt_config binary (default $URT_BUILD/tools/urt_config "
                    "or build/tools/urt_config)")
    ap.add_argument("--lpf", type=float, default=10.0,
                    help="torque low-pass cut-off [Hz], 0 = off (default 10, as in the paper)")
    ap.add_argument("--show-rate", type=float, default=125.0,
                    help="rate the filtered torque is shown at [Hz], 0 = every sample "
                    "(default 125, the RTDE logging rate of the paper)")
    args = ap.parse_args(argv)

    run = read_run(args.csv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    name = Path(args.csv).stem
    kt, ratio = drive_constants(args)

    plot_positions(run, out, name)
    plot_tracking(run, out, name)
    plot_torque(run, out, name, kt, ratio, args.lpf, args.show_rate)
    if args.ref:
        plot_compare(run, read_run(args.ref), out, name)
    return 0


if __name__ == "__main__":
    sys.exit(main())
