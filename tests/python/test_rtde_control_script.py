# SPDX-License-Identifier: Apache-2.0
"""ur_rtde's control script as it arrives, through the URScript VM: ur_rtde 1.6.5's ScriptClient
prunes the script for a controller version; RTDEControlInterface then injects the register offsets
(the value lands at the start of the next line, clients.md §2.4) and, for movePath, the waypoints
into exec_move_path(). Every form compiles as uploaded, the upper register range (offset 24) runs
its register protocol on registers 24.., and a script whose offsets were never injected is the
syntax error a controller gives. (tests/python/test_ur_rtde_control.py drives the running script
through ur_rtde itself.)"""

import json
import os
import socket
import subprocess
import time

import pytest

import urtwin_ctypes as urt
from rtde_client import RtdeClient
from urtwin_proc import Emulator, PrimaryReader

import script_client

PROBE = urt.BUILD / "tests" / "net" / "urscript" / "urscript_check_probe"

VERSIONS = [(3, 15), (5, 19), (5, 23), (10, 11)]

PATH = ("\tsignal_async_progress(0)\n"
        "\tmovej([0.1,-1.5,1e-05,-1.57,0,0],a=1.4,v=1.05,r=0)\n"
        "\tsignal_async_progress(1)\n"
        "\tmovel(p[-0.143,-0.435,0.2,-0.001,3.12,0.04],a=0.5,v=0.25,r=0.02)\n")


def unit(major, minor, off_int, off_float, path=""):
    body = script_client.ScriptClient("127.0.0.1", major, minor).getScript()
    assert body.count("# float register offset\n") == 1 and body.count("# int register offset\n") == 1
    body = body.replace("# float register offset\n", f"# float register offset\n{off_float}")
    body = body.replace("# int register offset\n", f"# int register offset\n{off_int}")
    body = body.replace("# inject move path\n", "# inject move path\n" + path)
    return "def rtde_control():\n" + body + "end\n"


def check(text):
    if not os.access(PROBE, os.X_OK):
        pytest.fail(f"{PROBE} is not built: run make build", pytrace=False)
    out = subprocess.run([str(PROBE)], input=text.encode(), capture_output=True, check=True)
    return json.loads(out.stdout)


@pytest.mark.parametrize("version", VERSIONS, ids=str)
@pytest.mark.parametrize("offsets", [(0, 0), (24, 24), (24, 0)])
@pytest.mark.parametrize("path", ["", PATH], ids=["no-path", "path"])
def test_every_form_of_the_script_compiles(version, offsets, path):
    r = check(unit(*version, *offsets, path))
    assert r["ok"], r


def test_uninjected_script_is_a_syntax_error():
    # `global reg_offset_float = # comment` then `global …`: no value, as on a controller
    body = script_client.ScriptClient("127.0.0.1", 5, 23).getScript()
    r = check("def rtde_control():\n" + body + "end\n")
    assert not r["ok"] and r["text"].startswith("syntax_error_on_line:")


def test_upper_register_range_runs_on_registers_24_and_up():
    """the script with offset 24 uploaded raw on 30003: ready on output_int_register_24 (0 stays
    untouched), stopScript (255) on input_int_register_24 ends it"""
    with Emulator(version="5.23") as emu:
        c = RtdeClient(emu.host).connect()
        c.negotiate_protocol_version(2)
        c.setup_outputs(["output_int_register_0", "output_int_register_24", "runtime_state"],
                        frequency=125)
        inputs = c.setup_inputs(["input_int_register_24"])
        c.send_inputs(inputs, {"input_int_register_24": 0})
        c.start()
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()
            with socket.create_connection((emu.host, 30003), timeout=2) as s:
                s.sendall(unit(5, 23, 24, 24).encode())
            t_end = time.monotonic() + 3.0
            v = c.receive().values
            while v["output_int_register_24"] != 1 and time.monotonic() < t_end:
                v = c.receive().values
            assert v["output_int_register_24"] == 1 and v["output_int_register_0"] == 0
            assert v["runtime_state"] == 2  # PLAYING
            c.send_inputs(inputs, {"input_int_register_24": 255})
            msgs = pr.robot_messages(1.0)
        c.close()
    texts = [m["text"] for m in msgs if m["type"] == 0]
    keys = [(m["title"], m["text"]) for m in msgs if m["type"] == 7]
    assert "Received stop script!" in texts
    assert ("PROGRAM_XXX_STOPPED", "rtde_control") in keys
    assert not [m for m in msgs if m["type"] == 10]
