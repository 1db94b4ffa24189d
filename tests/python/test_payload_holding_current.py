# SPDX-License-Identifier: Apache-2.0
"""The payload in the dynamics, end to end (core/payload.cpp, issue 10 item 1): a 3 kg payload
0.1 m along the flange's z axis must raise the shoulder's holding current, at the five poses of
tests/core/test_step.c's hold test, by Δg_shoulder(q) / (k_t τ) — Δg computed by Pinocchio from
the resolved parameters with the payload appended to link 6 — within 1 %. The payload comes in
four ways: the config (`--set payload.…`, against a run without one), a URScript program on
30002 (set_payload), URScript set_target_payload with an inertia (also read back on RTDE
`payload`, `payload_cog`, `payload_inertia`), and ur_rtde's RTDEControlInterface.setPayload
(ur_rtde's own control script, run by urtwin's VM). UR's RTDE has no payload input, so there is
no RTDE path to test.

The emulator runs with friction, noise and quantisation off (as the C hold test), so that the
held current is the gravity torque's alone; the current is read on 30003 (`i_actual`) averaged
over 0.3 s of controller time. Numbers are printed (pytest -s)."""

import os
import threading
import time

import numpy as np
import pinocchio as pin
import pytest

import built

import urtwin_ctypes as urt
from test_arm_pinocchio import build_pinocchio
from urtwin_proc import Emulator, RtReader, URTWIN

built.require(URTWIN)

POSES = [[0.0, -1.2, 1.0, -1.4, -1.5708, 0.0],
         [0.5, -0.3, 0.4, -0.8, 1.0, 0.5],
         [-0.7, -2.0, 2.2, 0.3, -0.5, 1.0],
         [1.2, -0.8, -1.0, -2.0, 0.7, -1.0],
         [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]]
MASS, COG = 3.0, [0.0, 0.0, 0.1]
INERTIA = [0.004, 0.005, 0.003, 0.0005, 0.0, -0.0004]  # a full tensor for set_target_payload
QUIET = ("friction_common.enabled=false", "sensors.noise=false", "sensors.quantise=false")
CONFIG_LOAD = (f"payload.mass={MASS}", f"payload.cog={COG}")
SHOULDER = 1
RTOL = 0.01


def overrides_args(overrides):
    return [arg for o in overrides for arg in ("--set", o)]


class Stream:
    """Every 30003 packet, read on a thread (a client that stops reading gets stale packets)."""

    def __init__(self, host):
        self.packets, self.stop = [], threading.Event()
        self.rt = RtReader(host)
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()
        t_end = time.monotonic() + 2.0
        while not self.packets and time.monotonic() < t_end:
            time.sleep(0.001)

    def _run(self):
        while not self.stop.is_set():
            self.packets.append(self.rt.read_decoded())

    def now(self):
        return self.packets[-1]["time"]

    def wait(self, seconds, wall=30.0):
        """Until `seconds` of controller time have passed (bounded in wall time)."""
        t_end, w_end = self.now() + seconds, time.monotonic() + wall
        while self.now() < t_end:
            assert time.monotonic() < w_end, "controller time does not advance"
            time.sleep(0.01)

    def settle_at(self, q, wall=60.0):
        """Until the arm rests at q (1e-3 rad, speeds below 1e-3 rad/s over 0.2 s)."""
        w_end = time.monotonic() + wall
        while True:
            last = self.packets[-1]
            if (max(abs(a - b) for a, b in zip(last["q_actual"], q)) < 1e-3 and
                    max(abs(v) for v in last["qd_actual"]) < 1e-3):
                break
            assert time.monotonic() < w_end, f"the arm did not reach {q}: {last['q_actual']}"
            time.sleep(0.02)
        self.wait(1.0)

    def mean(self, seconds=0.3):
        """Mean actual q and current over the last `seconds` of controller time."""
        self.wait(seconds)
        t0 = self.now() - seconds
        window = [p for p in list(self.packets) if p["time"] > t0]
        return (np.mean([p["q_actual"] for p in window], axis=0),
                np.mean([p["i_actual"] for p in window], axis=0))

    def close(self):
        self.stop.set()
        self.thread.join(timeout=2)
        self.rt.close()


@pytest.fixture(scope="module")
def expected():
    """Δi_shoulder(q) = (g_with(q) − g_without(q))_shoulder / (k_t τ), by Pinocchio."""
    bare = urt.resolved_model(urt.UR5_YAML, QUIET)
    loaded = urt.resolved_model(urt.UR5_YAML, QUIET + CONFIG_LOAD)
    assert loaded["payload"]["mass"] == MASS and loaded["payload"]["cog"] == COG
    m0, _ = build_pinocchio(bare)
    m1, _ = build_pinocchio(loaded)
    d0, d1 = m0.createData(), m1.createData()
    j = bare["joints"][SHOULDER]
    kt_tau = j["motor"]["kt"] * j["gear"]["ratio"]

    def delta_i(q):
        q = np.asarray(q, dtype=float)
        dg = (pin.computeGeneralizedGravity(m1, d1, q) -
              pin.computeGeneralizedGravity(m0, d0, q))[SHOULDER]
        return dg / kt_tau
    return delta_i


def movej_script(q):
    return f"movej([{', '.join(repr(x) for x in q)}], a=4.0, v=3.0)\n"


def check(path, rows, expected):
    """rows: (q, Δi measured) per pose."""
    worst = 0.0
    for p, (q, di) in enumerate(rows):
        want = expected(q)
        ratio = di / want
        worst = max(worst, abs(ratio - 1.0))
        print(f"\n{path} pose {p}: shoulder Δi = {di:+.5f} A, Pinocchio Δg/(kt τ) = {want:+.5f} A,"
              f" ratio {ratio:.5f}")
        assert abs(want) > 0.1, "the pose must load the shoulder for the check to mean anything"
    print(f"\n{path}: worst |ratio − 1| = {worst:.2e}")
    assert worst <= RTOL, f"{path}: holding-current rise off by {worst:.3%} (> 1 %)"


def runtime_rows(emu, stream, mount, unmount, move):
    """At each pose: current without payload, mount it, current with it, unmount."""
    rows = []
    for q in POSES:
        move(q)
        stream.settle_at(q)
        _, i0 = stream.mean()
        mount()
        stream.wait(1.0)
        qm, i1 = stream.mean()
        rows.append((qm, i1[SHOULDER] - i0[SHOULDER]))
        unmount()
        stream.wait(0.2)
    return rows


def script_mover(emu):
    return lambda q: emu.send_script(movej_script(q))


def test_config_payload_raises_the_holding_current(expected):
    currents = []
    for overrides in (QUIET, QUIET + CONFIG_LOAD):
        with Emulator(*overrides_args(overrides)) as emu:
            stream = Stream(emu.host)
            try:
                row = []
                for q in POSES:
                    emu.send_script(movej_script(q))
                    stream.settle_at(q)
                    row.append(stream.mean())
                currents.append(row)
            finally:
                stream.close()
    rows = [(q1, i1[SHOULDER] - i0[SHOULDER])
            for (_, i0), (q1, i1) in zip(currents[0], currents[1])]
    check("config", rows, expected)


def test_urscript_set_payload_raises_the_holding_current(expected):
    with Emulator(*overrides_args(QUIET)) as emu:
        stream = Stream(emu.host)
        try:
            rows = runtime_rows(
                emu, stream,
                lambda: emu.send_script(f"set_payload({MASS}, {COG})\n"),
                lambda: emu.send_script("set_payload(0.0, [0, 0, 0])\n"),
                script_mover(emu))
        finally:
            stream.close()
    check("URScript set_payload (30002)", rows, expected)


def test_urscript_set_target_payload_with_inertia_and_the_rtde_outputs(expected):
    from rtde_client import RtdeClient
    names = ["payload", "payload_cog", "payload_inertia"]
    with Emulator(*overrides_args(QUIET)) as emu:
        stream = Stream(emu.host)
        try:
            rows = runtime_rows(
                emu, stream,
                lambda: emu.send_script(
                    f"set_target_payload({MASS}, {COG}, {INERTIA}, 0)\n"),
                lambda: emu.send_script("set_target_payload(0.0, [0, 0, 0])\n"),
                script_mover(emu))

            # the mounted payload as RTDE reports it
            emu.send_script(f"set_target_payload({MASS}, {COG}, {INERTIA})\n")
            stream.wait(0.2)
            with RtdeClient(emu.host).connect() as c:
                c.negotiate_protocol_version(2)
                c.setup_outputs(names, frequency=10)
                c.start()
                v = c.receive(timeout=2.0).values
        finally:
            stream.close()
    print(f"\nRTDE: payload {v['payload']}, payload_cog {v['payload_cog']}, "
          f"payload_inertia {v['payload_inertia']}")
    assert v["payload"] == MASS
    assert list(v["payload_cog"]) == COG
    assert list(v["payload_inertia"]) == INERTIA
    # the inertia does not load a joint at rest: the same rise as a point mass
    check("URScript set_target_payload (30002)", rows, expected)


def test_ur_rtde_set_payload_raises_the_holding_current(expected):
    import rtde_control
    with Emulator(*overrides_args(QUIET)) as emu:
        stream = Stream(emu.host)
        c = rtde_control.RTDEControlInterface(emu.host)
        try:
            rows = runtime_rows(
                emu, stream,
                lambda: c.setPayload(MASS, COG),
                lambda: c.setPayload(0.0, [0.0, 0.0, 0.0]),
                lambda q: c.moveJ(q, 1.05, 1.4))
        finally:
            c.stopScript()
            c.disconnect()
            stream.close()
    check("ur_rtde setPayload", rows, expected)
