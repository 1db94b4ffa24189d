#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/bench.py — the driver behind `make bench`.

Runs build/tools/urt_bench (urt_step at 20 kHz and 10 kHz, and MuJoCo's mj_step on a UR5-like
model through the pip wheel's libmujoco.so), times Pinocchio's ABA on the same UR5 arm, and
merges everything into one JSON file plus a table of medians and ratios. Everything is measured
in one run on the same machine; nothing here asserts a time (the machine is shared and noisy).

    URT_BUILD=build .venv/bin/python tools/bench.py --out build/bench.json

Then the replay speed: `urt_sim --replay` of an 80 s recording (../shared's no5_acc_slow.csv
played forward and back to 80 s; a synthetic one without ../shared), three runs, the median of
simulated seconds per wall second and per CPU second of the simulating thread (target: at
least 10; reported, never asserted), at the config's rate and at 10 kHz, with the largest
difference of the two replays' per-joint RMS current errors.

Pinocchio is only reachable through Python here, so ABA is reported three ways, labelled (the
workloads are interleaved batch by batch, like the cases inside urt_bench):
  native     per-call cost of the C++ loop inside pin.abaInParallel (1 thread, a batch of
             configurations per call):
             no Python in the loop; this is the one the ratio uses;
  raw        a Python `for` loop of pin.aba calls: native cost + ~1 µs of binding overhead
             (argument conversion, overload dispatch, result wrapping);
  corrected  raw minus a near-empty bound call of similar signature (pin.integrate(model, q, v)).
"""

import argparse
import datetime
import glob
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from urt_replay_judge import replay  # the replay every tool runs (urt_sim --replay)

ROOT = Path(__file__).resolve().parent.parent

def warn(msg):
    print(f"bench.py: warning: {msg}", file=sys.stderr)


# ---- machine and build info --------------------------------------------------------------

def machine_info(build):
    info = {
        "date_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "cpu_model": "unknown",
        "cpu_count": os.cpu_count(),
        "cpus_allowed": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "kernel": platform.release(),
        "python": platform.python_version(),
        "loadavg_start": list(os.getloadavg()),
    }
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    info["cpu_model"] = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        rev = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                             capture_output=True, text=True, timeout=10)
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain",
                                "--untracked-files=no"], capture_output=True, text=True, timeout=10)
        if rev.returncode == 0:
            info["git"] = rev.stdout.strip() + ("-dirty" if dirty.stdout.strip() else "")
    except (OSError, subprocess.SubprocessError):
        pass
    # the compiler flags decide the numbers as much as the code does
    cache = Path(build) / "CMakeCache.txt"
    if cache.is_file():
        for line in cache.read_text(errors="replace").splitlines():
            for key in ("CMAKE_BUILD_TYPE", "CMAKE_CXX_COMPILER", "CMAKE_C_COMPILER"):
                if line.startswith(key + ":"):
                    info[key.lower()] = line.split("=", 1)[1]
    return info


# ---- urt_bench (urt_step and mj_step) ------------------------------------------------------

def find_mujoco_lib():
    """Path of the wheel's libmujoco.so*, or (None, reason)."""
    try:
        import mujoco
    except Exception as e:  # any import failure just makes MuJoCo unavailable
        return None, f"import mujoco: {e}"
    libs = sorted(glob.glob(os.path.join(os.path.dirname(mujoco.__file__), "libmujoco.so*")))
    if not libs:
        return None, "no libmujoco.so* next to the mujoco package"
    # the fully versioned name is the real file; the others (if any) are symlinks to it
    return max(libs, key=len), None


def run_urt_bench(args, build):
    exe = Path(build) / "tools" / "urt_bench"
    if not os.access(exe, os.X_OK):
        sys.exit(f"bench.py: {exe} not found; build first (make build)")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "urt_bench.json"
        cmd = [str(exe), "--config", args.config, "--steps", str(args.steps),
               "--warmup", str(args.warmup), "--json", str(out), "--quiet"]
        for s in args.set:
            cmd += ["--set", s]
        if args.cpu is not None:
            cmd += ["--cpu", str(args.cpu)]
        lib, why = (None, "disabled by --no-mujoco") if args.no_mujoco else find_mujoco_lib()
        if lib:
            cmd += ["--mujoco-lib", lib]
        else:
            warn(f"MuJoCo unavailable: {why}")
            cmd += ["--skip-mujoco"] if args.no_mujoco else []
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
        sys.stderr.write(proc.stderr)
        if not out.is_file():
            sys.exit(f"bench.py: urt_bench exited {proc.returncode} without writing JSON")
        res = json.loads(out.read_text())
    if not lib:
        res["mujoco"]["error"] = why
    res["command"] = cmd
    res["exit_code"] = proc.returncode
    return res


# ---- Pinocchio ABA ---------------------------------------------------------------------------

def load_arm(args, build, bench):
    """(arm, source, q0 or None): the UR5 arm as the core sees it — from urt_config, else from
    urt_bench's dump of the model it loaded; (None, reason, None) when neither has it."""
    exe = Path(build) / "tools" / "urt_config"
    if os.access(exe, os.X_OK):
        cmd = [str(exe), "--print", "--json", args.config]
        for s in args.set:
            cmd += ["--set", s]
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=60)
            if p.returncode == 0:
                obj = json.loads(p.stdout)
                arm = obj.get("arm", obj)
                joints = obj.get("joints", [])
                q0 = [j["q0"] for j in joints] if len(joints) == 6 else None
                if len(arm.get("links", [])) == 6:
                    return arm, "urt_config", q0
            warn(f"urt_config failed (exit {p.returncode}): {p.stderr.strip()[:200]}")
        except (OSError, subprocess.SubprocessError, ValueError) as e:
            warn(f"urt_config: {e}")
    if "arm" in bench and len(bench["arm"].get("links", [])) == 6:
        return bench["arm"], "urt_bench (model as loaded)", bench["arm"].get("q0")
    return None, "no urt model: neither urt_config nor urt_bench loaded the config", None


def pin_model(pin, np, arm):
    """Pinocchio model of the Hayati-DH chain (model.md §1.8).

    ^{i-1}A_i = Transl(z,d)·Rot(z,θ+q)·Transl(x,a)·Rot(x,α)·Rot(y,β): joint i turns about z of
    frame i-1 after Transl(z,d)·Rot(z,θ) (Rot(z,·) and Transl(z,·) commute), and link i's
    inertia is given in frame i = joint frame · Transl(x,a)·Rot(x,α)·Rot(y,β).
    """
    def rot(axis, ang):
        return pin.SE3(pin.utils.rotate(axis, ang), np.zeros(3))

    def transl(axis, dist):
        p = np.zeros(3)
        p["xyz".index(axis)] = dist
        return pin.SE3(np.eye(3), p)

    model = pin.Model()
    model.gravity = pin.Motion(np.array(arm["gravity"], dtype=float), np.zeros(3))
    parent, fixed_prev = 0, pin.SE3.Identity()
    for i, link in enumerate(arm["links"]):
        placement = fixed_prev * transl("z", link["d"]) * rot("z", link["theta"])
        jid = model.addJoint(parent, pin.JointModelRZ(), placement, f"joint{i + 1}")
        fixed = transl("x", link["a"]) * rot("x", link["alpha"]) * rot("y", link["beta"])
        ixx, iyy, izz, ixy, ixz, iyz = link["inertia"]
        inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)
        body = pin.Inertia(float(link["mass"]), np.array(link["com"], dtype=float), inertia)
        model.appendBodyToJoint(jid, fixed.act(body), pin.SE3.Identity())
        parent, fixed_prev = jid, fixed
    return model


def stats_us(per_call_s):
    xs = sorted(per_call_s)
    n = len(xs)

    def pct(p):
        return xs[min(max(math.ceil(p * n), 1), n) - 1] * 1e6

    med = (xs[n // 2] if n % 2 else 0.5 * (xs[n // 2 - 1] + xs[n // 2])) * 1e6
    return {"n": n, "median_us": med, "p99_us": pct(0.99), "max_us": xs[-1] * 1e6,
            "mean_us": sum(xs) / n * 1e6, "min_us": xs[0] * 1e6}


def bench_aba(args, build, bench):
    res = {"status": "ok"}
    try:
        import numpy as np
        import pinocchio as pin
    except Exception as e:
        return {"status": "unavailable", "error": f"import pinocchio: {e}"}
    res["version"] = pin.__version__
    arm, source, q0 = load_arm(args, build, bench)
    if arm is None:
        return {"status": "unavailable", "error": source}
    res["model_source"] = source
    model = pin_model(pin, np, arm)
    data = model.createData()
    res["nq"] = model.nq

    # sanity: gravity torque at q = 0 against model.md A2 (−53.81 / −15.63 N m), reported only
    g0 = pin.computeGeneralizedGravity(model, data, np.zeros(model.nq))
    res["gravity_torque_q0"] = [float(x) for x in g0]

    # inputs near the benchmark's start configuration, moving at up to 1 rad/s
    q0 = np.array(q0 if q0 is not None else np.zeros(model.nq), dtype=float)
    rng = np.random.default_rng(1)
    nb = args.aba_native_batch
    Q = np.asfortranarray(q0[:, None] + rng.uniform(-0.5, 0.5, (6, nb)))
    V = np.asfortranarray(rng.uniform(-1.0, 1.0, (6, nb)))
    T = np.asfortranarray(np.stack([pin.rnea(model, data, Q[:, k], V[:, k], np.zeros(6))
                                    for k in range(nb)], axis=1)
                          + rng.uniform(-5.0, 5.0, (6, nb)))
    q, v, tau = Q[:, 0].copy(), V[:, 0].copy(), T[:, 0].copy()

    # Four workloads, interleaved batch by batch so a busy spell on the shared machine hits
    # them alike: native (the loop runs in C++ inside abaInParallel; one thread, so no parallel
    # speed-up), the raw Python loop, and two references for the overhead that loop carries.
    have_native = hasattr(pin, "abaInParallel") and hasattr(pin, "ModelPool")
    pool = pin.ModelPool(model, 1) if have_native else None
    A = np.asfortranarray(np.zeros((6, nb)))
    aba, integrate = pin.aba, pin.integrate
    noop = lambda m_, d_, q_, v_, t_: None  # noqa: E731
    k = args.aba_per_batch
    clock = time.perf_counter_ns
    t_native, t_raw, t_ref, t_noop = [], [], [], []

    def loop(fn, fargs):
        t0 = clock()
        for _ in range(k):
            fn(*fargs)
        return (clock() - t0) * 1e-9 / k

    for i in range(args.aba_batches + 3):
        if have_native:
            t0 = clock()
            pin.abaInParallel(1, pool, Q, V, T, A)
            tn = (clock() - t0) * 1e-9 / nb
        tr = loop(aba, (model, data, q, v, tau))
        tf = loop(integrate, (model, q, v))
        to = loop(noop, (model, data, q, v, tau))
        if i >= 3:  # the first rounds only warm up
            if have_native:
                t_native.append(tn)
            t_raw.append(tr)
            t_ref.append(tf)
            t_noop.append(to)

    batches = f"{args.aba_batches} batches interleaved; stats over per-batch means"
    if have_native:
        native = stats_us(t_native)
        native["method"] = (f"pin.abaInParallel(1 thread) over {nb} configurations per batch; "
                            f"{batches}")
        # same answers as the plain call (to round-off): guards against timing a no-op
        ref_a = aba(model, data, q, v, tau)
        native["max_rel_diff_vs_aba"] = float(np.max(np.abs(A[:, 0] - ref_a))
                                              / max(1.0, float(np.max(np.abs(ref_a)))))
        res["native"] = native
    else:
        res["native"] = {"status": "unavailable", "error": "pin.abaInParallel not in this build"}
    method = f"{k} calls per batch in a Python for-loop; {batches}"
    res["python_raw"] = dict(stats_us(t_raw), method=method, call="pin.aba(model, data, q, v, tau)")
    res["python_binding_reference"] = dict(
        stats_us(t_ref), method=method,
        call="pin.integrate(model, q, v): a bound call with two vector arguments, ~no work")
    res["python_noop"] = dict(
        stats_us(t_noop), method=method,
        call="a Python no-op with the same five arguments (interpreter loop and call only)")
    res["python_corrected_median_us"] = (res["python_raw"]["median_us"]
                                         - res["python_binding_reference"]["median_us"])
    if "median_us" in res["native"]:
        res["binding_overhead_median_us"] = (res["python_raw"]["median_us"]
                                             - res["native"]["median_us"])
    return res


# ---- merge and report ------------------------------------------------------------------------

def ratios(bench, aba):
    out = list(bench.get("ratios", []))
    for r in bench.get("urt", {}).get("runs", []):
        if r.get("status") != "ok" or r.get("faults", 0):
            continue
        if "median_us" in aba.get("native", {}):
            out.append({"dt": r["dt"], "numerator": "urt_step median",
                        "denominator": "pin.aba median (native, abaInParallel 1 thread)",
                        "value": r["median_us"] / aba["native"]["median_us"]})
        corr = aba.get("python_corrected_median_us")
        if corr and corr > 0:
            out.append({"dt": r["dt"], "numerator": "urt_step median",
                        "denominator": "pin.aba median (Python loop, binding-corrected)",
                        "value": r["median_us"] / corr})
    return out


def finite_or_null(x):
    """NaN/Inf are not JSON: write them as null so every reader can parse the file."""
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: finite_or_null(v) for k, v in x.items()}
    if isinstance(x, list):
        return [finite_or_null(v) for v in x]
    return x


def rate(dt):
    return f"{1e-3 / dt:g} kHz"


def print_table(res):
    m = res["machine"]
    print(f"urtwin bench  {m['date_utc']}  {m['cpu_model']} ({m['cpu_count']} CPUs, load "
          f"{m['loadavg_start'][0]:.2f})  git {m.get('git', '?')}  "
          f"build {m.get('cmake_build_type', '?')}")
    b = res["urt_bench"]
    print(f"{b['steps']} timed steps (+{b['warmup']} warm-up) per case; medians of one run on a "
          f"shared machine, not assertions")
    hdr = (f"{'case':<40} {'dt[us]':>7} {'median':>9} {'p99':>9} {'p99.9':>9} {'max':>9} "
           f"{'RTF':>8} {'wall/sim':>9}")
    print(hdr)
    print(f"{'':<40} {'':>7} {'[us]':>9} {'[us]':>9} {'[us]':>9} {'[us]':>9} {'':>8} {'[s/s]':>9}")
    print("-" * len(hdr))

    def row(name, dt, s):
        dts = f"{dt * 1e6:7.1f}" if dt else f"{'-':>7}"
        p999 = f"{s['p999_us']:9.3f}" if "p999_us" in s else f"{'-':>9}"
        rtf = f"{s['rtf']:8.2f}" if "rtf" in s else f"{'-':>8}"
        wall = f"{s['wall_s_per_sim_s']:9.3f}" if "wall_s_per_sim_s" in s else f"{'-':>9}"
        print(f"{name:<40} {dts} {s['median_us']:9.3f} {s['p99_us']:9.3f} {p999} "
              f"{s['max_us']:9.1f} {rtf} {wall}")

    urt = b["urt"]
    if not urt["runs"]:
        print(f"{'urt_step':<40} {urt['status']}: {urt.get('error', '')}")
    for r in urt["runs"]:
        faults = f", {r['faults']} faults" if r.get("faults", 0) else ""
        if r["status"] == "ok":
            row(f"urt_step {rate(r['dt'])}{faults}", r["dt"], r)
        else:
            print(f"{'urt_step ' + rate(r['dt']):<40} error: {r.get('error', '')}")
    # the arm holding q0 (set-point at rest): the drives' friction refines the step near zero speed
    for r in urt.get("standing_runs", []):
        if r["status"] == "ok":
            row(f"urt_step {rate(r['dt'])}, standing", r["dt"], r)
        else:
            print(f"{'urt_step ' + rate(r['dt']) + ', standing':<40} error: {r.get('error', '')}")
    mj = b["mujoco"]
    if mj["status"] != "ok":
        print(f"{'mj_step (MuJoCo)':<40} {mj['status']}: {mj.get('error', '')}")
    for r in mj["runs"]:
        name = f"mj_step {r['variant']} {rate(r['dt'])}"
        if r["status"] == "ok":
            row(name, r["dt"], r)
        else:
            print(f"{name:<40} error: {r.get('error', '')}")
    aba = res["pinocchio"]
    if aba["status"] != "ok":
        print(f"{'pin.aba (Pinocchio)':<40} {aba['status']}: {aba.get('error', '')}")
    else:
        if "median_us" in aba["native"]:
            row("pin.aba native (C++ loop, 1 thread)", None, aba["native"])
        row("pin.aba Python loop, raw", None, aba["python_raw"])
        row("  reference: pin.integrate call", None, aba["python_binding_reference"])
        c = aba["python_corrected_median_us"]
        print(f"{'pin.aba Python loop, corrected':<40} {'-':>7} {c:9.3f}  "
              "(raw - reference, median)")
    print("-" * len(hdr))
    for r in res["ratios"] + b.get("standing_ratios", []):
        what = f"{r['numerator']} / {r['denominator']}"
        print(f"ratio at {rate(r['dt']):>7}: {what:<80} = {r['value']:7.2f}")
    if aba["status"] == "ok":
        if "binding_overhead_median_us" in aba:
            cost = f"measured here as raw - native = {aba['binding_overhead_median_us']:.2f} us"
        else:
            cost = "typically ~1 us; no native figure in this build"
        print(f"note: Pinocchio is reached through its Python binding; its per-call overhead is "
              f"{cost}. ABA model from {aba['model_source']}.")
    if aba["status"] == "ok":
        print("note: pin.aba rows are stats over per-batch means (see JSON 'method'), so their "
              "p99/max show preemptions, not per-call jitter.")
    if mj["status"] == "ok":
        print(f"note: MuJoCo {mj['version']}, UR5-like MJCF, timestep = the urt dt of the row, "
              f"no contacts; euler is MuJoCo's default integrator.")


def run_vm_bench(build, ticks):
    """The URScript VM's cost per controller tick (tools/urt_vmbench.c): median, p99, max."""
    exe = Path(build) / "tools" / "urt_vmbench"
    if not exe.exists():
        return {"status": "skipped", "reason": f"{exe} not built"}
    try:
        proc = subprocess.run([str(exe), str(ticks)], capture_output=True, text=True, timeout=300)
        out = json.loads(proc.stdout)
    except (OSError, subprocess.SubprocessError, ValueError) as e:
        return {"status": "failed", "reason": str(e)}
    out["status"] = "ok" if proc.returncode == 0 else "failed"
    return out


# ../shared beside the checkout (or beside the worktrees' parent)
SHARED_REC = next((p / "data" / "ur5-kufieta2014" / "no5_acc_slow.csv"
                   for p in (ROOT.parent / "shared", ROOT.parents[1] / "shared")
                   if (p / "data" / "ur5-kufieta2014" / "no5_acc_slow.csv").is_file()),
                  ROOT.parent / "shared" / "data" / "ur5-kufieta2014" / "no5_acc_slow.csv")


def long_recording(path, seconds, src=SHARED_REC):
    """A recording of `seconds` in record.py's layout: src played forward, then backward in time
    (q̇ negated), and so on; without src a smooth synthetic motion of every joint."""
    import numpy as np
    if src.is_file():
        header = src.read_text().split("\n", 1)[0].split()
        fwd = np.loadtxt(src, skiprows=1, ndmin=2)
        dt = float(np.median(np.diff(fwd[:, 0])))
        back = fwd[::-1].copy()
        for i, name in enumerate(header):
            if name.startswith(("target_qd_", "actual_qd_")):
                back[:, i] = -back[:, i]
        parts, n, k = [], 0, 0
        need = int(round(seconds / dt)) + 1
        while n < need:
            part = fwd if k % 2 == 0 else back
            parts.append(part[1:] if k else part)
            n += len(parts[-1])
            k += 1
        data = np.vstack(parts)[:need]
        data[:, 0] = np.round(np.arange(need) * dt, 6)
        source = f"{src.name} forward and back"
    else:
        dt = 0.008
        t = np.arange(0.0, seconds + 1e-9, dt)
        q0 = np.array([0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0])
        w = 2 * np.pi * np.array([0.05, 0.07, 0.09, 0.11, 0.13, 0.15])
        amp = np.array([1.0, 0.4, 0.5, 0.6, 0.6, 0.8])
        q = q0 + amp * np.sin(np.outer(t, w))
        qd = amp * w * np.cos(np.outer(t, w))
        qdd = -amp * w**2 * np.sin(np.outer(t, w))
        header = ["timestamp"] + [f"{c}_{j}" for c in ("target_q", "target_qd", "target_qdd",
                                                        "actual_current") for j in range(6)]
        data = np.hstack([t[:, None], q, qd, qdd, np.zeros_like(q)])
        source = "synthetic sinusoids"
    np.savetxt(path, data, fmt="%.9g", header=" ".join(header), comments="")
    return source


def run_replay_bench(build, config, quick):
    """urt_sim --replay speed: simulated s per wall s and per CPU s of the simulating thread
    (the wall figure counts every other process on a shared machine), median of the runs, at
    the config's rate and at 10 kHz (the slowest rate the model is built for), with the
    largest difference between the two rates' RMS(twin − measured) per joint: what the
    cheaper rate changes in a replay's verdict."""
    exe = Path(build) / "tools" / "urt_sim"
    if not exe.exists():
        return {"status": "skipped", "reason": f"{exe} not built"}
    seconds, runs = (8.0, 1) if quick else (80.0, 3)

    def at_rate(rec, rate):
        speeds, cpus, walls, summary = [], [], [], None
        for _ in range(runs):
            summary = replay(rec, config=config, rate=rate, sim=exe, timeout=1800)
            speeds.append(summary["speed"])
            cpus.append(summary["speed_cpu"])
            walls.append(summary["wall"])
        speeds.sort()
        cpus.sort()
        return {"rate_hz": round(summary["steps"] / summary["duration"]), "runs": runs,
                "speed_median": speeds[len(speeds) // 2], "speeds": speeds,
                "speed_cpu_median": cpus[len(cpus) // 2], "speeds_cpu": cpus,
                "wall_s": walls}, [j["rms_err_twin"] for j in summary["joints"]]

    with tempfile.TemporaryDirectory() as tmp:
        rec = Path(tmp) / "long.csv"
        source = long_recording(rec, seconds)
        try:
            res, err = at_rate(rec, None)
            res10, err10 = at_rate(rec, 10000)
        except (OSError, subprocess.SubprocessError, ValueError, RuntimeError) as e:
            return {"status": "failed", "reason": str(e)}
    res.update({"status": "ok", "recording": source, "duration_s": seconds, "target": 10.0})
    res10["max_rms_err_diff_a"] = max(abs(a - b) for a, b in zip(err, err10))
    res["at_10khz"] = res10
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="build/bench.json", help="merged JSON (default %(default)s)")
    ap.add_argument("--build", default=os.environ.get("URT_BUILD", str(ROOT / "build")),
                    help="build directory (default $URT_BUILD or build/)")
    ap.add_argument("--config", default=str(ROOT / "config" / "ur5.yaml"))
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override passed to urt_bench and urt_config (repeatable)")
    ap.add_argument("--steps", type=int, default=20000, help="timed steps per case")
    ap.add_argument("--warmup", type=int, default=2000)
    ap.add_argument("--cpu", type=int, default=None, help="pin urt_bench to this CPU")
    # batches stay well under a scheduler slice (~0.3 ms each): on a busy machine a longer batch
    # often absorbs a preemption, which biases its mean (the median of short ones shrugs it off)
    ap.add_argument("--aba-batches", type=int, default=1000, help="interleaved ABA batches")
    ap.add_argument("--aba-per-batch", type=int, default=200, help="pin.aba calls per Python batch")
    ap.add_argument("--aba-native-batch", type=int, default=200,
                    help="configurations per abaInParallel batch")
    ap.add_argument("--quick", action="store_true", help="small counts (smoke tests)")
    ap.add_argument("--no-mujoco", action="store_true")
    ap.add_argument("--no-pinocchio", action="store_true")
    args = ap.parse_args(argv)
    if args.quick:
        args.steps, args.warmup = min(args.steps, 2000), min(args.warmup, 200)
        args.aba_batches, args.aba_per_batch, args.aba_native_batch = 20, 50, 50
    build = os.path.abspath(args.build)

    res = {"tool": "tools/bench.py", "schema": 1, "machine": machine_info(build)}
    res["urt_bench"] = run_urt_bench(args, build)
    res["pinocchio"] = ({"status": "skipped"} if args.no_pinocchio
                        else bench_aba(args, build, res["urt_bench"]))
    res["ratios"] = ratios(res["urt_bench"], res["pinocchio"])
    res["urscript_vm"] = run_vm_bench(build, 2000 if args.quick else 20000)
    res["replay"] = run_replay_bench(build, args.config, args.quick)
    res["machine"]["loadavg_end"] = list(os.getloadavg())

    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(finite_or_null(res), indent=2, allow_nan=False) + "\n")
    print_table(res)
    for name, c in res["urscript_vm"].get("cases", {}).items():
        print(f"URScript VM per controller tick, {name}: median {c['median_us']:.2f} us, "
              f"p99 {c['p99_us']:.2f} us (of a {res['urscript_vm']['period_us']} us period)")
    rp = res["replay"]
    if rp["status"] == "ok":
        print(f"urt_sim --replay, {rp['duration_s']:.0f} s recording ({rp['recording']}): "
              f"median {rp['speed_median']:.1f} x real time by the wall clock, "
              f"{rp['speed_cpu_median']:.1f} x by the simulating thread's CPU time, over "
              f"{rp['runs']} run(s) at {rp['rate_hz']} Hz (target >= 10, not asserted)")
        r10 = rp["at_10khz"]
        print(f"urt_sim --replay --rate 10000: median {r10['speed_median']:.1f} x by the wall "
              f"clock, {r10['speed_cpu_median']:.1f} x by CPU time; RMS(twin - measured) "
              f"differs from the {rp['rate_hz']} Hz replay's by at most "
              f"{r10['max_rms_err_diff_a']:.2g} A")
    else:
        print(f"urt_sim --replay: {rp['status']}: {rp.get('reason', '')}")
    print(f"wrote {out}")
    # the core is what is benchmarked: its failure fails `make bench`; MuJoCo/Pinocchio never do
    return 0 if res["urt_bench"]["urt"]["status"] == "ok" else 1


if __name__ == "__main__":
    sys.exit(main())
