# SPDX-License-Identifier: Apache-2.0
"""python/urtwin (import urtwin): the same bits as urt_sim's CSV for the same trajectory, seed,
rate and decimation; overrides and overlays as urt_sim's --set and --overlay; sampled arrays
and record.py CSVs as set-points; bad input raising with the C core's text; two threads
stepping at once (the GIL released) giving the same results as one after the other. Runs of
0.2 s (tens of ms each)."""

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import built

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("URT_BUILD", ROOT / "build"))
URT_SIM = BUILD / "tools" / "urt_sim"
CONFIG = ROOT / "config" / "ur5.yaml"
OVERLAY = ROOT / "config" / "overlays" / "ur5-kufieta2014.yaml"
built.require(URT_SIM)

# this checkout's package, whatever the venv's .pth points at
sys.path.insert(0, str(ROOT / "python"))
if not list((ROOT / "python" / "urtwin").glob("_urtwin*.so")):
    pytest.fail("python/urtwin/_urtwin*.so is not built: run make build", pytrace=False)
import urtwin  # noqa: E402


def urt_sim_csv(tmp_path, *args):
    out = tmp_path / "run.csv"
    res = subprocess.run([str(URT_SIM), "--config", str(CONFIG), "--quiet", "--out", str(out),
                          *args], capture_output=True, text=True, check=False, cwd=ROOT)
    assert res.returncode == 0, res.stderr
    return np.genfromtxt(out, delimiter=",", names=True)


def urt_sim_error(*args):
    res = subprocess.run([str(URT_SIM), "--config", str(CONFIG), "--quiet", "--duration",
                          "0.01", *args], capture_output=True, text=True, check=False, cwd=ROOT)
    assert res.returncode == 2
    return res.stderr.strip()


def assert_same_bits(result, ref):
    cols = result.csv_columns()
    assert list(cols) == list(ref.dtype.names)
    assert len(result) == ref.shape[0]
    differ = [k for k, v in cols.items() if not np.array_equal(v, ref[k])]
    assert not differ, f"columns that differ from urt_sim's: {differ}"


def test_import_from_the_venv():
    # make build writes a .pth into the venv: a plain `import urtwin` works without PYTHONPATH
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    res = subprocess.run([sys.executable, "-c", "import urtwin; print(urtwin.__file__)"],
                         capture_output=True, text=True, check=False, cwd="/", env=env)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip().endswith("urtwin/__init__.py")


@pytest.mark.parametrize("traj,args,kw", [
    ("excitation", ["--traj", "excitation", "--seed", "3", "--decimate", "10"],
     dict(traj_seed=3, decimate=10)),
    ("pickplace", ["--traj", "pickplace", "--decimate", "7"], dict(decimate=7)),
    ("hold", ["--traj", "hold", "--rate", "10000", "--decimate", "3"],
     dict(rate=10000, decimate=3)),
])
def test_same_bits_as_urt_sim(tmp_path, traj, args, kw):
    ref = urt_sim_csv(tmp_path, "--duration", "0.2", *args)
    r = urtwin.run(urtwin.Model(CONFIG), traj, duration=0.2, **kw)
    assert_same_bits(r, ref)


def test_noise_seed_is_simulation_seed(tmp_path):
    ref = urt_sim_csv(tmp_path, "--traj", "excitation", "--duration", "0.2", "--decimate",
                      "20", "--set", "simulation.seed=77")
    m = urtwin.Model(CONFIG)
    r = urtwin.run(m, "excitation", duration=0.2, decimate=20, seed=77)
    assert_same_bits(r, ref)
    # and another seed gives another noise
    r2 = urtwin.run(m, "excitation", duration=0.2, decimate=20, seed=78)
    assert not np.array_equal(r["i_meas"], r2["i_meas"])
    assert np.array_equal(r["q_set"], r2["q_set"])


def test_overrides_and_overlays_as_urt_sim(tmp_path):
    ref = urt_sim_csv(tmp_path, "--traj", "excitation", "--duration", "0.2", "--decimate",
                      "20", "--overlay", str(OVERLAY), "--set", "sensors.noise=false",
                      "--set", "joints.1.friction.f_c=9.5")
    m = urtwin.Model(CONFIG, overlays=[OVERLAY],
                     overrides={"sensors.noise": False, "joints.1.friction.f_c": 9.5})
    r = urtwin.run(m, "excitation", duration=0.2, decimate=20)
    assert_same_bits(r, ref)
    plain = urtwin.run(urtwin.Model(CONFIG, overrides=["sensors.noise=false"]), "excitation",
                       duration=0.2, decimate=20)
    assert not np.array_equal(plain["i"], r["i"])
    assert "f_c: 9.5" in m.print().replace("\"", "") or "9.5" in m.print()


def test_channels_and_units():
    r = urtwin.run(urtwin.Model(CONFIG), "hold", duration=0.05, decimate=100)
    names = [c[0] for c in urtwin.CHANNELS]
    for n in ("t", "q_set", "q", "i", "i_meas", "v", "tcs", "tf", "tcp", "qdm", "q_meas",
              "qd_meas", "i_target", "temperature", "tin", "pstop"):
        assert n in names and n in r
    assert r["i_meas"].shape == (len(r), 6) and r.t.shape == (len(r),)
    assert r.unit("i_meas") == "A"
    # the last sample is always recorded: 0.05 s = 1000 steps, rows at 0, 100, …, 1000
    assert len(r) == 11 and r.t[-1] == pytest.approx(0.05)
    # the controller's thermal model starts at ambient and warms with the holding current
    assert np.all(r["temperature"][0] == r["temperature"][0][0])
    assert np.all(r["temperature"][-1] >= r["temperature"][0])


def test_arrays_reproduce_the_built_in():
    # the excitation's own set-point at every step, given as samples, gives the same bits:
    # the Hermite and the linear interpolations return the sample at a sample's time
    m = urtwin.Model(CONFIG)
    ref = urtwin.run(m, "excitation", traj_seed=2, duration=0.1)
    tr = urtwin.from_arrays(ref.t, ref["q_set"], ref["qd_set"], ref["qdd_set"])
    r = urtwin.run(m, tr)
    assert np.array_equal(r.data, ref.data)


def test_arrays_with_derived_rates():
    # q alone at 500 Hz: q̇, q̈ from finite differences; the drives follow the same motion
    m = urtwin.Model(CONFIG, overrides={"sensors.noise": False})
    ref = urtwin.run(m, "excitation", traj_seed=2, duration=0.2, decimate=40)
    tr = urtwin.from_arrays(ref.t, ref["q_set"])
    assert tr.kind == "samples" and tr.duration == pytest.approx(0.2)
    r = urtwin.run(m, tr, decimate=40)
    assert np.max(np.abs(r["q_set"] - ref["q_set"])) < 1e-7
    assert np.max(np.abs(r["qd_set"][2:-2] - ref["qd_set"][2:-2])) < 1e-3
    assert np.max(np.abs(r["q"] - ref["q"])) < 1e-5


def test_record_csv(tmp_path):
    m = urtwin.Model(CONFIG, overrides={"sensors.noise": False})
    ref = urtwin.run(m, "excitation", traj_seed=4, duration=0.2, decimate=40)
    path = tmp_path / "rec.csv"
    cols = ["timestamp"] + [f"{n}_{j}" for n in ("target_q", "target_qd", "actual_current")
                            for j in range(6)]
    rows = np.column_stack([ref.t + 12.5, ref["q_set"], ref["qd_set"], ref["i_meas"]])
    np.savetxt(path, rows, header=" ".join(cols), comments="", fmt="%.17g")
    rec = urtwin.read_record_csv(path)
    assert np.array_equal(rec["target_q"], ref["q_set"])
    r = urtwin.run(m, urtwin.from_record_csv(path), decimate=40)
    assert r.t[0] == 0.0 and len(r) == len(ref)
    assert np.max(np.abs(r["q_set"] - ref["q_set"])) < 1e-7


def test_bad_input_raises_with_the_c_text(tmp_path):
    with pytest.raises(ValueError) as e:
        urtwin.Model(CONFIG, overrides=["sensors.nosie=false"])
    assert str(e.value) == urt_sim_error("--set", "sensors.nosie=false")
    with pytest.raises(ValueError, match="cannot open"):
        urtwin.Model(CONFIG, overlays=[tmp_path / "missing.yaml"])
    with pytest.raises(ValueError, match="rate"):
        urtwin.Model(CONFIG, rate=-5)
    m = urtwin.Model(CONFIG)
    t = np.linspace(0, 0.1, 11)
    q = np.tile(m.q0, (11, 1))
    with pytest.raises(ValueError, match=r"q: expected shape \(11, 6\), got \(11, 5\)"):
        urtwin.from_arrays(t, q[:, :5])
    with pytest.raises(ValueError, match=r"qdd: expected shape \(11, 6\)"):
        urtwin.from_arrays(t, q, np.zeros((11, 6)), np.zeros((10, 6)))
    qn = q.copy()
    qn[4, 2] = np.nan
    with pytest.raises(ValueError, match="q: non-finite value at sample 4"):
        urtwin.from_arrays(t, qn)
    with pytest.raises(ValueError, match="strictly increasing"):
        urtwin.from_arrays(t[::-1], q)
    with pytest.raises(ValueError, match="decimate"):
        urtwin.run(m, "hold", decimate=0)
    with pytest.raises(ValueError, match="trajectory: expected"):
        urtwin.run(m, "wave")
    # an empty scenario is the loader's error (tests/python/test_urtwin_faults.py: the rest)
    with pytest.raises(ValueError, match=r"^<faults>:1: faults: must be a list"):
        urtwin.run(m, "hold", faults="faults: []")
    # a built-in trajectory the model's limits refuse: urt_traj_check's text
    with pytest.raises(ValueError, match=r"joint 1 \(base\).*qd_max"):
        urtwin.excitation(urtwin.Model(CONFIG, overrides=["joints.0.qd_max=0.01"]), 1)
    # a sampled set-point beyond a limit: refused at run time, as urt_command_set refuses it
    fast = q.copy()
    fast[:, 0] += np.linspace(0, 2.0, 11)   # 20 rad/s
    with pytest.raises(RuntimeError, match="command refused .*speed limit"):
        urtwin.run(m, urtwin.from_arrays(t, fast))
    bad = tmp_path / "bad.csv"
    bad.write_text("timestamp target_q_0 bogus\n0 0 0\n")
    with pytest.raises(ValueError, match="bad.csv:1"):
        urtwin.read_record_csv(bad)


def test_threads_step_in_parallel():
    # the GIL is released while a run steps: two threads give the results of two runs in
    # sequence, and the wall times are printed (measured, not asserted: the machine is shared)
    m = urtwin.Model(CONFIG)
    kw = dict(duration=0.5, decimate=100)
    t0 = time.perf_counter()
    seq = [urtwin.run(m, "excitation", traj_seed=s, **kw) for s in (1, 2)]
    t_seq = time.perf_counter() - t0
    par = [None, None]

    def work(i):
        par[i] = urtwin.run(m, "excitation", traj_seed=i + 1, **kw)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    t0 = time.perf_counter()
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    t_par = time.perf_counter() - t0
    for a, b in zip(seq, par):
        assert np.array_equal(a.data, b.data)
    print(f"two 0.5 s runs: in sequence {t_seq:.3f} s, in two threads {t_par:.3f} s "
          f"(speed-up {t_seq / t_par:.2f}x)")


def test_a_python_thread_runs_while_the_c_loop_steps():
    # the direct proof that the GIL is released: a pure-Python thread notes the time as it
    # goes, and some of its notes fall inside the C call (more than the 5 ms switch interval
    # from either end: with the GIL held it could not run there at all)
    m = urtwin.Model(CONFIG)
    tr = urtwin.excitation(m, 1)
    notes, stop = [], [False]

    def spin():
        n = 0
        while not stop[0]:
            n += 1
            if n % 1000 == 0:
                notes.append(time.perf_counter())

    th = threading.Thread(target=spin)
    th.start()
    time.sleep(0.05)
    t0 = time.perf_counter()
    urtwin._urtwin.run(m._m, tr, 1.0, 100, None)   # the C call alone, no Python around it
    t1 = time.perf_counter()
    stop[0] = True
    th.join()
    inside = [t for t in notes if t0 + 0.02 < t < t1 - 0.02]
    assert t1 - t0 > 0.05 and inside, f"no progress of the Python thread in {t1 - t0:.3f} s"
    print(f"the Python thread noted {len(inside)} times during the {t1 - t0:.3f} s C call")
