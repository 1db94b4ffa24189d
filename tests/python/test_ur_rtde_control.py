# SPDX-License-Identifier: Apache-2.0
"""ur_rtde 1.6.5's RTDEControlInterface, unmodified, against a urtwin process: its ~50 kB
rtde_control script is recognised on 30003 and run natively. The arm's motion is judged on the
30003 stream; dynamics getters against the core's own functions (through liburtwin.so).
Numbers are printed (pytest -s)."""

import json
import math
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

import built

import urtwin_ctypes as urt
from urtwin_proc import RT_ARGS, Emulator, RtReader, URTWIN

import rtde_control
import rtde_receive

SERVO_CLIENT = Path(__file__).resolve().parent / "ur_rtde_servo_client.py"
built.require(URTWIN)

# the version whose pruned script keeps the dynamics getters (from 5.23; ur_rtde removes them
# from the script it sends to older controllers)
FULL = "5.23"
# ur_rtde 1.6.5 sends direct_torque (with viscous_scale and coulomb_scale) from 5.26 only; to
# older controllers its directTorque is a no-op in the script ("dummy_op = 1")
TORQUE = "5.26"


class Stream:
    """Every 30003 packet, on a thread; also checks the period never breaks."""

    def __init__(self, host, period=0.002):
        self.period, self.packets, self.stop = period, [], threading.Event()
        self.rt = RtReader(host)
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()
        # a client call that holds the GIL (ur_rtde's constructor does) would otherwise leave
        # this thread without its first packet when the test asks for the latest one
        t_end = time.monotonic() + 2.0
        while not self.packets and time.monotonic() < t_end:
            time.sleep(0.001)

    def _run(self):
        while not self.stop.is_set():
            self.packets.append(self.rt.read_decoded())

    def since(self, t):
        return [p for p in list(self.packets) if p["time"] >= t]

    def latest(self):
        return self.packets[-1]

    def motion(self, t_from, standing=25, timeout=5.0):
        """The motion since controller time t_from, once this reader has seen the arm stand for
        `standing` ticks after it (the reader may lag the controller): (controller time of the
        first and of the last tick with a nonzero target speed, the newest packet)."""
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            ps = self.since(t_from)
            moving = [p for p in ps if any(abs(v) > 1e-9 for v in p["qd_target"])]
            if moving and ps[-1]["time"] - moving[-1]["time"] >= standing * self.period - 1e-9:
                return moving[0]["time"], moving[-1]["time"], ps[-1]
            time.sleep(0.005)
        raise AssertionError(f"no motion since t={t_from} ended within {timeout} s on 30003")

    def rest_speed(self, window=0.2):
        """Largest mean joint speed over the last `window` s, from the positions: the measured
        speed alone flickers by one encoder quantum (a few mrad/s) at rest."""
        last = self.packets[-1]
        first = next(p for p in reversed(self.packets) if last["time"] - p["time"] >= window)
        return max(abs(a - b) for a, b in zip(last["q_actual"], first["q_actual"])) / (
            last["time"] - first["time"])

    def irregular(self):
        ts = [p["time"] for p in self.packets]
        return sum(1 for a, b in zip(ts, ts[1:]) if round((b - a) / self.period) != 1)

    def close(self):
        self.stop.set()
        self.thread.join(timeout=2)
        self.rt.close()


class RtdeStream:
    """Another RTDE client at 500 Hz beside ur_rtde's (clean-room client): counts breaks."""

    def __init__(self, host, extra=()):
        from rtde_client import RtdeClient
        self.c = RtdeClient(host).connect()
        self.c.negotiate_protocol_version(2)
        self.extra = list(extra)
        self.c.setup_outputs(["timestamp", "actual_q"] + self.extra, frequency=500)
        self.c.start()
        self.ts, self.values, self.stop = [], [], threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        while not self.stop.is_set():
            v = self.c.receive().values
            self.ts.append(v["timestamp"])
            if self.extra:
                self.values.append(v)

    def irregular(self):
        return sum(1 for a, b in zip(self.ts, self.ts[1:]) if round((b - a) / 0.002) != 1)

    def close(self):
        self.stop.set()
        self.thread.join(timeout=2)
        self.c.close()


@pytest.fixture(scope="module")
def ur5_model():
    lib = urt.load_library()
    with urt.Model(lib, urt.UR5_YAML) as m:
        yield m


@pytest.mark.parametrize("version", ["5.19", "3.15", FULL, TORQUE])
def test_constructor_is_fast_and_the_script_runs(version):
    with Emulator(version=version) as emu:
        t0 = time.monotonic()
        c = rtde_control.RTDEControlInterface(emu.host)
        took = time.monotonic() - t0
        running = c.isProgramRunning()
        c.stopScript()
        c.disconnect()
    print(f"\n{version}: RTDEControlInterface constructor {took * 1000:.0f} ms, running {running}")
    # about 80 ms here; the bound is ur_rtde's own patience (2.5 s socket timeouts; 5 s for the
    # program to start): it catches a constructor that falls back on a timeout, not a slow machine
    assert took < 2.5 and running


def trapezoid_time(dist, a, v):
    return 2 * math.sqrt(dist / a) if dist * a < v * v else dist / v + v / a


def test_movej_movel_ik_fk():
    with Emulator() as emu:
        s = Stream(emu.host)
        other = RtdeStream(emu.host)
        c = rtde_control.RTDEControlInterface(emu.host)
        time.sleep(0.05)
        first = s.latest()
        q0 = first["q_actual"]
        target = list(q0)
        target[1] += math.radians(30)
        t0 = time.monotonic()
        assert c.moveJ(target, 1.05, 1.4)
        took = time.monotonic() - t0
        # judged in controller time: the ticks with a nonzero target speed, then the arm at rest
        m0, m1, rest_j = s.motion(first["time"])
        dur_j = m1 - m0 + s.period
        err_j = max(abs(a - b) for a, b in zip(rest_j["q_actual"], target))
        ideal = trapezoid_time(math.radians(30), 1.4, 1.05)

        # moveL 10 cm along x; the deviation from the line is read off 30003
        p0 = rest_j["tool_vector_actual"]
        goal = list(p0)
        goal[0] += 0.10
        assert c.moveL(goal, 0.25, 1.2)
        _, _, rest_l = s.motion(rest_j["time"], standing=100)  # settled, as 0.2 s after
        track = [p["tool_vector_actual"] for p in s.since(rest_j["time"]) if p["time"] <= rest_l["time"]]
        end = rest_l["tool_vector_actual"]
        err_l = math.dist(end[:3], goal[:3])
        dev = max(math.hypot(p[1] - p0[1], p[2] - p0[2]) for p in track)

        # ur_rtde 1.6.5 quirks, as against a real controller: getForwardKinematics(q) sends only
        # d0..d5 while its script reads the TCP offset from d6..d11, whatever the last command
        # left there (a moveL's speed and acceleration, a qnear); getForwardKinematics(q, tcp)
        # sends 12 doubles on its 6-double recipe, which the controller drops (the call then
        # waits 300 s). poseTrans writes d0..d11, so zeros there first make FK(q) exact.
        rt = 0.0
        for q in (s.latest()["q_actual"], [0.4, -1.1, 1.3, -1.9, -1.4, 0.7],
                  [-1.0, -2.0, -1.2, -1.2, 1.6, -2.0]):
            c.poseTrans([0.0] * 6, [0.0] * 6)
            fk = c.getForwardKinematics(q)
            ik = c.getInverseKinematics(fk, q)
            rt = max(rt, max(abs(a - b) for a, b in zip(ik, q)))
        c.stopScript()
        c.disconnect()
        s.close()
        other.close()
    print(f"\nmoveJ 30 deg: moved for {dur_j:.3f} s of controller time (trapezoid {ideal:.3f} s, "
          f"{100 * (dur_j / ideal - 1):+.2f} %; the call returned after {took:.3f} s of wall time), "
          f"error {err_j:.2e} rad; moveL 10 cm: end error "
          f"{err_l * 1e3:.4f} mm, max deviation from the line {dev * 1e3:.4f} mm; IK(FK(q)) "
          f"round trip {rt:.2e} rad; irregular steps: 30003 {s.irregular()}, other RTDE client "
          f"{other.irregular()} of {len(other.ts)}")
    # the planner ends the trapezoid on a controller tick
    assert abs(dur_j - ideal) <= 2 * s.period + 1e-9 and err_j < 1e-4
    assert err_l < 1e-4 and dev < 1e-4
    assert rt < 1e-9
    assert s.irregular() == 0 and other.irregular() == 0 and len(other.ts) > 1000


def cpu_hogs(n):
    """n busy processes at normal priority (killed by the caller)"""
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]


def servoj_law(held, q_start, gain, lookahead, period, substeps=8):
    """What servoj's documented law (core/motion_servoj.cpp: q'' = gain (target - q - lookahead
    q'), which follows a ramp exactly lookahead late) makes of targets held one per controller
    tick, from rest at q_start: [(time, q)], each at the end of its tick. The joints' speed and
    acceleration limits, which the law also obeys, are far from this test's sine."""
    q, v, h, out = q_start, 0.0, period / substeps, []
    for t, target in held:
        for _ in range(substeps):
            v1 = v + gain * (target - q - lookahead * v) * h
            q += 0.5 * (v + v1) * h
            v = v1
        out.append((t + period, q))
    return out


@pytest.mark.parametrize("hogs", [0, 2])
def test_servoj_sine_tracks_with_the_lookahead_lag_then_servo_stop(hogs):
    """ur_rtde's servoJ at 500 Hz (issue 9), gain and lookahead URCL's and the ROS 2 driver's
    (2000, 0.03 s), the sine tests/urcl/ros2_driver_pattern's (0.2 rad, 0.2 Hz), also beside two
    busy processes. Judged against the commands as they reached the controller, tick by tick
    (the input register ur_rtde writes them to, read back by a second RTDE client): the arm
    moves as servoj's law makes of them, within 2 ticks and 1e-3 rad — the law follows a ramp
    exactly one lookahead late, so the arm follows the command one lookahead late. How often
    and how evenly the client managed to send is the client's and the machine's: a starved
    client's commands arrive as a staircase, and the arm must follow the law's response to that
    staircase all the same (a CI run's client reached the controller every 3-6 ticks). Measured
    (-s): arm 6e-5-1.3e-4 rad off the law at 0 ticks, also without --rt-priority beside the
    hogs (the input latch and the late-servoj replay: net/urscript/README.md)."""
    period, lookahead, gain = 0.002, 0.03, 2000
    amp, freq, seconds = 0.2, 0.2, 5.0
    rt_client = ["chrt", "-f", "50"] if RT_ARGS else []
    with Emulator() as emu:
        s = Stream(emu.host)
        # a second RTDE client reads back input_double_register_0, where ur_rtde writes the servoJ
        # target's base angle, with the arm's angle and the controller's set-point of the same tick
        other = RtdeStream(emu.host, extra=["input_double_register_0", "target_q", "target_qd"])
        busy = cpu_hogs(hogs)
        try:
            r = subprocess.run([*rt_client, sys.executable, str(SERVO_CLIENT), emu.host,
                                str(seconds), str(lookahead), str(gain), str(amp), str(freq)],
                               capture_output=True, text=True, timeout=60)
        finally:
            for p in busy:
                p.kill()
                p.wait()
        assert r.returncode == 0, r.stderr[-2000:]
        sent = json.loads(r.stdout.strip().splitlines()[-1])
        # the arm at rest after servoStop (the script's stop): 1 s of packets after it
        t_end = time.monotonic() + 5
        while s.latest()["time"] < sent[-1][0] + 1.2 and time.monotonic() < t_end:
            time.sleep(0.01)
        rest = s.rest_speed()
        s.close()
        other.close()
    ticks = [v for v in other.values if v["timestamp"] >= sent[0][0]]
    # every tick is there (the indices below count ticks)
    assert other.irregular() == 0 and len(other.ts) > 2500
    held = [(v["timestamp"], v["input_double_register_0"]) for v in ticks]
    law = servoj_law(held, ticks[0]["actual_q"][0], gain, lookahead, period)
    t0 = sent[0][0]
    mid = [v for v in ticks if 1.5 < v["timestamp"] - t0 < seconds - 0.5]
    first = ticks.index(mid[0])

    def residual(key, shift):
        """largest |key's base angle - the law's, `shift` ticks earlier| over the middle ticks"""
        return max(abs(v[key][0] - law[first + i - 1 - shift][1]) for i, v in enumerate(mid))
    shift_arm = min(range(0, 6), key=lambda k: residual("actual_q", k))
    res_arm = residual("actual_q", shift_arm)
    shift_set = min(range(0, 6), key=lambda k: residual("target_q", k))
    res_set = residual("target_q", shift_set)
    # printed beside it: the arm against the command itself one lag late, as the issue first put
    # it; a client that reached the controller only every few ticks leaves a staircase there
    lag_cmd = min(range(0, 40), key=lambda k: sum(
        (v["actual_q"][0] - held[first + i - k][1]) ** 2 for i, v in enumerate(mid)))
    res_cmd = max(abs(v["actual_q"][0] - held[first + i - lag_cmd][1]) for i, v in enumerate(mid))
    streamed = [r for t, r in held if t <= sent[-1][0]]
    changes = sum(1 for a, b in zip(streamed, streamed[1:]) if a != b)
    longest, run = 0, 0
    for a, b in zip(streamed, streamed[1:]):
        run = run + 1 if a == b else 0
        longest = max(longest, run)
    print(f"\nservoJ {freq} Hz sine streamed by ur_rtde ({hogs} CPU hogs, emulator "
          f"{'real-time' if RT_ARGS else 'plain'}, client "
          f"{'SCHED_FIFO' if rt_client else 'plain'}): the command reached the controller in "
          f"{changes} of {len(streamed)} ticks (longest hold {longest + 1} ticks); against servoj's law "
          f"applied to it (lag {lookahead * 1e3:.0f} ms): set-point {shift_set} ticks later, "
          f"{res_set:.2e} rad; arm {shift_arm} ticks later, {res_arm:.2e} rad; against the command "
          f"{lag_cmd * period * 1e3:.0f} ms late, {res_cmd:.2e} rad; after servoStop "
          f"|qd| {rest:.2e} rad/s; irregular steps: 30003 {s.irregular()}, other RTDE client "
          f"{other.irregular()} of {len(other.ts)}")
    # lag = lookahead + shift within 4 ms, as issue 9 asks; what is left after it within 1e-3 rad
    assert shift_arm <= 2 and res_arm <= 1e-3
    assert rest < 1e-3
    assert s.irregular() == 0


def test_speedj_one_second_then_speed_stop():
    """speedJ holds the commanded speeds until speedStop, judged in controller time: the span
    of nonzero target speeds on 30003 is when the controller held the command (the client's
    wall clock and this reader both lag it under load), and the arm moves the commanded speed
    times that span, less what the ramps at `a` lose."""
    with Emulator() as emu:
        s = Stream(emu.host)
        c = rtde_control.RTDEControlInterface(emu.host)
        time.sleep(0.05)
        q0 = s.latest()["q_actual"]
        t_cmd = s.latest()["time"]
        qd = [0.2, 0.0, 0.0, 0.0, 0.0, -0.3]
        a = 10.0
        t0 = time.monotonic()
        assert c.speedJ(qd, a, 0.0)
        while time.monotonic() - t0 < 1.0:
            time.sleep(0.001)
        c.speedStop(a)
        t_first, t_last, _ = s.motion(t_cmd)
        time.sleep(0.3)
        q1 = s.latest()["q_actual"]
        rest = s.rest_speed()
        c.stopScript()
        c.disconnect()
        s.close()
    span = [p for p in s.packets if t_first <= p["time"] <= t_last]
    moved = [b - a for a, b in zip(q0, q1)]
    # the same velocity profile, integrated from the target speeds the controller produced
    integral = [sum(p["qd_target"][j] for p in span) * s.period for j in range(6)]
    err = max(abs(m / i - 1) for m, i in zip(moved, integral) if abs(i) > 1e-3)
    # ramp up and ramp down at a, both over the leading joint's |qd|/a: each loses half of its
    # time at full speed; the span runs from the first to the last nonzero tick (one period
    # more than the held time)
    held = t_last - t_first + s.period - max(abs(v) for v in qd) / a
    expected = [v * held for v in qd]
    print(f"\nspeedJ held {t_last - t_first:.3f} s of controller time (1 s on the client's "
          f"clock): moved {moved[0]:.4f}, {moved[5]:.4f} rad (commanded {expected[0]:.4f}, "
          f"{expected[5]:.4f}: {100 * (moved[0] / expected[0] - 1):+.2f} %, "
          f"{100 * (moved[5] / expected[5] - 1):+.2f} %); the target-speed profile integrates to "
          f"the motion within {100 * err:.2f} %; after speedStop |qd| {rest:.2e} rad/s")
    assert 0.9 <= t_last - t_first <= 3.0  # sanity: the client held it 1 s by its own clock
    assert abs(moved[0] / expected[0] - 1) < 0.02
    assert abs(moved[5] / expected[5] - 1) < 0.02
    assert err < 0.01
    assert rest < 1e-3


def test_dynamics_getters_equal_the_core(ur5_model):
    """getJacobian() and getMassMatrix() are the core's own functions at the actual q of the
    tick that served them. ur_rtde's script calls get_jacobian() and get_mass_matrix() without
    arguments (it ignores a q given to the client), so the reference is the core evaluated at
    the 30003 q of each tick around the call; the closest must agree to rounding.

    ur_rtde's receive thread stores output_int_register_0 (the script's "done") before the
    double registers of the same package, and the caller reads the registers as soon as it sees
    "done": a receive thread preempted between the two hands back the previous command's
    registers (seen under load). Each getter is called three times and judged on its best call;
    the count of calls that read another command's registers is printed."""
    import numpy as np
    with Emulator(version=FULL) as emu:
        s = Stream(emu.host)
        c = rtde_control.RTDEControlInterface(emu.host)
        time.sleep(0.05)
        t0 = s.latest()["time"]
        Js, Ms = [], []
        for _ in range(3):
            Js.append(np.array(c.getJacobian()).reshape(6, 6).T)  # written column by column
            Ms.append(np.array(c.getMassMatrix()).reshape(6, 6).T)
        time.sleep(0.02)
        around = s.since(t0 - 0.01)
        c.stopScript()
        c.disconnect()
        s.close()

    def err(A, f):
        return min(np.abs(A - f(p["q_actual"])).max() for p in around)
    errsJ = [err(J, ur5_model.jacobian) for J in Js]
    errsM = [err(M, ur5_model.mass_matrix) for M in Ms]
    stale = sum(e >= 1e-12 for e in errsJ + errsM)
    print(f"\ngetJacobian vs core at the tick's q: max |diff| {min(errsJ):.2e}; getMassMatrix: "
          f"{min(errsM):.2e}; calls that read another command's registers: {stale} of 6")
    assert min(errsJ) < 1e-12 and min(errsM) < 1e-12


def test_direct_torque_zero_holds_still_and_a_torque_moves_the_joint():
    """UR's direct_torque compensates gravity itself ("the provided target torque should not
    include gravity compensation", script manual 5.25.1): zero torques hold the arm, which
    would fall without it; a torque on wrist 3 turns wrist 3 alone."""
    with Emulator(version=TORQUE) as emu:
        s = Stream(emu.host)
        c = rtde_control.RTDEControlInterface(emu.host)
        time.sleep(0.05)

        def stream(torque, seconds):
            t_end = time.monotonic() + seconds
            while time.monotonic() < t_end:
                t_cycle = c.initPeriod()
                assert c.directTorque(torque)
                c.waitPeriod(t_cycle)

        q0 = s.latest()["q_actual"]
        stream([0.0] * 6, 2.0)
        q1 = s.latest()["q_actual"]
        stream([0.0] * 5 + [5.0], 0.2)
        q2 = s.latest()["q_actual"]
        c.stopScript()
        c.disconnect()
        s.close()
    drift = max(abs(a - b) for a, b in zip(q1, q0))
    others = max(abs(a - b) for a, b in zip(q2[:5], q1[:5]))
    print(f"\ndirectTorque(0) for 2 s: max drift {drift:.2e} rad; "
          f"+5 N m on wrist 3 for 0.2 s (its friction is about 2-4 N m): wrist 3 {q2[5] - q1[5]:+.3f} rad, others {others:.2e} rad")
    # the wrist moving proves the torques arrived (a script without direct_torque holds in
    # position control); the hold before it, that gravity was compensated
    assert drift < 1e-3
    assert q2[5] - q1[5] > 0.05 and others < 1e-3


def test_watchdog_stops_the_program_and_the_arm():
    """rtde_set_watchdog at 4 Hz: kicked at 50 Hz the program runs; without kicks it stops
    within 1/f, in controller time. 4 Hz rather than 10: a test process starved for 100 ms on
    a loaded machine would miss a 10 Hz watchdog as a real client would, and the stop read
    from this reader can be late by its own lag (up to 0.1 s seen under load)."""
    freq = 4.0
    with Emulator() as emu:
        s = Stream(emu.host)
        c = rtde_control.RTDEControlInterface(emu.host)
        assert c.setWatchdog(freq)
        t_end = time.monotonic() + 0.5
        while time.monotonic() < t_end:  # kicked at 50 Hz: keeps running
            c.kickWatchdog()
            time.sleep(0.02)
        assert c.isProgramRunning()
        q = s.latest()["q_actual"]
        target = list(q)
        target[0] += 0.5
        c.moveJ(target, 0.5, 1.0, True)  # an asynchronous move, then no more kicks
        t_last_kick = s.latest()["time"]
        time.sleep(1.0 / freq + 0.5)
        stopped = [p for p in s.since(t_last_kick) if p["program_state"] != 2]
        t_stop = stopped[0]["time"] - t_last_kick if stopped else None
        time.sleep(1.0)
        rest = s.rest_speed()
        running = c.isProgramRunning()
        c.disconnect()
        s.close()
    assert t_stop is not None, "the program kept running without kicks"
    print(f"\nwatchdog {freq:.0f} Hz: program stopped {t_stop * 1e3:.0f} ms after the last kick "
          f"(bound 1/f + 0.2 s); arm |qd| {rest:.2e} rad/s afterwards")
    assert t_stop <= 1.0 / freq + 0.2
    assert not running and rest < 1e-3


def test_stop_script_and_reupload():
    with Emulator() as emu:
        s = Stream(emu.host)
        c = rtde_control.RTDEControlInterface(emu.host)
        t0 = s.latest()["time"]
        c.stopScript()
        t_end = time.monotonic() + 2.0
        stopped = []
        while not stopped and time.monotonic() < t_end:  # this reader may lag the controller
            stopped = [p for p in s.since(t0) if p["program_state"] != 2]
            time.sleep(0.005)
        assert stopped, "the program kept playing after stopScript"
        dt = stopped[0]["time"] - t0
        t_up = time.monotonic()
        assert c.reuploadScript()
        running = False
        while not running and time.monotonic() - t_up < 2.0:  # reuploadScript does not wait
            running = c.isProgramRunning()
            time.sleep(0.005)
        t_up = time.monotonic() - t_up
        c.stopScript()
        c.disconnect()
        s.close()
    print(f"\nstopScript: program stopped {dt * 1e3:.0f} ms of controller time after the call; "
          f"reuploadScript: running again after {t_up * 1e3:.0f} ms")
    # a few ms here; t0 is this reader's newest packet, which under load can lag the controller
    # by 0.1 s, so the bound is 0.25 s of controller time
    assert dt <= 0.25 and running


def test_custom_script_function_then_the_control_script_again():
    with Emulator() as emu:
        c = rtde_control.RTDEControlInterface(emu.host)
        t0 = time.monotonic()
        ok = c.sendCustomScriptFunction("urtwin_custom", 'textmsg("custom function ran")\n'
                                        "set_standard_digital_out(5, True)\n")
        took = time.monotonic() - t0
        s = Stream(emu.host)
        t_end = time.monotonic() + 2.0  # this reader may lag the controller
        while not (do5 := int(s.latest()["digital_outputs"]) >> 5 & 1) and time.monotonic() < t_end:
            time.sleep(0.005)
        t_up = time.monotonic()
        while not c.isProgramRunning() and time.monotonic() - t_up < 2.0:
            time.sleep(0.005)
        running = c.isProgramRunning()
        c.stopScript()
        c.disconnect()
        s.close()
    print(f"\nsendCustomScriptFunction: {ok} after {took * 1e3:.0f} ms, DO5 {do5}, control script "
          f"running again: {running}")
    assert ok and do5 == 1 and running


def test_second_control_interface_replaces_the_first():
    with Emulator() as emu:
        s = Stream(emu.host)
        a = rtde_control.RTDEControlInterface(emu.host)
        a.disconnect()  # as on a real controller, a's script keeps playing
        assert s.latest()["program_state"] == 2
        t0 = time.monotonic()
        b = rtde_control.RTDEControlInterface(emu.host)  # stops that script, dashboard stop, re-uploads
        took = time.monotonic() - t0
        first = s.latest()
        target = list(first["q_actual"])
        target[5] += 0.2
        assert b.moveJ(target, 1.0, 1.0)
        _, _, rest = s.motion(first["time"])
        err = max(abs(x - y) for x, y in zip(rest["q_actual"], target))
        b.stopScript()
        b.disconnect()
        s.close()
    print(f"\nsecond RTDEControlInterface: constructor {took * 1e3:.0f} ms, its moveJ error {err:.1e} rad")
    assert took < 2.5 and err < 1e-4  # see test_constructor_is_fast_and_the_script_runs


def test_remote_control_is_checked_for_non_local_hosts():
    with Emulator("--local-control") as emu:  # a 127.0.0.N address: ur_rtde asks the dashboard
        with pytest.raises(RuntimeError) as e:
            rtde_control.RTDEControlInterface(emu.host)
    print(f"\nlocal control: {e.value}")
    assert "remote control" in str(e.value).lower()


def test_move_until_contact_against_a_wall_given_through_rtde():
    """The 'wall': another RTDE client writes external_force_torque (the world pushing back on
    the tool) once the TCP has gone 2 cm down; moveUntilContact stops on it. ur_rtde runs with
    FLAG_NO_EXT_FT, or its own recipe would hold that input (IN_USE for anyone else)."""
    from rtde_client import RtdeClient
    with Emulator() as emu:
        s = Stream(emu.host)
        C = rtde_control.RTDEControlInterface
        c = C(emu.host, 500.0, C.FLAG_UPLOAD_SCRIPT | C.FLAG_NO_EXT_FT)
        wall = RtdeClient(emu.host).connect()
        wall.negotiate_protocol_version(2)
        recipe = wall.setup_inputs(["external_force_torque"])
        z0 = s.latest()["tool_vector_actual"][2]
        done = threading.Event()

        def push():
            while not done.is_set():
                z = s.latest()["tool_vector_actual"][2]
                f = 50.0 if z < z0 - 0.02 else 0.0  # a stiff wall 2 cm below the start
                wall.send_inputs(recipe, {"external_force_torque": [0.0, 0.0, f, 0.0, 0.0, 0.0]})
                time.sleep(0.002)

        th = threading.Thread(target=push, daemon=True)
        th.start()
        t0 = time.monotonic()
        ok = c.moveUntilContact([0.0, 0.0, -0.02, 0.0, 0.0, 0.0])
        took = time.monotonic() - t0
        time.sleep(0.3)
        z = s.latest()["tool_vector_actual"][2]
        done.set()
        th.join(timeout=1)
        c.stopScript()
        c.disconnect()
        wall.close()
        s.close()
    print(f"\nmoveUntilContact: returned {ok} after {took:.2f} s; TCP went {1e3 * (z0 - z):.1f} mm "
          f"down (wall at 20 mm)")
    assert ok and took < 5.0
    assert 0.015 < z0 - z < 0.03
