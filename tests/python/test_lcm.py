# SPDX-License-Identifier: Apache-2.0
"""End-to-end LCM: a real urtwin process with --lcm, judged by a Python LCM subscriber using the
types lcm-gen wrote into the build tree (build/net/lcm/python). Traffic stays on this host
(ttl=0); each emulator gets its own udpm port and channel prefix, so parallel runs never cross.
Numbers are printed (pytest -s)."""

import importlib.util
import itertools
import math
import os
import re
import sys
import threading
import time

import pytest

from rtde_client import RtdeClient
from udp_drops import URL_OPTIONS, udp_drops_now
from urtwin_proc import BUILD, Emulator, PrimaryReader, RtReader, URTWIN

import lcm  # pinned in tools/requirements.txt

LCM_TYPES = os.path.join(BUILD, "net", "lcm", "python")
if not os.path.isdir(os.path.join(LCM_TYPES, "urtwin")):  # make build generates them
    pytest.fail(f"{LCM_TYPES} has no generated LCM types: run make build", pytrace=False)


def lcm_type(name):
    """A generated LCM type, loaded from its file: the generated package is named `urtwin`
    (the .lcm files' package), which the Python package `import urtwin` shadows on sys.path."""
    path = os.path.join(LCM_TYPES, "urtwin", f"{name}.py")
    spec = importlib.util.spec_from_file_location(f"urtwin_lcm_types.{name}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return getattr(mod, name)

_runs = itertools.count()


def lcm_endpoint():
    """A udpm URL and channel prefix of this process and call."""
    k = next(_runs)
    port = 10000 + (os.getpid() * 13 + 500 + k) % 20000  # below the ephemeral range
    return f"udpm://239.255.76.67:{port}?{URL_OPTIONS}", f"URTWIN_PY{os.getpid()}_{k}"


class Listener:
    """Decodes status and drive messages on a thread; keeps them all."""

    def __init__(self, url, prefix):
        lcmt_urtwin_drive, lcmt_urtwin_status = (lcm_type("lcmt_urtwin_drive"),
                                                 lcm_type("lcmt_urtwin_status"))
        self.lc = lcm.LCM(url)
        self.status, self.drive = [], []
        self.lock = threading.Lock()

        def on_status(_ch, data):
            m = lcmt_urtwin_status.decode(data)
            with self.lock:
                self.status.append((time.monotonic(), m))

        def on_drive(_ch, data):
            m = lcmt_urtwin_drive.decode(data)
            with self.lock:
                self.drive.append(m)

        self.lc.subscribe(prefix + "_STATUS", on_status).set_queue_capacity(5000)
        self.lc.subscribe(prefix + "_DRIVE", on_drive).set_queue_capacity(10000)
        self.stop = False
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        while not self.stop:
            self.lc.handle_timeout(20)

    def last(self):
        with self.lock:
            return self.status[-1][1] if self.status else None

    def wait_tick(self, tick, timeout=2.0):
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            s = self.last()
            if s is not None and s.tick >= tick:
                return s
            time.sleep(0.0005)
        return self.last()

    def close(self):
        self.stop = True
        self.thread.join()


def command(q, qd=None, tau=None):
    lcmt_urtwin_command = lcm_type("lcmt_urtwin_command")
    c = lcmt_urtwin_command()
    c.utime = int(time.time() * 1e6)
    c.num_joints, c.joint_position = 6, list(q)
    c.num_velocities, c.joint_velocity = (6, list(qd)) if qd is not None else (0, [])
    c.num_torques, c.joint_torque = (6, list(tau)) if tau is not None else (0, [])
    return c.encode()


def test_lcm_status_every_tick_equals_30003_and_drive_at_its_rate():
    """10 s of status at the controller rate, each message equal to the 30003 packet of the
    same controller time; drive messages at their own 1 kHz."""
    url, prefix = lcm_endpoint()
    rt_packets = {}
    with Emulator("--lcm", "--lcm-url", url, "--lcm-prefix", prefix, "--drive-rate", "1000") as emu:
        ls = Listener(url, prefix)
        drops0 = udp_drops_now()
        stop = threading.Event()

        def read_rt():
            with RtReader(emu.host) as rt:
                while not stop.is_set():
                    p = rt.read_decoded()
                    rt_packets[round(p["time"] / 0.002)] = p

        reader = threading.Thread(target=read_rt, daemon=True)
        reader.start()
        time.sleep(10.6)
        stop.set()
        reader.join(timeout=2)
        ls.close()
    dropped = udp_drops_now() - drops0
    with ls.lock:
        msgs = [m for t, m in ls.status]
        drive = list(ls.drive)
    t0 = ls.status[0][0]
    window = [m for t, m in ls.status if t0 + 0.3 <= t < t0 + 10.3]
    ticks = [m.tick for m in msgs]
    gaps = sum(1 for a, b in zip(ticks, ticks[1:]) if b != a + 1)
    missing = sum(b - a - 1 for a, b in zip(ticks, ticks[1:]) if b > a + 1)
    span = window[-1].time - window[0].time
    # the same tick on both interfaces carries the same numbers, bit for bit
    both = [m for m in msgs if m.tick in rt_packets]
    fields = [("q_actual", "q_actual"), ("q_target", "q_target"), ("qd_actual", "qd_actual"),
              ("current_actual", "i_actual"), ("current_control", "i_control"),
              ("tcp_pose_actual", "tool_vector_actual"), ("tcp_force", "tcp_force"),
              ("voltage_actual", "v_actual"), ("temperature", "motor_temperatures")]
    differ = sum(1 for m in both for a, b in fields
                 if list(getattr(m, a)) != list(rt_packets[m.tick][b]))
    print(f"\nLCM status: {len(window)} messages in 10 s of wall time (controller time "
          f"{span:.3f} s), {gaps} gaps, {msgs[-1].ticks_lost} ticks lost; {len(both)} ticks also "
          f"read on 30003, {differ} field differences; drive: {len(drive)} messages over "
          f"{drive[-1].time - drive[0].time:.3f} s of physics time; the kernel dropped "
          f"{dropped} datagrams")
    # every tick once and in order, but for what loopback UDP dropped (udp_drops.py)
    assert all(b > a for a, b in zip(ticks, ticks[1:]))
    assert missing <= dropped and (gaps == 0 or dropped > 0)
    assert msgs[-1].ticks_lost == 0
    assert all(m.utime == round(m.tick * 2000) and m.period == 0.002 for m in msgs)
    # 500 Hz of wall time: with no missed period the loop stays within its catch-up limit of 50
    # periods of its clock (core/include/urt/loop.h), +1 for the window's edges and +2 for the
    # listener's receive times
    missed = window[-1].missed_periods - window[0].missed_periods
    if missed == 0:
        assert -53 - dropped <= len(window) - 5000 <= 53
    else:
        print(f"the loop missed {missed} periods on this machine: the rate is not checked")
    assert len(both) > 4500 and differ == 0
    seqs = [d.seq for d in drive]
    assert all(b > a for a, b in zip(seqs, seqs[1:]))
    span_d = drive[-1].time - drive[0].time
    rate = (len(drive) - 1) / span_d
    assert abs(rate - 1000) <= 10 or (rate < 1000 and 1000 * span_d - len(drive) <= dropped + 10)


def test_lcm_command_stream_moves_the_arm():
    url, prefix = lcm_endpoint()
    with Emulator("--lcm", "--lcm-url", url, "--lcm-prefix", prefix):
        ls = Listener(url, prefix)
        s0 = ls.wait_tick(50)
        assert s0 is not None and s0.robot_mode == 7 and s0.safety_mode == 1
        pub = lcm.LCM(url)
        T, dq = 0.5, 0.05
        for k in range(1, 501):  # a 0.5 s quintic ramp of joint 0 streamed at 500 Hz, then hold
            t = k * 0.002
            u = min(t / T, 1.0)
            q = list(s0.q_target)
            qd = [0.0] * 6
            q[0] += dq * u ** 3 * (10 - 15 * u + 6 * u * u)
            qd[0] = dq * 30 * u * u * (1 - u) ** 2 / T if t < T else 0.0
            pub.publish(prefix + "_COMMAND", command(q, qd))
            time.sleep(0.002)
        time.sleep(0.2)
        s1 = ls.last()
        ls.close()
    print(f"\nLCM command: joint 0 {s0.q_actual[0]:.5f} -> {s1.q_actual[0]:.5f} rad "
          f"(target {s1.q_target[0]:.5f}), motion {s1.motion}, safety {s1.safety_mode}")
    assert s1.safety_mode == 1 and s1.motion == 7
    assert abs(s1.q_target[0] - (s0.q_target[0] + dq)) < 1e-9
    assert abs(s1.q_actual[0] - (s0.q_actual[0] + dq)) < 0.005


def test_lcm_position_jump_is_a_protective_stop_with_urs_message():
    """A command 0.5 rad away from the set-point (250 rad/s over one period) stops the arm where
    it is: safety mode PROTECTIVE_STOP on LCM, the SAFETY_MODE and ERROR_CODE C204A0 messages on
    30001, and neither the set-point nor the arm moves; later commands are refused until unlock."""
    url, prefix = lcm_endpoint()
    with Emulator("--lcm", "--lcm-url", url, "--lcm-prefix", prefix) as emu:
        ls = Listener(url, prefix)
        s0 = ls.wait_tick(50)
        assert s0 is not None and s0.safety_mode == 1
        primary = PrimaryReader(emu.host)
        messages = []
        reader = threading.Thread(target=lambda: messages.extend(primary.robot_messages(1.5)))
        reader.start()
        time.sleep(0.2)
        pub = lcm.LCM(url)
        q = list(s0.q_target)
        q[1] += 0.5
        pub.publish(prefix + "_COMMAND", command(q))
        time.sleep(0.5)
        # after the stop, a command is refused: the arm stays
        pub.publish(prefix + "_COMMAND", command(q))
        time.sleep(0.3)
        history = [m for _, m in ls.status]
        s1 = ls.last()
        ls.close()
        reader.join()
        primary.close()
    after = [m for m in history if m.tick > s0.tick]
    jump_q = max(abs(m.q_actual[j] - s0.q_actual[j]) for m in after for j in range(6))
    jump_target = max(abs(m.q_target[j] - s0.q_target[j]) for m in after for j in range(6))
    errors = [m for m in messages if m["type"] == 6]
    modes = [m["safety_mode"] for m in messages if m["type"] == 5]
    print(f"\nLCM jump of 0.5 rad: safety {s1.safety_mode}, largest |q - q0| "
          f"{jump_q:.2e} rad, |q_target - q_target0| {jump_target:.2e} rad; 30001: "
          f"{[(m['code'], m['argument'], m['level'], m['text']) for m in errors]}, modes {modes}")
    assert s1.safety_mode == 3  # PROTECTIVE_STOP
    assert modes == [3]
    assert [(m["code"], m["argument"], m["text"]) for m in errors] == [
        (204, 0, "Protective Stop: Invalid setpoints: Position jump")]
    # neither the set-point nor the arm took the step: the stop holds where the arm stood (the
    # set-point moves by the arm's tracking error, micro-radians)
    assert jump_target < 1e-3
    assert jump_q < 1e-3


def test_lcm_lockstep_one_tick_per_command():
    url, prefix = lcm_endpoint()
    with Emulator("--lcm", "--lcm-url", url, "--lcm-prefix", prefix, "--pacing", "lockstep"):
        ls = Listener(url, prefix)
        s = ls.wait_tick(1)
        assert s is not None and s.tick == 1
        pub = lcm.LCM(url)
        t0 = time.monotonic()
        for k in range(1, 201):  # Drake's client loop: a command per status received
            pub.publish(prefix + "_COMMAND", command(s.q_target))
            s = ls.wait_tick(k + 1)
            assert s.tick == k + 1
        dt = time.monotonic() - t0
        pub.publish(prefix + "_COMMAND", command([math.nan] * 6))  # refused: no tick
        time.sleep(0.2)
        last = ls.last()
        ls.close()
    print(f"\nLCM lockstep: 200 command/status round trips in {dt:.3f} s "
          f"({dt / 200 * 1e3:.2f} ms each)")
    assert last.tick == 201


def io_message(digital_mask=0, digital_levels=0, analog_mask=0, analog=(0.0, 0.0, 0.0, 0.0)):
    lcmt_urtwin_io = lcm_type("lcmt_urtwin_io")
    m = lcmt_urtwin_io()
    m.utime = int(time.monotonic() * 1e6)
    m.digital_mask, m.digital_levels, m.analog_mask = digital_mask, digital_levels, analog_mask
    m.analog = list(analog)
    return m.encode()


def test_lcm_io_sets_inputs_and_bad_ones_are_counted_not_applied():
    url, prefix = lcm_endpoint()
    with Emulator("--lcm", "--lcm-url", url, "--lcm-prefix", prefix) as emu:
        ls = Listener(url, prefix)
        assert ls.wait_tick(20) is not None
        pub = lcm.LCM(url)
        with RtReader(emu.host) as rt:
            rt.read_decoded()
            # bad: levels outside the mask, a pin past 17, a NaN, a value above 10 V, garbage
            pub.publish(prefix + "_IO", io_message(0b1, 0b11))
            pub.publish(prefix + "_IO", io_message(1 << 18, 0))
            pub.publish(prefix + "_IO", io_message(0, 0, 0b1, (math.nan, 0, 0, 0)))
            pub.publish(prefix + "_IO", io_message(0, 0, 0b10, (0, 10.5, 0, 0)))
            pub.publish(prefix + "_IO", b"\x00" * 12)
            time.sleep(0.1)
            bad_seen = rt.read_decoded()["digital_inputs"]
            # good: standard 5 and tool 0 high, standard analog 1 at 2.5 V
            # (the 30003 reader has a backlog: judge by controller time, against the newest
            # tick the status listener had seen when the message went out)
            tick_sent = ls.last().tick
            pub.publish(prefix + "_IO", io_message((1 << 5) | (1 << 16), (1 << 5) | (1 << 16),
                                                   0b10, (0.0, 2.5, 0.0, 0.0)))
            for _ in range(2000):
                p = rt.read_decoded()
                if int(p["digital_inputs"]) == (1 << 5) | (1 << 16):
                    break
            ticks = round(p["time"] / 0.002) - tick_sent
        with RtdeClient(emu.host).connect() as c:
            c.negotiate_protocol_version(2)
            c.setup_outputs(["actual_digital_input_bits", "standard_analog_input1"], frequency=125)
            c.start()
            v = c.receive(timeout=2).values
        ls.close()
    log = emu.err.decode(errors="replace")
    stats = re.search(r"inputs received (\d+) accepted (\d+) rejected (\d+) dropped (\d+)", log)
    print(f"\nLCM io: shown on 30003 {ticks} ticks after the status tick seen at sending; RTDE {v}; "
          f"{stats.group(0) if stats else log[-500:]}")
    assert bad_seen == 0
    assert int(p["digital_inputs"]) == (1 << 5) | (1 << 16)
    # Never before it was sent. How many ticks later is the scheduling of three processes on a
    # shared machine (CI saw 4 under load); that the controller applies a command in the period
    # that drains it is proven without a clock in tests/core/test_controller_modes.c
    # (test_set_inputs__...). The upper bound only catches inputs applied by something else.
    assert 1 <= ticks <= 250
    assert v == {"actual_digital_input_bits": (1 << 5) | (1 << 16), "standard_analog_input1": 2.5}
    assert stats and [int(x) for x in stats.groups()] == [6, 1, 5, 0]


def fault_message(fault_class, joint=0, severity=0.0, profile="step", onset=0.0, inject=1,
                  component=0, ramp=0.0, **kw):
    lcmt_urtwin_fault = lcm_type("lcmt_urtwin_fault")
    m = lcmt_urtwin_fault()
    m.utime = int(time.monotonic() * 1e6)
    m.inject, m.fault_class, m.joint, m.component = inject, fault_class, joint, component
    m.severity, m.profile, m.onset, m.ramp = severity, profile, onset, ramp
    for k, v in kw.items():
        setattr(m, k, v)
    return m.encode()


def test_lcm_fault_truth_matches_the_scenario_and_live_faults_come_and_go(tmp_path):
    # a scenario fault ramping in (demagnetisation of the shoulder, 0.2 over 0.5 s from 0.3 s),
    # then a live backlash on the elbow injected on URTWIN_FAULT and cleared again, and bad
    # messages that are counted and refused while the emulator runs on
    onset, ramp, sev = 0.3, 0.5, 0.2
    scenario = tmp_path / "faults.yaml"
    scenario.write_text("faults:\n  - class: demagnetisation\n    joint: 1\n    severity: 0.2\n"
                        "    unit: \"1\"\n    profile: {kind: linear, onset: 0.3, ramp: 0.5}\n")
    lcmt_urtwin_fault_truth = lcm_type("lcmt_urtwin_fault_truth")
    url, prefix = lcm_endpoint()
    period = 0.002
    with Emulator("--lcm", "--lcm-url", url, "--lcm-prefix", prefix, "--faults",
                  str(scenario)) as emu:
        ls = Listener(url, prefix)
        truth, lock = [], threading.Lock()
        tl = lcm.LCM(url)

        def on_truth(_ch, data):
            with lock:
                truth.append(lcmt_urtwin_fault_truth.decode(data))

        tl.subscribe(prefix + "_FAULT_TRUTH", on_truth).set_queue_capacity(5000)
        stop = threading.Event()

        def spin():
            while not stop.is_set():
                tl.handle_timeout(20)

        th = threading.Thread(target=spin, daemon=True)
        th.start()
        assert ls.wait_tick(int(0.9 / period), timeout=10) is not None
        pub = lcm.LCM(url)
        # bad: an unknown class, a severity beyond the class's range, an unknown profile,
        # a bearing without its geometry, garbage
        pub.publish(prefix + "_FAULT", fault_message("flux_capacitor", 1, 0.1))
        pub.publish(prefix + "_FAULT", fault_message("demagnetisation", 1, 0.5))
        pub.publish(prefix + "_FAULT", fault_message("backlash", 2, 1e-3, profile="sawtooth"))
        pub.publish(prefix + "_FAULT", fault_message("wg_bearing", 4, 0.01))
        pub.publish(prefix + "_FAULT", b"\x01" * 40)
        tick_sent = ls.last().tick
        pub.publish(prefix + "_FAULT", fault_message("backlash", 2, 1e-3))
        ls.wait_tick(tick_sent + 150, timeout=10)
        tick_clear = ls.last().tick
        pub.publish(prefix + "_FAULT", fault_message("backlash", 2, inject=0, component=-1))
        ls.wait_tick(tick_clear + 150, timeout=10)
        stop.set()
        th.join()
        ls.close()
    log = emu.err.decode(errors="replace")
    stats = re.search(r"faults received (\d+) accepted (\d+) rejected (\d+) dropped (\d+), "
                      r"fault truth (\d+)", log)
    print(f"\nLCM faults: {len(truth)} truth messages; {stats.group(0) if stats else log[-500:]}")
    assert stats and [int(x) for x in stats.groups()[:4]] == [7, 2, 5, 0]
    assert truth and all(t.num_faults >= 1 for t in truth)

    # the scenario's fault: onset within one period, severity on its profile within 1e-9
    first_on = next(t for t in truth if t.active[0])
    print(f"scenario onset {first_on.onset[0]:.6f} s, first active tick at {first_on.utime} us")
    assert truth[0].fault_class[0] == "demagnetisation" and truth[0].joint[0] == 1
    assert abs(first_on.onset[0] - onset) <= period
    assert onset <= first_on.utime * 1e-6 <= onset + period
    worst = 0.0
    for t in truth:
        want = sev * min(1.0, (t.sim_time - onset) / ramp) if t.sim_time >= onset else 0.0
        worst = max(worst, abs(t.severity[0] - want))
    print(f"scenario severity: worst |s - s(t)| {worst:.2e} over {len(truth)} ticks")
    assert worst <= 1e-9

    # the live fault: there from the tick after it was sent, with its severity, gone when
    # cleared; the scenario fault keeps its onset through both
    live = [t for t in truth if t.num_faults == 2]
    assert live and all(t.fault_class[1] == "backlash" and t.joint[1] == 2 for t in live)
    first = live[0]
    print(f"live backlash seen from tick {first.tick} (sent at status tick {tick_sent}), onset "
          f"{first.onset[1]:.6f} s at tick time {first.utime * 1e-6:.6f} s")
    assert first.tick >= tick_sent
    assert abs(first.onset[1] - first.utime * 1e-6) <= period
    assert all(abs(t.severity[1] - 1e-3) <= 1e-9 for t in live if t.active[1])
    after = [t for t in truth if t.tick > live[-1].tick]
    assert after and all(t.num_faults == 1 for t in after)
    assert all(t.onset[0] == first_on.onset[0] for t in truth if t.tick >= first_on.tick)
    assert truth[-1].faults_applied == 2 and truth[-1].faults_refused == 0
