# SPDX-License-Identifier: Apache-2.0
"""The native rtde_control recogniser on the real scripts: ur_rtde 1.6.5's ScriptClient prunes
its control script for a controller version; RTDEControlInterface then injects the register
offsets (the value lands at the start of the next line, clients.md §2.4) and, for movePath,
the waypoints into exec_move_path(). The probe prints what urtwin learns from the unit."""

import json
import os
import subprocess

import pytest

import urtwin_ctypes as urt

script_client = pytest.importorskip("script_client")

PROBE = urt.BUILD / "tests" / "net" / "urscript" / "rtde_control_probe"

# the branches each version keeps with a body (pruning leaves `dummy_op = 1` for the others)
VERSIONS = [((3, 15), {26, 66, 67, 68, 69, 70, 71}), ((5, 19), {66, 67, 68, 69, 70, 71}),
            ((5, 23), {66}), ((10, 11), set())]

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


def probe(text):
    if not os.access(PROBE, os.X_OK):
        pytest.skip(f"{PROBE} is not built")
    out = subprocess.run([str(PROBE)], input=text.encode(), capture_output=True, check=True)
    return json.loads(out.stdout)


@pytest.mark.parametrize("version,pruned", VERSIONS, ids=lambda v: str(v))
@pytest.mark.parametrize("offsets", [(0, 0), (24, 24), (24, 0)])
def test_real_script_is_recognised_with_its_offsets(version, pruned, offsets):
    r = probe(unit(*version, *offsets))
    assert r["recognised"]
    assert (r["reg_offset_int"], r["reg_offset_float"]) == offsets
    assert r["tag"] == "RTDE Control Script Loaded (14.02.2024-12:23)"
    commands = dict(r["commands"])
    assert {1, 2, 3, 4, 6, 9, 10, 11, 24, 33, 34, 35, 45, 46, 51, 255} <= set(commands)
    assert {c for c, body in commands.items() if not body and c != 0} == pruned
    assert r["path"] == [] and r["path_bad_line"] == 0


@pytest.mark.parametrize("version", [v for v, _ in VERSIONS], ids=str)
def test_injected_path_is_read(version):
    r = probe(unit(*version, 0, 0, PATH))
    assert r["recognised"] and r["path_bad_line"] == 0
    assert [(m["kind"], m["pose"]) for m in r["path"]] == [("j", False), ("l", True)]
    assert r["path"][0]["x"] == [0.1, -1.5, 1e-05, -1.57, 0, 0]
    assert (r["path"][1]["a"], r["path"][1]["v"], r["path"][1]["r"]) == (0.5, 0.25, 0.02)


def test_uninjected_script_and_other_programs_are_interpreted():
    body = script_client.ScriptClient("127.0.0.1", 5, 23).getScript()
    assert not probe("def rtde_control():\n" + body + "end\n")["recognised"]
    assert not probe("def my_func():\n\twrite_output_integer_register(0 +0, 1)\nend\n")["recognised"]
