# SPDX-License-Identifier: Apache-2.0
"""The controller's motor/joint encoder check (core/controller_encoders.cpp) in a running urtwin:
a base joint encoder stuck from the start (`--faults`), then a program turns the base by 0.5 rad.
The loop, closed on the stuck reading, carries the arm on until the two encoders disagree by
0.05 rad: a protective stop, UR's SAFETY_MODE message on the primary interface, the program
paused as for any stop met while running, and the controller log naming the joint. The 30003
actual_q stays the stuck reading throughout: the joint encoder is what it reports."""


import yaml

from urtwin_proc import Dashboard, Emulator, PrimaryReader, rt_now

TURN = """def turn():
  q = get_actual_joint_positions()
  q[0] = q[0] + 0.5
  movej(q, a=2.0, v=1.0)
  textmsg("arrived")
end
"""



def test_a_stuck_joint_encoder_stops_the_moving_arm_with_urs_messages(tmp_path):
    scenario = tmp_path / "stuck.yaml"
    scenario.write_text(yaml.safe_dump({"faults": [
        {"class": "encoder_stuck", "joint": 0, "component": "joint", "severity": 1.0,
         "unit": "1", "profile": {"kind": "step", "onset": 0.0}}]}, sort_keys=False))
    with Emulator("--faults", str(scenario), "--log-dir", str(tmp_path)) as emu:
        before = rt_now(emu.host)
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()
            emu.send_script(TURN, port=30001)
            msgs = pr.messages_until(5, 3.0, then=0.3)
        after = rt_now(emu.host)
        d = Dashboard(emu.host)
        state = d.ask("programState")
        assert d.ask("saveLog") == "Log saved to disk"
        d.close()
    history = (tmp_path / "log_history.txt").read_text()
    stops = [line for line in history.splitlines() if "PROTECTIVE_STOP" in line]
    print(f"\nsafety lines: {stops}\nprogram: {state}")
    assert [m["safety_mode"] for m in msgs if m["type"] == 5] == [3]
    assert not any(m["type"] == 0 and m["text"] == "arrived" for m in msgs)
    assert after["safety_mode"] == 3 and after["program_state"] == 4
    assert state.startswith("PAUSED")
    assert any("encoder disagreement of the Base joint" in line for line in stops)
    # the joint encoder reports its stuck value, not where the arm went
    assert abs(after["q_actual"][0] - before["q_actual"][0]) < 1e-9
