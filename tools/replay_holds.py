#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/replay_holds.py — the standstill check of issue 10 on replay traces
(`urt_sim --replay REC.csv --out TRACE`): find the holds and compare the twin's current drift
with the real robot's.

    replay_holds.py TRACE... [--window 5] [--settle 0.5] [--margin 0.05] [--json OUT]

A hold of joint j is a stretch where its set-point stands still (target_qd_j = 0 and target_q_j
changing by less than 1e-4 rad a sample); an arm hold, where every joint's does. Over every window of --window seconds inside
a hold, starting --settle seconds after the hold began and sliding by 0.25 s, the drift of a
current is |mean over the window's last 0.5 s − mean over its first 0.5 s|. A window passes when
the twin's drift is at most the measured drift + --margin. Holds shorter than settle + window
are listed with their own (shorter) window, marked "short", and do not count for the verdict.
Exit status: 0 every full window passes, 1 some window fails, 2 bad input.
"""

import argparse
import json
import sys

import numpy as np

NJ = 6
AVG = 0.5  # [s] the averaging span at each end of a window
STEP = 0.25  # [s] window slide


def read_trace(path):
    with open(path) as f:
        header = f.readline().split()
    data = np.loadtxt(path, skiprows=1, ndmin=2)
    cols = {n: data[:, i] for i, n in enumerate(header)}
    need = ["timestamp"] + [f"{c}_{j}" for c in ("target_q", "target_qd", "actual_current",
                                                 "twin_current") for j in range(NJ)]
    missing = [c for c in need if c not in cols]
    if missing:
        raise ValueError(f"{path}: not a replay trace (missing {', '.join(missing[:3])} ...)")
    return cols


def runs(mask):
    """(first, last) index pairs of the True runs of mask."""
    out, i, n = [], 0, len(mask)
    while i < n:
        if mask[i]:
            k = i
            while k + 1 < n and mask[k + 1]:
                k += 1
            out.append((i, k))
            i = k + 1
        else:
            i += 1
    return out


def still_mask(cols, j):
    qd = cols[f"target_qd_{j}"]
    q = cols[f"target_q_{j}"]
    dq = np.concatenate([[0.0], np.abs(np.diff(q))])
    # the files print 6 digits; a hold's target may also follow the measured position by a
    # few of them (UR's controller after a move)
    return (np.abs(qd) < 1e-9) & (dq < 1e-4)


def drift(t, x, a, b):
    first = (t >= a) & (t < a + AVG)
    last = (t > b - AVG) & (t <= b)
    if not first.any() or not last.any():
        return float("nan")
    return abs(float(x[last].mean() - x[first].mean()))


def holds_of(cols, window, settle, margin):
    t = cols["timestamp"]
    arm = np.all([still_mask(cols, j) for j in range(NJ)], axis=0)
    found = []
    for who, mask in [("arm", arm)] + [(j, still_mask(cols, j)) for j in range(NJ)]:
        for i, k in runs(mask):
            t_a, t_b = t[i] + settle, t[k]
            length = t_b - t_a
            if length < 2 * AVG + STEP:
                continue
            short = length < window
            w = window if not short else length
            joints = range(NJ) if who == "arm" else [who]
            worst = {}
            a = t_a
            while a + w <= t_b + 1e-9:
                for j in joints:
                    real = drift(t, cols[f"actual_current_{j}"], a, a + w)
                    twin = drift(t, cols[f"twin_current_{j}"], a, a + w)
                    excess = twin - real
                    if j not in worst or excess > worst[j]["excess"]:
                        worst[j] = {"joint": j, "from": round(a, 3), "to": round(a + w, 3),
                                    "real": real, "twin": twin, "excess": excess,
                                    "ok": bool(twin <= real + margin)}
                a += STEP
            found.append({"who": who, "start": float(t[i]), "end": float(t[k]),
                          "window": w, "short": bool(short), "joints": list(worst.values())})
    return found


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("traces", nargs="+")
    ap.add_argument("--window", type=float, default=5.0)
    ap.add_argument("--settle", type=float, default=0.5)
    ap.add_argument("--margin", type=float, default=0.05)
    ap.add_argument("--json", help="write every hold and window result here")
    a = ap.parse_args(argv)
    report, failed, full = [], 0, 0
    for path in a.traces:
        try:
            cols = read_trace(path)
        except (OSError, ValueError) as e:
            print(f"replay_holds: {e}", file=sys.stderr)
            return 2
        for h in holds_of(cols, a.window, a.settle, a.margin):
            h["trace"] = path
            report.append(h)
            for r in h["joints"]:
                tag = "short" if h["short"] else ("ok" if r["ok"] else "FAIL")
                if not h["short"]:
                    full += 1
                    failed += not r["ok"]
                print(f"{path}: {h['who']} hold {h['start']:.2f}-{h['end']:.2f} s, joint "
                      f"{r['joint']}: window {r['from']:.2f}-{r['to']:.2f} s drift real "
                      f"{r['real']:.3f} A twin {r['twin']:.3f} A  {tag}")
    print(f"{full} full {a.window:g} s windows checked (worst per hold and joint), "
          f"{failed} over the real drift + {a.margin:g} A")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(report, f, indent=1)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
