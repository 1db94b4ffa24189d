# SPDX-License-Identifier: Apache-2.0
"""The I/O thread's command rings (net/server/emulator.c, port_rtde.c; core/loop.c): one per
kind of client, so that a client flooding RTDE inputs cannot cost another's dashboard commands.

A separate process sends RTDE inputs (speed slider, digital outputs) at 10 kHz for 10 s while
this one sends 100 state-changing dashboard commands (power off, power on, brake release, in
turn, one every 90 ms), each checked as answered and as applied (`robotmode` shows its mode within a bound).
The emulator's closing line gives each ring's drops: the dashboard's must be 0 and every ring is
counted. The last RTDE input pattern must be what 30003 shows at the end."""

import json
import os
import re
import subprocess
import sys
import time

import pytest

import built

from urtwin_proc import URTWIN, Dashboard, Emulator, RtReader

built.require(URTWIN)
FLOOD = os.path.join(os.path.dirname(__file__), "rtde_input_client.py")

# command, its answer, the robot mode it leads to
CYCLE = [("power off", "Powering off", "POWER_OFF"), ("power on", "Powering on", "IDLE"),
         ("brake release", "Brake releasing", "RUNNING")]


def test_rtde_input_flood_costs_the_dashboard_no_command():
    with Emulator() as emu:
        dash = Dashboard(emu.host)
        assert dash.wait_mode("RUNNING")
        flood = subprocess.Popen([sys.executable, FLOOD, emu.host, "10000", "10"],
                                 stdout=subprocess.PIPE, text=True,
                                 cwd=os.path.dirname(__file__))
        time.sleep(0.5)  # the flood is on
        answered = applied = 0
        wrong = []
        t0 = time.monotonic()
        for k in range(100):
            # spread over the flood's 10 s (one every 90 ms), not all in its first second
            time.sleep(max(0.0, t0 + 0.09 * k - time.monotonic()))
            command, answer, mode = CYCLE[k % 3]
            reply = dash.ask(command)
            answered += reply == answer
            if reply != answer:
                wrong.append((command, reply))
            applied += dash.wait_mode(mode)
        took = time.monotonic() - t0
        out, _ = flood.communicate(timeout=30)
        sent = json.loads(out)
        while dash.ask("robotmode") != "Robotmode: RUNNING":  # bounded by wait_mode's 2 s
            dash.ask("brake release")
            assert dash.wait_mode("RUNNING")
        time.sleep(0.1)
        with RtReader(emu.host) as rt:
            last = rt.read_decoded()
        dash.close()
        alive = emu.alive()
    log = emu.err.decode(errors="replace")
    rings = re.findall(r"commands dropped per ring: (.*)", log)
    assert rings, log[-2000:]
    drops = {name: int(n) for name, n in re.findall(r"([a-z_]+) (\d+)", rings[-1])}
    print(f"\nRTDE inputs: {sent['sent']} packages in {sent['seconds']:.1f} s "
          f"({sent['rate']:.0f}/s); dashboard: {answered}/100 answered, {applied}/100 applied in "
          f"{took:.1f} s; drops per ring {drops}; digital outputs at the end "
          f"{int(last['digital_outputs']) & 0xFF:#04x} (last sent {sent['last_pattern']:#04x})")
    assert alive
    assert sent["rate"] > 9000 and sent["seconds"] >= 9.9  # the flood was 10 kHz for 10 s
    assert answered == 100 and wrong == []
    assert applied == 100
    assert set(drops) >= {"primary", "rtde", "dashboard", "urscript"}
    assert drops["dashboard"] == 0
    assert int(last["digital_outputs"]) & 0xFF == sent["last_pattern"]
