#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/dataset_demo.py — what `make dataset-demo` shows of a dataset (issue 11 item 6): the
faults' current signatures and a baseline detector's honest table.

    dataset_demo.py DATASET_DIR --sweep SWEEP.yaml --out DIR

For each run of the dataset (python -m urtwin.dataset) it computes the baseline detector's
residual, the measured current minus the current of the healthy twin (the same model,
trajectory, payload and unit with sensor noise off, run here with urtwin.run), as the RMS over
0.5 s windows per joint. The threshold per trajectory and joint is the largest window RMS of
the healthy runs of the train split times 1.2; a run is "detected" when any joint's window RMS
exceeds it. The healthy twin of a (trajectory, payload, unit) is run once and shared by all
its fault cases. Writes into DIR:

  signatures.png   per trajectory, the measured current per joint of each unit against the
                   healthy twin, and its amplitude spectrum
  faults.png       per fault class (the sweep's faults axis), the measured current of the
                   faulted joint (the shoulder for a collision) of the first unit at each
                   severity against that unit's healthy run, and for the periodic classes
                   (crack) its amplitude spectrum after the onset
  detector.md      the table: per trajectory, split, fault class and severity the runs
                   detected out of the runs; on healthy runs that is the false-alarm count
"""

import argparse
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pyarrow.parquet as pq  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))
import urtwin  # noqa: E402
from urtwin import dataset  # noqa: E402

NJ = 6
WINDOW_S = 0.5
MARGIN = 1.2


PERIODIC = {"crack", "wg_bearing", "transmission_error"}   # signatures that are spectral lines


def healthy_twin(sweep, side, cache={}):
    """The noise-free twin's true current for a run, at the run's sample times (one per
    trajectory, payload and unit: the fault cases share it)."""
    key = (side["trajectory"]["name"], side["payload"]["name"], side["seed"])
    if key not in cache:
        cache[key] = _healthy_twin(sweep, side)
    return cache[key]


def _healthy_twin(sweep, side):
    p = side["payload"]
    s = dict(sweep, overrides=list(sweep["overrides"]) + ["sensors.noise=false"])
    m = dataset.model_for(s, p)
    t = next(x for x in sweep["trajectories"] if x["name"] == side["trajectory"]["name"])
    tr = dataset.trajectory_for(m, t, side["seed"], sweep["duration"])
    r = urtwin.run(m, tr, duration=sweep["duration"], seed=side["seed"], decimate=side["decimate"])
    return r["i"]


def window_rms(res, n):
    """Largest RMS over consecutive windows of n samples, per joint."""
    k = res.shape[0] // n
    w = res[:k * n].reshape(k, n, NJ) if k > 0 else res[None]
    return np.sqrt(np.mean(w ** 2, axis=1)).max(axis=0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dataset")
    ap.add_argument("--sweep", required=True, help="the sweep file that made the dataset")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    d, out = Path(a.dataset), Path(a.out)
    sweep = dataset.load_sweep(a.sweep)
    out.mkdir(parents=True, exist_ok=True)
    index = pq.read_table(d / "index.parquet").to_pylist()

    rows = []
    for r in index:
        side = json.loads((d / "runs" / f"{r['run_id']}.json").read_text())
        t = pq.read_table(d / side["file"])
        meas = np.column_stack([t[f"actual_current_{j}"].to_numpy() for j in range(NJ)])
        twin = healthy_twin(sweep, side)
        n = max(1, int(round(WINDOW_S * side["output_rate"])))
        rows.append({**r, "time": t["timestamp"].to_numpy(), "meas": meas, "twin": twin,
                     "score": window_rms(meas - twin, n),
                     "fault": side.get("fault_case", "healthy") if side["faults"] else
                     "healthy",
                     "severity": "-" if side.get("severity_override") is None
                     else f"{side['severity_override']:g}",
                     "joint": next((f.get("joint", 1) for f in side["faults"]), None)})

    # thresholds from the healthy train runs, per trajectory and joint
    thr = {}
    for r in rows:
        if r["split"] == "train" and r["fault"] == "healthy":
            thr[r["trajectory"]] = np.maximum(thr.get(r["trajectory"], 0.0), r["score"])
    lines = ["# Baseline detector: residual against the healthy twin", "",
             f"Window RMS over {WINDOW_S} s of (measured current - healthy twin current), per "
             f"joint; threshold = {MARGIN} x the largest of the healthy train runs. On "
             "healthy runs a detection is a false alarm; a fault not detected is reported as "
             "such (0 / n), whatever the class.", "",
             "| trajectory | split | class | severity | detected / runs |",
             "|---|---|---|---|---|"]
    table = {}
    for r in rows:
        if r["trajectory"] not in thr:
            continue
        det = bool(np.any(r["score"] > MARGIN * thr[r["trajectory"]]))
        key = (r["trajectory"], r["split"], r["fault"], r["severity"])
        hit, n = table.get(key, (0, 0))
        table[key] = (hit + det, n + 1)
    def order(item):
        (traj, split, cls, sev), _ = item
        return (traj, cls != "healthy", cls, -1.0 if sev == "-" else float(sev), split)

    for (traj, split, cls, sev), (hit, n) in sorted(table.items(), key=order):
        lines.append(f"| {traj} | {split} | {cls} | {sev} | {hit} / {n} |")
    lines.append("")
    for traj, th in sorted(thr.items()):
        lines.append(f"threshold {traj} [A]: " + " ".join(f"{MARGIN * x:.4g}" for x in th))
    missing = sorted({r["trajectory"] for r in rows} - set(thr))
    if missing:
        lines += ["", f"No healthy train run (no threshold) for: {', '.join(missing)}"]
    (out / "detector.md").write_text("\n".join(lines) + "\n")

    trajs = sorted({r["trajectory"] for r in rows})
    fig, ax = plt.subplots(NJ, 2 * len(trajs), figsize=(7 * len(trajs), 2.0 * NJ),
                           squeeze=False)
    for c, traj in enumerate(trajs):
        for r in (x for x in rows if x["trajectory"] == traj and x["fault"] == "healthy"):
            for j in range(NJ):
                ax[j, 2 * c].plot(r["time"], r["meas"][:, j], lw=0.5,
                                  label=f"unit {r['unit']}")
                f = np.fft.rfftfreq(len(r["time"]), r["time"][1] - r["time"][0])
                spec = np.abs(np.fft.rfft(r["meas"][:, j] - r["meas"][:, j].mean()))
                ax[j, 2 * c + 1].semilogy(f[1:], spec[1:] + 1e-12, lw=0.5)
        r0 = next(x for x in rows if x["trajectory"] == traj and x["fault"] == "healthy")
        for j in range(NJ):
            ax[j, 2 * c].plot(r0["time"], r0["twin"][:, j], "k--", lw=0.7,
                             label=f"healthy twin of unit {r0['unit']}")
            ax[j, 2 * c].set_ylabel(f"J{j} [A]")
        ax[0, 2 * c].set_title(f"{traj}: measured current")
        ax[0, 2 * c + 1].set_title(f"{traj}: spectrum")
        ax[0, 2 * c].legend(fontsize=6)
        ax[-1, 2 * c].set_xlabel("t [s]")
        ax[-1, 2 * c + 1].set_xlabel("f [Hz]")
    fig.tight_layout()
    fig.savefig(out / "signatures.png", dpi=90)
    plt.close(fig)
    plot_faults(rows, out / "faults.png")
    print((out / "detector.md").read_text())
    return 0


def plot_faults(rows, path):
    """Per fault class, its current signature against the healthy run of the same unit."""
    classes = sorted({r["fault"] for r in rows} - {"healthy"})
    if not classes:
        return
    fig, ax = plt.subplots(len(classes), 2, figsize=(13, 1.9 * len(classes)), squeeze=False)
    for k, cls in enumerate(classes):
        runs = [r for r in rows if r["fault"] == cls]
        unit = min(r["unit"] for r in runs)
        runs = sorted((r for r in runs if r["unit"] == unit), key=lambda r: float(r["severity"]))
        healthy = next((r for r in rows if r["fault"] == "healthy" and r["unit"] == unit
                        and r["trajectory"] == runs[0]["trajectory"]), None)
        j = runs[0]["joint"] if runs[0]["joint"] is not None else 1
        a, b = ax[k, 0], ax[k, 1]
        if healthy is not None:
            a.plot(healthy["time"], healthy["meas"][:, j], "k", lw=0.6, label="healthy")
        for r in runs:
            a.plot(r["time"], r["meas"][:, j], lw=0.5, label=f"severity {r['severity']}")
        a.set_ylabel(f"J{j} [A]")
        a.set_title(f"{cls}: measured current, unit {unit}", fontsize=8)
        a.legend(fontsize=5, loc="upper right")
        if cls in PERIODIC:
            for r in ([healthy] if healthy is not None else []) + runs:
                after = r["time"] >= 2.0
                x = r["meas"][after, j] - r["meas"][after, j].mean()
                f = np.fft.rfftfreq(len(x), r["time"][1] - r["time"][0])
                lab = "healthy" if r is healthy else f"severity {r['severity']}"
                b.semilogy(f[1:], np.abs(np.fft.rfft(x))[1:] + 1e-12, lw=0.5, label=lab)
            b.set_title(f"{cls}: spectrum of the current after t = 2 s", fontsize=8)
            b.set_xlabel("f [Hz]")
            b.legend(fontsize=5)
        else:
            # the residual against the healthy run: where a slow signature shows
            for r in runs if healthy is not None else []:
                b.plot(r["time"], r["meas"][:, j] - healthy["meas"][:, j], lw=0.5,
                       label=f"severity {r['severity']}")
            b.set_title(f"{cls}: faulted minus healthy current", fontsize=8)
            b.legend(fontsize=5)
    ax[-1, 0].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
