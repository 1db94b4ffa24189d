# SPDX-License-Identifier: Apache-2.0
"""RTDE outputs that used to carry stand-ins (net/rtde/rtde_outputs.def) now carry the model's
values, each judged against a value computed here independently of urtwin's code:

- actual_current_as_torque = i · k_t · N per joint, with i the same package's actual_current
  and k_t, N the resolved configuration's (urt_config --print --json);
- target_gravity = the configuration's gravity at start, then what a program's
  set_gravity(d) asks for (UR's d points away from the earth: the acceleration is −d).

And the outputs urtwin has no model for are refused at setup as NOT_FOUND, not sent as zero."""

import os
import time

import pytest

import built

from rtde_client import RecipeError, RtdeClient
from urtwin_proc import URTWIN, Emulator, RtReader

built.require(URTWIN)

# the first e-Series that has both outputs (actual_current_as_torque 5.23, target_gravity 5.24)
VERSION = "5.25"


def packages(host, names, n):
    with RtdeClient(host) as c:
        c.negotiate_protocol_version(2)
        c.setup_outputs(names, frequency=500)
        c.start()
        return [c.receive().values for _ in range(n)]


def test_actual_current_as_torque_is_current_times_kt_times_ratio(ur5_params):
    kt = [j["motor"]["kt"] for j in ur5_params["joints"]]
    ratio = [j["gear"]["ratio"] for j in ur5_params["joints"]]
    with Emulator(version=VERSION) as emu:
        # the arm under gravity: every joint carries current, the shoulder most
        emu.send_script("def m():\n  movej([0.3, -1.2, 1.0, -1.4, -1.5, 0.2], a=1.4, v=1.0)\nend")
        rows = packages(emu.host, ["timestamp", "actual_current", "actual_current_as_torque",
                                   "actual_joint_voltage"], 1500)  # 3 s, the movej included
    worst = 0.0
    for r in rows:
        for j in range(6):
            want = r["actual_current"][j] * kt[j] * ratio[j]
            got = r["actual_current_as_torque"][j]
            worst = max(worst, abs(got - want) / max(1e-9, abs(want)))
    shoulder = max(abs(r["actual_current_as_torque"][1]) for r in rows)
    print(f"\nactual_current_as_torque: {len(rows)} packages, worst relative difference from "
          f"i·k_t·N {worst:.1e}; shoulder up to {shoulder:.1f} N m")
    assert worst < 1e-12
    assert shoulder > 10.0  # a real load, not zeros that would match trivially


def test_target_gravity_follows_the_config_then_set_gravity(ur5_params):
    g0 = ur5_params["arm"]["gravity"]
    with Emulator(version=VERSION) as emu:
        before = packages(emu.host, ["timestamp", "target_gravity"], 5)
        emu.send_script("def g():\n  set_gravity([0.0, 4.9, 8.5])\nend")
        after = None
        t_end = time.monotonic() + 3.0
        while time.monotonic() < t_end:
            after = list(packages(emu.host, ["timestamp", "target_gravity"], 1)[0]["target_gravity"])
            if after != list(g0):
                break
            time.sleep(0.05)
    print(f"\ntarget_gravity: {before[0]['target_gravity']} at start (config {g0}), "
          f"{after} after set_gravity([0, 4.9, 8.5])")
    assert all(list(r["target_gravity"]) == list(g0) for r in before)
    assert after == [0.0, -4.9, -8.5]


@pytest.mark.parametrize("name", ["io_current", "actual_TCP_acceleration",
                                  "actual_robot_energy_consumed", "target_base_wrench"])
def test_outputs_without_a_model_are_not_found(name):
    with Emulator(version=VERSION) as emu, RtdeClient(emu.host) as c:
        c.negotiate_protocol_version(2)
        with pytest.raises(RecipeError) as e:
            c.setup_outputs(["timestamp", name], frequency=500)
    assert "NOT_FOUND" in e.value.types
    assert e.value.types[0] == "DOUBLE"


def test_zero_ftsensor_zeroes_the_tcp_force_reading_as_on_the_robot():
    """A 20 N push along base z (RTDE external_force_torque, what the virtual world applies)
    reads as about 20 N in actual_TCP_force; after zero_ftsensor() the same push reads 0, and
    when the push ends the reading is -20 N (the offset stays, as on a UR), the same on 30003."""
    names = ["timestamp", "actual_TCP_force"]
    with Emulator("--set", "sensors.noise=false", version=VERSION) as emu:
        with RtdeClient(emu.host) as c:
            c.negotiate_protocol_version(2)
            push = c.setup_inputs(["external_force_torque"])
            c.send_inputs(push, {"external_force_torque": [0.0, 0.0, 20.0, 0.0, 0.0, 0.0]})
            time.sleep(1.0)  # the arm settles against the push
            pushed = packages(emu.host, names, 5)[-1]["actual_TCP_force"]
            emu.send_script("def z():\n  zero_ftsensor()\nend")
            time.sleep(0.5)
            zeroed = packages(emu.host, names, 5)[-1]["actual_TCP_force"]
            c.send_inputs(push, {"external_force_torque": [0.0] * 6})
            time.sleep(1.0)
            released = packages(emu.host, names, 5)[-1]["actual_TCP_force"]
            with RtReader(emu.host) as rt:
                rt_released = rt.read_decoded()["tcp_force"]
    print(f"\nzero_ftsensor: pushed Fz {pushed[2]:.2f} N, zeroed {zeroed[2]:.3f} N, "
          f"released {released[2]:.2f} N (30003 {rt_released[2]:.2f} N)")
    assert abs(pushed[2] - 20.0) < 1.0
    assert all(abs(f) < 0.05 for f in zeroed)
    assert abs(released[2] + pushed[2]) < 0.1
    assert max(abs(a - b) for a, b in zip(released, rt_released)) < 0.05
