# SPDX-License-Identifier: Apache-2.0
"""Smoke test of the benchmark: urt_bench and tools/bench.py run and write complete JSON.

Only structure and sanity (positive, finite, ordered percentiles) are checked — never a time:
the machine is shared and noisy, so a timing threshold would only make the suite flaky.
"""

import glob
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

import built

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("URT_BUILD", ROOT / "build"))
URT_BENCH = BUILD / "tools" / "urt_bench"
STATS = ("median_us", "p99_us", "p999_us", "max_us", "mean_us", "min_us", "rtf",
         "wall_s_per_sim_s")

built.require(URT_BENCH)


def mujoco_lib():
    try:
        import mujoco
    except ImportError:
        return None
    libs = glob.glob(os.path.join(os.path.dirname(mujoco.__file__), "libmujoco.so*"))
    return max(libs, key=len) if libs else None


def run_urt_bench(tmp_path, *extra):
    out = tmp_path / "urt_bench.json"
    cmd = [str(URT_BENCH), "--config", str(ROOT / "config" / "ur5.yaml"), "--steps", "2000",
           "--warmup", "200", "--json", str(out), "--quiet", *extra]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert out.is_file(), proc.stderr
    return proc, json.loads(out.read_text())


def check_stats(run, n):
    assert run["status"] == "ok", run.get("error")
    assert run["n"] == n
    for key in STATS:
        assert math.isfinite(run[key]) and run[key] > 0, key
    # order statistics of one sample: holds whatever the machine is doing
    assert run["min_us"] <= run["median_us"] <= run["p99_us"] <= run["p999_us"] <= run["max_us"]


def test_urt_bench__writes_stats_for_both_rates_and_mujoco(tmp_path):
    lib = mujoco_lib()
    proc, res = run_urt_bench(tmp_path, *(["--mujoco-lib", lib] if lib else []))
    assert proc.returncode == 0, proc.stderr

    urt = res["urt"]
    assert urt["status"] == "ok", urt.get("error")
    # both rates healthy, and the first again with five faults active (issue 11)
    assert sorted((r["dt"], r["faults"]) for r in urt["runs"]) == [(5e-5, 0), (5e-5, 5),
                                                                   (1e-4, 0)]
    for run in urt["runs"]:
        check_stats(run, 2000)
        assert run["step_errors"] == 0 and run["pstop"] == 0
    faulted = [r for r in res["ratios"] if r["numerator"] == "urt_step median, 5 faults active"]
    assert len(faulted) == 1 and faulted[0]["dt"] == 5e-5 and faulted[0]["value"] > 0

    assert len(res["arm"]["links"]) == 6
    assert res["clock"]["overhead_ns"] > 0

    mj = res["mujoco"]
    if lib is None:
        assert mj["status"] == "unavailable"
        return
    assert mj["status"] == "ok", mj.get("error")
    assert mj["version"]
    assert {r["variant"] for r in mj["runs"]} >= {"euler"}
    for run in mj["runs"]:
        check_stats(run, 2000)
    euler = [r for r in res["ratios"] if r["denominator"] == "mj_step median (euler)"]
    assert len(euler) == 2 and all(r["value"] > 0 for r in euler)


def test_urt_bench__reports_mujoco_unavailable_without_failing(tmp_path):
    proc, res = run_urt_bench(tmp_path, "--steps", "100",
                              "--mujoco-lib", "/nonexistent/libmujoco.so")
    assert proc.returncode == 0, proc.stderr
    assert res["mujoco"]["status"] == "unavailable"
    assert "dlopen" in res["mujoco"]["error"]
    assert res["mujoco"]["runs"] == []
    assert res["urt"]["status"] == "ok"


def test_bench_py__merges_everything_into_one_json(tmp_path):
    out = tmp_path / "bench.json"
    env = dict(os.environ, URT_BUILD=str(BUILD))
    proc = subprocess.run([sys.executable, str(ROOT / "tools" / "bench.py"), "--quick",
                           "--out", str(out)], capture_output=True, text=True, cwd=ROOT,
                          env=env, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    res = json.loads(out.read_text())

    assert res["machine"]["cpu_model"] and res["machine"]["date_utc"]
    assert res["urt_bench"]["urt"]["status"] == "ok"
    assert res["urt_bench"]["mujoco"]["status"] in ("ok", "unavailable")
    pin = res["pinocchio"]
    assert pin["status"] in ("ok", "unavailable")
    if pin["status"] == "ok":
        assert pin["python_raw"]["median_us"] > 0
        assert pin["python_binding_reference"]["median_us"] > 0
        assert len(pin["gravity_torque_q0"]) == 6
        if "median_us" in pin["native"]:
            assert pin["native"]["median_us"] > 0
            assert pin["native"]["max_rel_diff_vs_aba"] < 1e-9
    assert res["ratios"] and all(r["value"] > 0 for r in res["ratios"])
    assert "urt_step" in proc.stdout
    # the replay speed: reported (8 s recording in --quick), never judged against its target
    rp = res["replay"]
    assert rp["status"] == "ok", rp
    assert rp["runs"] == 1 and rp["duration_s"] == 8.0
    assert math.isfinite(rp["speed_median"]) and rp["speed_median"] > 0
    # per CPU second too (a shared machine's wall clock counts the others)
    assert math.isfinite(rp["speed_cpu_median"]) and rp["speed_cpu_median"] > 0
    assert rp["rate_hz"] == 20000 and rp["at_10khz"]["rate_hz"] == 10000
    # the same recording at half the rate: a replay judged at 125 Hz barely notices
    assert 0 <= rp["at_10khz"]["max_rms_err_diff_a"] < 0.01
    assert "urt_sim --replay" in proc.stdout and "--rate 10000" in proc.stdout


def test_bench_physics_worst__reports_ordered_figures_and_the_motion_ran(tmp_path):
    """tools/bench_physics_worst.py: both runs give ordered per-period quantiles from the
    emulator itself, the loaded run really moved (movel) and really flooded (RTDE inputs)."""
    out = tmp_path / "worst.json"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "bench_physics_worst.py"), "--seconds", "2",
         "--host", "127.0.0.81", "--out", str(out)],
        capture_output=True, text=True, cwd=ROOT, timeout=240,
        env={**os.environ, "URT_BUILD": str(BUILD)})
    assert proc.returncode == 0, proc.stderr + proc.stdout
    res = json.loads(out.read_text())
    # as root, the same two runs again with urtwin at SCHED_FIFO (--rt auto)
    names = ("idle", "loaded") + (("idle_rt", "loaded_rt") if os.geteuid() == 0 else ())
    assert sorted(k for k in res if k.startswith(("idle", "loaded"))) == sorted(names)
    for name in names:
        r = res[name]
        assert r["period_us"] == 2000
        for series in ("wall_us", "cpu_us"):
            q = r[series]
            assert 0 < q["p50"] <= q["p99"] <= q["p999"] <= q["max"], (name, series, q)
    for suffix in ("", "_rt") if os.geteuid() == 0 else ("",):
        loaded = res["loaded" + suffix]
        assert loaded["tcp_x_travel_m"] > 0.05  # movel moved the TCP (0.15 m per leg)
        assert loaded["rtde_inputs_per_s"] > 1000 and loaded["dashboard_answered"] > 0
        assert res["idle" + suffix]["tcp_x_travel_m"] < 1e-3
        # one forced refined step per period (simulation.refine_every=40 at 20 kHz), none idle
        assert loaded["refined_steps"] >= 0.9 * loaded["periods"] > 0
        assert res["idle" + suffix]["refined_steps"] == 0
    for name in names:
        r = res[name]
        assert 0 <= r["wall_over_half"] <= r["periods"] and 0 <= r["cpu_over_half"] <= r["periods"]


def test_bench_dataset__reports_both_worker_counts_and_the_bare_rate(tmp_path):
    """tools/bench_dataset.py --quick: one round, a sweep on 1 and on 2 Ray workers (in a
    loopback-only network namespace) each between two bare rates of the same runs (urt_sim),
    every figure positive, Ray's start-up and shutdown timed apart; the ratios are derived from them (each
    sweep against the mean of the bare rates around it)."""
    out = tmp_path / "dataset.json"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "bench_dataset.py"), "--quick", "--out", str(out)],
        capture_output=True, text=True, cwd=ROOT, timeout=600,
        env={**os.environ, "URT_BUILD": str(BUILD)})
    assert proc.returncode == 0, proc.stderr + proc.stdout
    res = json.loads(out.read_text())
    assert res["bare_urt_step_rtf"] > 0 and len(res["bare_sweep_rate_all"]) == 3
    assert all(b > 0 for b in res["bare_sweep_rate_all"])
    assert len(res["rounds"]) == 1
    rnd = res["rounds"][0]
    for w in (1, 2):
        t = rnd[f"workers_{w}"]
        assert t["workers"] == w and t["ray"] and t["runs"] == 4
        assert t["simulated_s"] == pytest.approx(4.0)
        assert t["wall_s"] > 0 and t["ray_start_s"] > 0 and t["ray_stop_s"] > 0
        before, after = rnd[f"bare_rate_adjacent_{w}"]
        assert rnd[f"per_worker_over_bare_{w}"] == pytest.approx(
            t["sim_per_wall"] / w / (0.5 * (before + after)))
    assert res["bare_sweep_rate_all"][1] == rnd["bare_rate_adjacent_1"][1] == \
        rnd["bare_rate_adjacent_2"][0]
    assert res["per_worker_over_bare"] == pytest.approx(rnd["per_worker_over_bare_1"])
    assert res["per_worker_over_loops"] == pytest.approx(
        rnd["workers_1"]["sim_per_wall"] / rnd["workers_1"]["sim_per_loop_cpu"])
    assert res["scaling_2_over_1"] == pytest.approx(
        rnd["workers_2"]["sim_per_wall"] / rnd["workers_1"]["sim_per_wall"])
    assert "2 workers / 1 worker" in proc.stdout
