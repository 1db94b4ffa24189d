# SPDX-License-Identifier: Apache-2.0
"""The safety net under the URScript runtime: every function that URCL 2.14's
external_control.urscript and ur_rtde 1.6.5's control script call is either defined by the
script itself or a builtin urtwin runs. The inventory (every version branch of both, from the
probe tests/net/urscript/script_inventory_probe.c) is printed; run with -s to see it.

A name urtwin does not run yet must be listed in PENDING with the reason, and leaves it as soon
as it is a builtin (the test fails on a stale entry), so the list is always the true gap."""

import json
import os
import subprocess
from pathlib import Path

import pytest

import urtwin_ctypes as urt

PROBE = urt.BUILD / "tests" / "net" / "urscript" / "script_inventory_probe"

URCL_REL = Path("clients") / "Universal_Robots_Client_Library-2.14.0"
# ../shared next to the checkout; a worktree under /work/wt/<name> finds the main one's
URCL_SRC = Path(os.environ.get("URCL_SRC", "")) if os.environ.get("URCL_SRC") else next(
    (p / URCL_REL for p in (urt.ROOT.parent / "shared", urt.ROOT.parents[1] / "shared")
     if (p / URCL_REL).is_dir()), urt.ROOT.parent / "shared" / URCL_REL)
URCL_SCRIPT = URCL_SRC / "resources" / "external_control.urscript"

# ur_rtde prunes its script per controller version: the inventory is the union
RTDE_VERSIONS = [(3, 15), (5, 19), (5, 23), (10, 11)]

# called by a client script and not run by urtwin yet: name → why, and who brings it
PENDING = {
    # no state behind them in the controller yet
    "get_target_waypoint": "needs the active motion's target (motions)",
    # urtwin has no external force/torque sensor input
    "ft_rtde_input_enable": "no external F/T sensor input in urtwin",
    "enable_external_ft_sensor": "no external F/T sensor input in urtwin",
}


def probe(text):
    if not os.access(PROBE, os.X_OK):
        pytest.fail(f"{PROBE} is not built (make build builds it)")
    out = subprocess.run([str(PROBE)], input=text.encode(), capture_output=True, check=True)
    return json.loads(out.stdout)


def urcl_calls():
    if not URCL_SCRIPT.is_file():
        pytest.skip(f"{URCL_SCRIPT} absent (../shared): URCL's script not inventoried")
    r = probe(URCL_SCRIPT.read_text())
    assert r["lex_errors"] == 0
    return r["calls"]


def rtde_calls():
    import script_client  # ur_rtde's, pinned in tools/requirements.txt: missing is a failure
    calls = {}
    for major, minor in RTDE_VERSIONS:
        body = script_client.ScriptClient("127.0.0.1", major, minor).getScript()
        r = probe("def rtde_control():\n" + body + "end\n")
        assert r["lex_errors"] == 0
        for c in r["calls"]:
            calls.setdefault(c["name"], c)
    return list(calls.values())


def check(client, calls):
    print(f"\n{client}: {len(calls)} functions called")
    for c in sorted(calls, key=lambda c: (c["status"], c["name"])):
        note = f"  PENDING: {PENDING[c['name']]}" if c["name"] in PENDING else ""
        print(f"  {c['status']:<11} {c['name']:<40} {c['calls']:>3}× from line {c['line']}{note}")
    gaps = {c["name"]: c["status"] for c in calls if c["status"] not in ("defined", "builtin")}
    unexplained = sorted(n for n in gaps if n not in PENDING)
    stale = sorted(c["name"] for c in calls if c["name"] in PENDING and c["status"] == "builtin")
    assert not unexplained, f"{client} calls what urtwin neither runs nor lists in PENDING: {unexplained}"
    assert not stale, f"now builtins, remove them from PENDING: {stale}"


def test_urcl_external_control_script_calls_only_what_urtwin_runs():
    check("URCL 2.14 external_control.urscript", urcl_calls())


def test_ur_rtde_control_script_calls_only_what_urtwin_runs():
    check("ur_rtde 1.6.5 rtde_control.script", rtde_calls())


def test_pending_names_are_called_by_a_client():
    # an entry no client calls any more is dead weight: it would hide nothing and mislead
    names = {c["name"] for c in rtde_calls()}
    if URCL_SCRIPT.is_file():
        names |= {c["name"] for c in urcl_calls()}
    else:
        pytest.skip(f"{URCL_SCRIPT} absent (../shared): cannot check URCL's part of PENDING")
    assert sorted(set(PENDING) - names) == []
