# SPDX-License-Identifier: Apache-2.0
"""The twin's judgement of a calibration, for tools/urt_identify.py: replays of recordings
through urtwin itself (urt_sim --replay … --summary-json), the replay table against UR's own
target_current, and the bristle relaxation rates chosen by those replays."""

import json
import os
import subprocess
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
NJ = 6
MOVE_RANGE = 0.05       # [rad] a joint "moves" in a file beyond this range (issue 10)


class UsageError(Exception):
    pass


def build_dir():
    return Path(os.environ.get("URT_BUILD", ROOT / "build"))


def tool(name):
    """A built urtwin executable (URT_BUILD, default build/)."""
    path = build_dir() / "tools" / name
    if not os.access(path, os.X_OK):
        raise UsageError(f"{path} is not built (make build, or set URT_BUILD)")
    return str(path)


def moving_joints(rec):
    """Which joints move in a recording: range of target_q over MOVE_RANGE (issue 10)."""
    return (rec["target_q"].max(axis=0) - rec["target_q"].min(axis=0)) > MOVE_RANGE


def replay(path, overlay=None, config=None, sets=(), rate=None, sim=None, timeout=None):
    """The twin's replay summary of one recording (urt_sim --replay … --summary-json), with
    --set KEY=VALUE for each of sets, at the config's rate or `rate` [Hz]; sim: the urt_sim to
    run (default the built one), timeout [s] (subprocess.TimeoutExpired past it)."""
    sim = sim or tool("urt_sim")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "summary.json"
        args = [str(sim), "--quiet", "--replay", str(path), "--summary-json", str(out)]
        if config:
            args += ["--config", str(config)]
        if overlay:
            args += ["--overlay", str(overlay)]
        for kv in sets:
            args += ["--set", kv]
        if rate:
            args += ["--rate", str(rate)]
        r = subprocess.run(args, capture_output=True, text=True, cwd=ROOT, timeout=timeout)
        if r.returncode != 0:
            raise RuntimeError(f"urt_sim --replay {path} failed ({r.returncode}): "
                               f"{r.stderr.strip()[-500:]}")
        return json.loads(out.read_text())


def replay_table(path, summary, moving, label):
    """The replay table as markdown, and whether the twin's error is at most UR's on every
    moving joint (True when the recording has no target_current to compare with)."""
    names = ("base", "shoulder", "elbow", "wrist1", "wrist2", "wrist3")
    f = lambda v, d=3: "-" if v is None else f"{v:.{d}f}"
    rows = [f"{Path(path).name} ({label}): RMS current [A]",
            "| joint | moves | RMS meas | RMS(twin-meas) | RMS(UR-meas) | ratio twin | ratio UR |"
            " corr twin | twin <= UR |",
            "|---|---|---|---|---|---|---|---|---|"]
    ok = True
    for j, js in enumerate(summary["joints"]):
        ur = js["rms_err_ur"]
        good = ur is None or js["rms_err_twin"] <= ur
        if moving[j]:
            ok &= good
        verdict = ("yes" if good else "NO") if moving[j] and ur is not None else "-"
        rows.append(f"| {names[j]} | {'yes' if moving[j] else 'no'} | {f(js['rms_meas'])} | "
                    f"{f(js['rms_err_twin'])} | {f(ur)} | {f(js['ratio_twin'], 2)} | "
                    f"{f(js['ratio_ur'], 2)} | {f(js['corr_twin'], 2)} | {verdict} |")
    return "\n".join(rows), ok


def relax_sets(lam):
    """--set arguments giving joint j the rate lam[j] (a number: every joint)."""
    lam = np.broadcast_to(np.asarray(lam, dtype=float), (NJ,))
    return [f"joints.{j}.friction.relax={lam[j]:g}" for j in range(NJ)]


def replay_ratios(recs, out, config, lam):
    """Per file and joint RMS(twin − measured)/RMS(measured) and RMS(twin − measured), the
    twin replaying the fit files with the overlay and rates lam."""
    ratio, err = [], []
    for r in recs:
        summ = replay(r.path, overlay=out, config=config, sets=relax_sets(lam))
        ratio.append([js["rms_err_twin"] / max(js["rms_meas"], 1e-9) for js in summ["joints"]])
        err.append([js["rms_err_twin"] for js in summ["joints"]])
    return np.array(ratio), np.array(err)


def joint_score(ratio, moving, j):
    """Joint j's mean RMS(twin − measured)/RMS(measured) over the files where it moves (over
    all files if it moves in none)."""
    return ratio[moving[:, j], j].mean() if moving[:, j].any() else ratio[:, j].mean()


def choose_relax(recs, out, config, grid, quiet):
    """The bristle relaxation rate λ_j per joint by the twin's own replay of the fit files with
    the overlay just written. Every file is replayed at each rate of grid given to all
    joints; joint j takes the rate with the lowest mean over the files where it moves (all
    files if it moves in none) of RMS(twin − measured)/RMS(measured): a joint's rate acts
    mostly on its own current, so one replay per file and rate serves all six. The surrogate's
    steady law cannot see λ: it acts where a joint stands still while held by its position
    loop, letting go of the friction it stopped with as the real drives do (no1's wrist 3
    stands at 8–12 s while the base turns: the real current relaxes from 0.2 A to 0 within
    ~2 s; with λ = 0 the twin holds the 0.2 A of stiction it stopped with). The chosen set is
    replayed once more and kept only if it scores at least as well as the best single rate.
    Returns (λ per joint, per-joint twin RMS error over the files at those rates)."""
    moving = np.array([moving_joints(r) for r in recs])
    tried = []
    for lam in grid:
        try:
            ratio, err = replay_ratios(recs, out, config, lam)
        except RuntimeError as e:
            if not quiet:
                print(f"relax {lam:g} 1/s: the twin's replay failed ({e}); not taken", flush=True)
            continue
        tried.append((lam, ratio, err))
        if not quiet:
            print(f"relax {lam:g} 1/s: mean RMS(twin - measured)/RMS(measured) "
                  f"{ratio[moving].mean():.4f} over the fit files' moving joints; per joint "
                  + " ".join(f"{joint_score(ratio, moving, j):.4f}" for j in range(NJ)),
                  flush=True)
    if not tried:
        raise RuntimeError("the twin cannot replay the fit files at any --relax rate")

    per_joint = np.array([min(tried, key=lambda t: joint_score(t[1], moving, j))[0]
                          for j in range(NJ)])
    single = min(tried, key=lambda t: t[1][moving].mean())
    err2 = lambda err: np.sqrt(np.mean(err ** 2, axis=0))
    if len(set(per_joint.tolist())) > 1:
        try:
            ratio, err = replay_ratios(recs, out, config, per_joint)
            if not quiet:
                print("relax per joint " + " ".join(f"{v:g}" for v in per_joint) +
                      f" 1/s: mean RMS(twin - measured)/RMS(measured) "
                      f"{ratio[moving].mean():.4f}", flush=True)
            if ratio[moving].mean() <= single[1][moving].mean():
                return per_joint, err2(err)
        except RuntimeError as e:
            if not quiet:
                print(f"relax per joint: the twin's replay failed ({e}); not taken", flush=True)
    return np.full(NJ, single[0]), err2(single[2])


def judge(h, overlay, config):
    """Replay table of holdout h with the paper's parameters and with overlay; True when the
    twin's RMS current error is at most UR's on every joint that moves."""
    moving = moving_joints(h)
    base = replay(h.path, config=config)
    fitted = replay(h.path, overlay=overlay, config=config)
    print(replay_table(h.path, base, moving, "paper parameters")[0], flush=True)
    table, ok = replay_table(h.path, fitted, moving, f"overlay {Path(overlay).name}")
    print(table, flush=True)
    print(f"{h.path.name}: twin <= UR on every moving joint with the overlay: "
          f"{'yes' if ok else 'NO'}", flush=True)
    return ok


