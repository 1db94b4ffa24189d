#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Calibrate urtwin to a robot from its own recordings (UR RTDE record.py layout).

  urt_identify.py FILES... --out config/overlays/NAME.yaml [--holdout FILE...]
                  [--config config/ur5.yaml] [--name NAME] [--max-iter N] [--no-arm]
                  [--hold-settle S] [--rest-model W] [--relax L...] [--leave-one-out]

Fits, by physically bounded least squares (scipy.optimize.least_squares, trust-region
reflective), the measured motor currents `actual_current_j` against the current a fast surrogate
of the twin predicts at the recorded set-point (tools/urt_surrogate.py: rigid-body torque +
reflected motor and gear inertia + the LuGre law in steady sliding, divided by k_t·r): per joint
that moves (range > 0.05 rad in a file) the Coulomb level f_c, the viscous level f_v, the
Stribeck level k_static and speed qd_s, the direction asymmetry asym; for every joint the
current-measurement offset; and the CoMs of links 2–6 (the first moments that set the gravity
torques of shoulder, elbow and wrists; masses are kept, a CoM is a mass-weighted position), and
per joint that moves the motor torque constant k_t (within ±10 % of the config's: the motors'
tolerance and temperature; the model's ke is kt), each within physical bounds and pulled weakly
towards the paper's value so that what the recordings cannot see stays the paper's. A Stribeck
dip steeper than the gear's output damping (the paper's own dip where that is steeper) is
penalised: it would self-excite. A payload (payload.mass, payload.cog) is fitted when the model
has those keys (urt_config prints a `payload` block).

It prints one progress line per iteration, then writes the overlay: only the keys it changed,
each with value, unit (as urt_config/--print-model prints it), the files it came from and the
fit's RMS current residual [A] on the joint(s) the key acts on (surrogate, fit files).

--holdout FILE... replays each file through the twin itself (tools/urt_replay_judge.py: urt_sim
--replay FILE --overlay OUT --summary-json), with the paper's parameters and with the overlay,
and prints the table: per joint RMS(measured), RMS(twin − measured), RMS(UR target_current −
measured), their ratios, and whether the joint moves. --leave-one-out fits on all FILES but one
and judges that one, for each (a fold whose replay fails is reported and counted as failed).
--hold-settle S also fits a moving joint's holds from S seconds after its set-point stopped
(default 0: not at all; config/overlays/README.md). --rest-model W (default 10) fits the current
the twin reports (holding torque and measurement offset), where the whole arm rests, to the
recording's target_current (the controller's gravity model there) with weight W, not to the
measured current, which carries the friction the drive was left holding. --relax L... (default 0
100 300 1000 [1/s]) chooses each joint's bristle relaxation rate from those by the twin's replay
of the fit files with the overlay (0 alone: no replays, no relax keys). Exit status: 0 done, 1
run-time failure (twin replay), 2 usage or input error (a bad recording reads file:line:
reason).
"""

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).resolve().parent))
import urt_recording as rec_io  # noqa: E402
import urt_replay_judge as judge_io  # noqa: E402
from urt_replay_judge import NJ, UsageError, moving_joints, tool  # noqa: E402
import urt_surrogate as sur  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
V_MIN = 0.02            # [rad/s] samples of a moving joint slower than this are not fitted
HOLD_SETTLE = 0.0       # [s] --hold-settle: … except in its holds from this long after its
                        # set-point stopped (0: not at all; config/overlays/README.md)
COM_BOUND = 0.05        # [m] CoM corrections within ± this of the paper's
COM_PRIOR = 0.02        # [m] scale of the weak pull towards the paper's CoM
PAYLOAD_PRIOR = 0.5     # [kg] its scale for the payload mass
PRIOR_WEIGHT = 0.03     # weight of that pull, relative to one normalised current RMS
FRICTION_NAMES = ("f_c", "f_v", "k_static", "qd_s", "asym")
FIT_LINKS = (1, 2, 3, 4, 5)  # 0-based: upper arm … link 6
FIT_KT = True           # fit the motor torque constants (off with --no-arm)
KT_BOUND = 0.10         # k_t within ± this fraction of the config's: the motors' tolerance
KT_PRIOR = 0.03         # scale of the weak pull towards the config's k_t (fraction)
REST_WEIGHT = 10.0      # --rest-model W: weight of the controller's own model at rest (0: off)
RELAX_GRID = (0.0, 100.0, 300.0, 1000.0)  # --relax: bristle relaxation rates tried [1/s]


def resolved(config, sets=()):
    """The model urtwin resolves (urt_config --json) and its printed units, keyed by generic
    path ("joints[].friction.f_c"): the units an overlay entry must state."""
    args = [tool("urt_config"), "--json"] + [a for s in sets for a in ("--set", s)] + [str(config)]
    js = subprocess.run(args, capture_output=True, text=True)
    if js.returncode != 0:
        raise UsageError(js.stderr.strip() or f"urt_config failed on {config}")
    params = json.loads(js.stdout)
    return params, params.get("units", {})


def unit_of(units, key):
    """The printed unit of a --set key such as joints.1.friction.f_c or arm.links.2.com."""
    generic = re.sub(r"\.(\d+)(?=\.|$)", "[]", key)
    return units.get(generic)


#---- the parameter vector ----

class Spec:
    """The fitted parameters: --set key, vector component, start, bounds, joints it acts on."""

    def __init__(self, params, moving, payload_keys):
        self.rows = []  # (key, component or None, x0, lo, hi, joints)
        js = params["joints"]
        for j in range(NJ):
            fr = js[j]["friction"]
            big = js[j]["size"] == "A"
            if moving[j]:
                bounds = {"f_c": (0.05, 30.0 if big else 8.0), "f_v": (0.0, 40.0 if big else 10.0),
                          "k_static": (0.0, 1.0), "qd_s": (0.2, 2.0), "asym": (-0.5, 0.5)}
                for name in FRICTION_NAMES:
                    lo, hi = bounds[name]
                    self.rows.append((f"joints.{j}.friction.{name}", None,
                                      float(np.clip(fr[name], lo, hi)), lo, hi, (j,)))
            i_max = js[j]["control"]["i_max"]
            self.rows.append((f"joints.{j}.current_offset", None, js[j]["current_offset"],
                              -0.2 * i_max, 0.2 * i_max, (j,)))
            if moving[j] and FIT_KT:
                # the current per output torque: k_t of the motor as built and at its
                # temperature (NdFeB loses ~0.1 %/K) against the data sheet's
                kt = js[j]["motor"]["kt"]
                self.rows.append((f"joints.{j}.motor.kt", None, kt, (1.0 - KT_BOUND) * kt,
                                  (1.0 + KT_BOUND) * kt, (j,)))
        for i in FIT_LINKS:
            com = params["arm"]["links"][i]["com"]
            for c in range(3):
                self.rows.append((f"arm.links.{i}.com", c, com[c], com[c] - COM_BOUND,
                                  com[c] + COM_BOUND, tuple(range(i + 1))))
        if payload_keys:
            p = params["payload"]
            self.rows.append(("payload.mass", None, p["mass"], 0.0, 5.0, tuple(range(NJ))))
            for c in range(3):
                self.rows.append(("payload.cog", c, p["cog"][c], -0.2, 0.2, tuple(range(NJ))))
        self.x0 = np.array([r[2] for r in self.rows])
        self.lo = np.array([r[3] for r in self.rows])
        self.hi = np.array([r[4] for r in self.rows])
        # nudge starts off the bounds (least_squares needs them strictly inside)
        span = self.hi - self.lo
        self.x0 = np.clip(self.x0, self.lo + 1e-6 * span, self.hi - 1e-6 * span)
        # the weak pull towards the paper's robot: link CoMs and the payload (none)
        self.prior = [k for k, r in enumerate(self.rows)
                      if r[0].startswith("arm.") or r[0].startswith("payload.")
                      or r[0].endswith(".motor.kt")]
        self.prior_scale = np.array([PAYLOAD_PRIOR if self.rows[k][0] == "payload.mass"
                                     else KT_PRIOR * self.rows[k][2]
                                     if self.rows[k][0].endswith(".motor.kt")
                                     else COM_PRIOR for k in self.prior])

    def unpack(self, x, params):
        js = params["joints"]
        fr = {n: np.array([js[j]["friction"][n] for j in range(NJ)], dtype=float)
              for n in FRICTION_NAMES}
        off = np.array([js[j]["current_offset"] for j in range(NJ)], dtype=float)
        kt = np.array([js[j]["motor"]["kt"] for j in range(NJ)], dtype=float)
        links = params["arm"]["links"]
        mass = [l["mass"] for l in links]
        com = [list(l["com"]) for l in links]
        payload = None
        if "payload" in params:
            payload = [params["payload"]["mass"], list(params["payload"]["cog"])]
        for (key, comp, *_), v in zip(self.rows, x):
            parts = key.split(".")
            if parts[0] == "joints" and parts[2] == "friction":
                fr[parts[3]][int(parts[1])] = v
            elif parts[0] == "joints" and parts[2] == "motor":
                kt[int(parts[1])] = v
            elif parts[0] == "joints":
                off[int(parts[1])] = v
            elif parts[0] == "arm":
                com[int(parts[2])][comp] = v
            elif key == "payload.mass":
                payload[0] = v
            else:
                payload[1][comp] = v
        return fr, off, mass, com, payload, kt


#---- data ----

class FitData:
    """One recording with its regressor, ready for the surrogate."""

    def __init__(self, rec, arm):
        self.rec = rec
        self.name = rec.path.name
        q, qd, qdd = rec["target_q"], rec["target_qd"], rec["target_qdd"]
        self.qd, self.qdd = qd, qdd
        self.i_meas = rec["actual_current"]
        self.y = arm.regressor(q, qd, qdd)
        self.moving = moving_joints(rec)
        # Near a reversal the set-point's sign of q̇ leads the joint's, and the friction there
        # (a jump of 2 f_c within µrad of bristle travel) is the twin's dynamics, not the
        # surrogate's steady law: those samples of a moving joint are left out of the fit.
        # A joint that never moves in the file keeps all its samples (gravity and offset).
        # With --hold-settle S its settled holds are fitted: S s after the joint's set-point
        # stopped, the real drive has let go of the friction current it carried into the stop
        # (no4_acc 12.7–15 s: the shoulder's 3.8 A relaxes to a flat 3.2 A within ~1 s), and
        # what is left is the holding torque, the level the surrogate predicts at q̇ = 0
        # (gravity, offset). Without them the recordings' long holds (56 % of no4_acc) see
        # gravity only through the moves, where it trades against the friction's asymmetry.
        # Off by default: see config/overlays/README.md for what it does to the folds.
        settled = settled_holds(rec.t, qd, HOLD_SETTLE) if HOLD_SETTLE > 0 else \
            np.zeros(qd.shape, dtype=bool)
        self.weight = np.where((np.abs(qd) >= V_MIN) | ~self.moving | settled, 1.0, 0.0)
        # The arm at rest (all six set-point speeds and accelerations 0): the controller's own
        # model current there (target_current) is its gravity model, the manufacturer's
        # calibration of the arm's first moments, while the measured current also carries
        # the friction the drive was left holding (history-dependent: ±0.3–1 A on the shoulder
        # and elbow of these recordings, relaxing over seconds; see rest_model_residual).
        self.rest = (np.all(qd == 0.0, axis=1) & np.all(qdd == 0.0, axis=1)) \
            if rec.has("target_current") else np.zeros(len(qd), dtype=bool)
        self.i_rest_model = rec["target_current"] if rec.has("target_current") else None


def settled_holds(t, qd, settle):
    """(n, 6) mask: the joint's set-point has stood still (target_qd_j = 0) for at least
    settle seconds at that sample, counted from the first sample of the stillness (a recording
    that starts standing counts from its start)."""
    out = np.zeros(qd.shape, dtype=bool)
    for j in range(qd.shape[1]):
        since = None
        for k in range(len(t)):
            if qd[k, j] != 0.0:
                since = None
                continue
            if since is None:
                since = t[k]
            out[k, j] = t[k] - since >= settle
    return out


def predict(spec, x, params, arm, drives, fd):
    """The current the twin reports (its measurement offset included) at fd's set-points."""
    fr, off, mass, com, payload, kt = spec.unpack(x, params)
    tau = fd.y @ arm.pi(mass, com, payload)
    return sur.current(drives, tau, fd.qd, fd.qdd, fr, off, kt)


def rest_model_residual(spec, x, params, arm, drives, fd, scale):
    """Where the arm rests: the current the surrogate reports (holding torque and measurement
    offset) against the controller's own model current, weighted by REST_WEIGHT. The measured
    current at rest is gravity plus whatever friction the drive was left holding when the arm
    stopped (these recordings: the elbow holds 0.5–0.7 A below its level after a move up and
    above it after a move down, relaxing over ~1 s and not always to the same level; the
    shoulder up to 1 A), which the twin's steady holding current cannot follow; fitted to it
    alone, the first moments bend to that history and extrapolate badly to poses the files do
    not hold (no1's shoulder, fitted on the four other files: a mean error of +0.34 A). The
    controller's model at rest is its gravity model alone, and it predicts the current the
    drive reports: the offset is held to it too. Left to the moves alone (session 26) the
    shoulder's offset came out at −0.04…−0.09 A, where the measured current at rest stands
    +0.20…+0.43 A over UR's model in every file that rests: not a zero the moves can see, and
    it put the twin's rests 0.09 A under UR's (test_shoulder_elbow's fold: 0.517 A RMS against
    UR's 0.498; 0.476 with the offset held here)."""
    if not fd.rest.any() or REST_WEIGHT == 0.0:
        return np.zeros(0)
    p = predict(spec, x, params, arm, drives, fd)
    return (REST_WEIGHT * fd.rest[:, None] * (p - fd.i_rest_model) / scale).ravel()


#---- the fit ----

SLOPE_WEIGHT = 10.0
_V = 1e-6 * 10.0 ** (7.0 * np.arange(401) / 400.0)  # 1e-6 … 10 rad/s, as model_prepare.cpp


def stribeck_slope_min(fr, k_q):
    """Most negative dg/dq̇ per joint over both directions (core/model_prepare.cpp's search)."""
    worst = np.zeros(NJ)
    for side in (1.0, -1.0):
        fc = fr["f_c"] * (1.0 + side * fr["asym"])
        e = np.exp(-np.outer(_V, k_q / fr["qd_s"]))
        dg = -fc * fr["k_static"] * (k_q / fr["qd_s"]) * e + \
            (2.0 / 3.0) * fr["f_v"] * np.cbrt(1.0 / _V)[:, None]
        worst = np.minimum(worst, dg.min(axis=0))
    return worst


def stribeck_slope_bound(params):
    """Per joint: the steepest Stribeck slope allowed [N m s/rad], the gear output damping
    c_CS (a steeper dip negatively damps the load mode: config/README.md, "Why k_q = 5"), or
    the paper's own slope where that is already steeper (size A: −14.6 against 13.9)."""
    return np.array([max(j["gear"]["c_cs"], -s) for j, s in
                     zip(params["joints"], params["integrator"]["friction_slope_min"])])


def fit(files, params, arm, drives, payload_keys, max_iter, quiet=False):
    moving = np.zeros(NJ, dtype=bool)
    for fd in files:
        moving |= fd.moving
    spec = Spec(params, moving, payload_keys)
    scale = np.sqrt(np.mean(np.concatenate([fd.i_meas for fd in files]) ** 2, axis=0))
    scale = np.maximum(scale, 0.05)
    n_res = sum(fd.weight.sum() for fd in files)
    x_paper = spec.x0.copy()
    prior_w = PRIOR_WEIGHT * np.sqrt(n_res / NJ)

    slope_bound = stribeck_slope_bound(params)

    def residuals(x):
        parts = [(fd.weight * (predict(spec, x, params, arm, drives, fd) - fd.i_meas) /
                  scale).ravel() for fd in files]
        parts += [rest_model_residual(spec, x, params, arm, drives, fd, scale) for fd in files]
        # a Stribeck dip steeper than the bound is a self-excited stick-slip, not a fit
        fr = spec.unpack(x, params)[0]
        excess = np.maximum(0.0, -stribeck_slope_min(fr, drives.k_q) - slope_bound)
        parts.append(SLOPE_WEIGHT * np.sqrt(n_res) * excess / slope_bound)
        parts.append(prior_w * (x[spec.prior] - x_paper[spec.prior]) / spec.prior_scale)
        return np.concatenate(parts)

    it = [0]

    def progress(intermediate_result):
        it[0] += 1
        if not quiet:
            cost = intermediate_result.cost if hasattr(intermediate_result, "cost") else \
                0.5 * np.sum(residuals(intermediate_result.x) ** 2)
            print(f"iteration {it[0]:3d}: cost {cost:.6g}, normalised RMS residual "
                  f"{np.sqrt(2 * cost / n_res):.4f}", flush=True)

    res = least_squares(residuals, spec.x0, bounds=(spec.lo, spec.hi), method="trf",
                        x_scale="jac", ftol=1e-10, xtol=1e-10, max_nfev=max_iter,
                        callback=progress)
    per_joint = np.sqrt(np.mean(np.concatenate(
        [predict(spec, res.x, params, arm, drives, fd) - fd.i_meas for fd in files]) ** 2,
        axis=0))
    return spec, res, per_joint


#---- the overlay ----

def fmt(v):
    return repr(float(v)) if not isinstance(v, list) else "[" + ", ".join(fmt(a) for a in v) + "]"


def changed_keys(spec, x, x_paper):
    """{key: value} for keys whose value moved (list keys as their full list)."""
    out = {}
    for (key, comp, *_), v, v0 in zip(spec.rows, x, x_paper):
        if comp is None:
            if abs(v - v0) > 1e-9 * max(1.0, abs(v0)):
                out[key] = float(v)
        else:
            out.setdefault(key, [None, None, None])
            out[key][comp] = (float(v), abs(v - v0) > 1e-9)
    for key, val in list(out.items()):
        if isinstance(val, list):
            if any(moved for _, moved in val):
                out[key] = [round(v, 9) for v, _ in val]
            else:
                del out[key]
    return out


def overlay_entry(key, val, units, from_list, resid):
    """One `set:` line of an overlay: value, unit as urt_config prints it, source files and
    the RMS current residual [A]."""
    unit = unit_of(units, key)
    if unit is None:
        raise UsageError(f"urt_config prints no unit for {key}")
    return (f"  {key}: {{value: {fmt(val)}, unit: \"{unit}\", from: [{from_list}], "
            f"residual: {resid:.4g}}}")


def write_overlay(path, name, base, argv, spec, res, per_joint, units, files, params):
    x_paper = np.array([_paper_value(params, r) for r in spec.rows])
    keys = changed_keys(spec, res.x, x_paper)
    joints_of = {}
    for key, _, _, _, _, joints in spec.rows:
        joints_of[key] = joints
    from_list = ", ".join(f.path.name for f in files)
    lines = [
        "# SPDX-License-Identifier: Apache-2.0",
        f"# {Path(path).name}: urtwin calibration overlay, written by tools/urt_identify.py.",
        "# residual: RMS(surrogate current - measured) [A] after the fit, over the `from` files,",
        "# on the joint the key acts on (for link CoMs and payload: over the joints it moves).",
        f"overlay: {{name: {name}, base: {Path(base).name}, "
        f"tool: \"tools/urt_identify.py {' '.join(argv)}\", "
        f"note: \"bounded least squares on {len(files)} recordings; "
        f"{res.nfev} evaluations, status {res.status}\"}}",
        "set:",
    ]
    for key, val in keys.items():
        resid = float(np.sqrt(np.mean(per_joint[list(joints_of[key])] ** 2)))
        lines.append(overlay_entry(key, val, units, from_list, resid))
    if not keys:
        lines[-1] = "set: {}"
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text("\n".join(lines) + "\n")
    return keys


def _paper_value(params, row):
    key, comp = row[0], row[1]
    parts = key.split(".")
    node = params
    for p in parts:
        node = node[int(p)] if p.isdigit() else node[p]
    return node[comp] if comp is not None else node


#---- main ----

def append_relax(path, lam, per_joint, units, files):
    """Add the chosen non-zero rates to the overlay at path; their residual is the twin's
    replay RMS error on the joint over the fit files (not the surrogate's)."""
    from_list = ", ".join(f.path.name for f in files)
    keys = [j for j in range(NJ) if lam[j] != 0.0]
    if not keys:
        return []
    text = Path(path).read_text().replace("set: {}\n", "set:\n")
    lines = [overlay_entry(f"joints.{j}.friction.relax", float(lam[j]), units, from_list,
                           per_joint[j]) for j in keys]
    Path(path).write_text(text + "\n".join(lines) + "\n")
    return [f"joints.{j}.friction.relax" for j in keys]


def fit_and_write(recs, out, a, argv, params, units, arm, drives):
    files = [FitData(r, arm) for r in recs]
    spec, res, per_joint = fit(files, params, arm, drives, "payload" in params and not a.no_arm,
                               a.max_iter, a.quiet)
    name = a.name or Path(out).stem
    keys = write_overlay(out, name, a.config, argv, spec, res, per_joint, units, recs, params)
    if len(RELAX_GRID) > 1 or RELAX_GRID[0] != 0.0:
        lam, twin_err = judge_io.choose_relax(recs, out, a.config, RELAX_GRID, a.quiet)
        keys = list(keys) + append_relax(out, lam, twin_err, units, recs)
        print("bristle relaxation per joint: " + " ".join(f"{v:g}" for v in lam) +
              " 1/s (the twin's replay of the fit files)")
    print(f"wrote {out}: {len(keys)} keys; surrogate RMS residual per joint [A]: "
          + " ".join(f"{v:.3f}" for v in per_joint))
    if not a.quiet:
        for fd in files:
            err = predict(spec, res.x, params, arm, drives, fd) - fd.i_meas
            line = f"  {fd.name}: surrogate/UR RMS error per joint [A]:"
            for j in range(NJ):
                ur = (np.sqrt(np.mean((fd.rec["target_current"][:, j] - fd.i_meas[:, j]) ** 2))
                      if fd.rec.has("target_current") else float("nan"))
                line += f" {np.sqrt(np.mean(err[:, j] ** 2)):.3f}/{ur:.3f}"
            print(line)


def main(argv=None):
    global FIT_LINKS, FIT_KT, HOLD_SETTLE, REST_WEIGHT, RELAX_GRID
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(prog="urt_identify.py", description=__doc__.split("\n")[0])
    ap.add_argument("files", nargs="+", help="recordings to fit (record.py layout)")
    ap.add_argument("--out", required=True,
                    help="overlay YAML to write (with --leave-one-out: a directory)")
    ap.add_argument("--holdout", nargs="+", default=[], help="recordings to judge, not fitted")
    ap.add_argument("--leave-one-out", action="store_true",
                    help="fit on all FILES but one, judge that one, for each; --out is a "
                         "directory for the overlays (without-STEM.yaml)")
    ap.add_argument("--config", default=str(ROOT / "config" / "ur5.yaml"))
    ap.add_argument("--name", default=None, help="overlay name (default: the file's stem)")
    ap.add_argument("--max-iter", type=int, default=60, help="function evaluations at most")
    ap.add_argument("--no-arm", action="store_true",
                    help="fit friction and offsets only (no link CoMs, no payload, no k_t)")
    ap.add_argument("--hold-settle", type=float, default=HOLD_SETTLE,
                    help="fit a moving joint's holds from this long after its set-point "
                         "stopped [s], e.g. 1; 0: not at all (the default)")
    ap.add_argument("--rest-model", type=float, default=REST_WEIGHT, metavar="W",
                    help="weight of the controller's own model current (target_current) where "
                         "the arm rests: the twin's holding current is fitted to it, not to "
                         "the measured one, which carries the friction the drive was left "
                         "holding (default %(default)s; 0: off)")
    ap.add_argument("--relax", type=float, nargs="+", default=list(RELAX_GRID), metavar="L",
                    help="bristle relaxation rates to try [1/s], one for every joint, chosen "
                         "by the twin's replay of the fit files (default %(default)s; 0 alone: "
                         "the paper's LuGre, no replays)")
    ap.add_argument("--quiet", action="store_true")
    try:
        a = ap.parse_args(argv)
    except SystemExit as e:
        return 2 if e.code else 0
    if a.hold_settle < 0:
        print("urt_identify: --hold-settle must be >= 0", file=sys.stderr)
        return 2
    HOLD_SETTLE = a.hold_settle
    if not np.isfinite(a.rest_model) or a.rest_model < 0:
        print("urt_identify: --rest-model must be a finite weight >= 0", file=sys.stderr)
        return 2
    REST_WEIGHT = a.rest_model
    if not all(np.isfinite(v) and 0.0 <= v <= 1000.0 for v in a.relax):
        print("urt_identify: --relax rates must be in [0, 1000] 1/s", file=sys.stderr)
        return 2
    RELAX_GRID = tuple(a.relax)
    try:
        params, units = resolved(a.config)
        recs = [rec_io.read_recording(f) for f in a.files]
        holdouts = [rec_io.read_recording(f) for f in a.holdout]
        overlap = {r.path.resolve() for r in recs} & {h.path.resolve() for h in holdouts}
        if overlap:
            raise UsageError(f"{sorted(map(str, overlap))[0]}: in both FILES and --holdout")
        if a.leave_one_out and (len(recs) < 2 or holdouts):
            raise UsageError("--leave-one-out needs two or more FILES and no --holdout")
    except (rec_io.RecordingError, UsageError) as e:
        print(f"urt_identify: {e}", file=sys.stderr)
        return 2

    if a.no_arm:
        FIT_LINKS, FIT_KT = (), False
    arm, drives = sur.Arm(params), sur.Drives(params)
    try:
        if not a.leave_one_out:
            fit_and_write(recs, a.out, a, argv, params, units, arm, drives)
            for h in holdouts:
                judge_io.judge(h, a.out, a.config)
            return 0
        verdicts = []
        for k, h in enumerate(recs):
            out = Path(a.out) / f"without-{h.path.stem}.yaml"
            print(f"== fold {k + 1}/{len(recs)}: fit without {h.path.name}", flush=True)
            fit_and_write(recs[:k] + recs[k + 1:], out, a, argv, params, units, arm, drives)
            try:
                verdicts.append((h.path.name, judge_io.judge(h, out, a.config)))
            except RuntimeError as e:
                # a twin that cannot replay the held-out file fails that fold; the other
                # folds are still judged, and the exit status says a replay failed
                print(f"{h.path.name}: the twin's replay failed: {e}", flush=True)
                verdicts.append((h.path.name, None))
        for name, ok in verdicts:
            print(f"leave-one-out {name}: "
                  f"{'pass' if ok else 'FAIL' if ok is not None else 'FAIL (replay failed)'}")
        return 1 if any(ok is None for _, ok in verdicts) else 0
    except (RuntimeError, UsageError) as e:
        print(f"urt_identify: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
