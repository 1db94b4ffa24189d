# SPDX-License-Identifier: Apache-2.0
"""The controller's over-current check (core/controller_overcurrent.cpp) in a running urtwin:
wrist 3's brake drags with the joint's peak torque (28 N m, `--faults`), then a program turns
wrist 3. Its drive stays at its current limit, and after URT_OVERCURRENT_TIME the joint faults:
safety mode FAULT, UR's SAFETY_MODE and C281 messages on the primary interface, the arm powered
off with wrist 3 in joint mode FAULT (252), the program ended by a runtime error (not paused, as
a protective stop would). The dashboard refuses `power on` until `restart safety`, which leaves
the arm powered off in NORMAL, from where it powers on and releases its brakes again."""

import time

import yaml

from urtwin_proc import Dashboard, Emulator, PrimaryReader, rt_now

TURN = """def turn():
  q = get_actual_joint_positions()
  q[5] = q[5] + 1.0
  movej(q, a=4.0, v=1.0)
  textmsg("arrived")
end
"""

FAULT = 9  # safety mode FAULT



def wait_for(pred, timeout=3.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = pred()
        if value:
            return value
        time.sleep(0.05)
    return pred()


def test_a_dragging_brake_faults_the_joint_and_restart_safety_recovers(tmp_path):
    scenario = tmp_path / "drag.yaml"
    scenario.write_text(yaml.safe_dump({"faults": [
        {"class": "brake_drag", "joint": 5, "severity": 28.0, "unit": "N m",
         "profile": {"kind": "step", "onset": 0.0}}]}, sort_keys=False))
    with Emulator("--faults", str(scenario), "--log-dir", str(tmp_path)) as emu:
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()
            emu.send_script(TURN, port=30001)
            msgs = pr.messages_until(6, 3.0, then=0.5)
        after = rt_now(emu.host)
        d = Dashboard(emu.host)
        try:
            state = wait_for(lambda: (s := d.ask("programState")).startswith("STOPPED") and s)
            safety = d.ask("safetymode")
            refused = d.ask("power on")
            robot_after_refusal = d.ask("robotmode")
            assert d.ask("restart safety") == "Restarting safety"
            restarted = wait_for(lambda: rt_now(emu.host)["safety_mode"] == 1)
            restarted_rt = rt_now(emu.host)
            assert d.ask("power on") == "Powering on"
            assert d.ask("brake release") == "Brake releasing"
            running = wait_for(lambda: d.ask("robotmode") == "Robotmode: RUNNING")
            assert d.ask("saveLog") == "Log saved to disk"
        finally:
            d.close()
    history = (tmp_path / "log_history.txt").read_text()
    faults = [line for line in history.splitlines() if "FAULT" in line]
    print(f"\nlog: {faults}\nprogram: {state}\nmessages: "
          f"{[(m['type'], m.get('code'), m.get('text')) for m in msgs if m['type'] in (5, 6, 10)]}")
    assert [m["safety_mode"] for m in msgs if m["type"] == 5] == [FAULT]
    codes = [m for m in msgs if m["type"] == 6]
    assert [(m["code"], m["argument"], m["level"]) for m in codes] == [(281, 0, 4)]
    assert codes[0]["text"] == "Robot State Machine: Wrist 3 joint entered the Fault State"
    assert any(m["type"] == 10 for m in msgs)  # the program's runtime error
    assert not any(m["type"] == 0 and m["text"] == "arrived" for m in msgs)
    assert after["safety_mode"] == FAULT and after["robot_mode"] == 3
    assert list(after["joint_modes"]) == [239] * 5 + [252]
    assert state.startswith("STOPPED")
    assert safety == "Safetymode: FAULT"
    assert refused == "Failed to execute: power on"
    assert robot_after_refusal == "Robotmode: POWER_OFF"
    assert restarted and restarted_rt["robot_mode"] == 3
    assert list(restarted_rt["joint_modes"]) == [239] * 6
    assert running
    assert any("over-current of the Wrist 3 joint" in line for line in faults)
