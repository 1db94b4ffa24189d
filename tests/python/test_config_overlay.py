# SPDX-License-Identifier: Apache-2.0
"""Overlays (--overlay FILE, urt_model_load_overlays) and `include:` in a config file
(core/config_tree.cpp), through urt_config, urt_sim and urtwin: values land in the model, in
order, before --set; every refusal reads "file:line: key: reason" with exit 2; and the unit table
(core/model_units.cpp) covers every key of config/ur5.yaml with the unit urt_config prints."""

import json
import os
import subprocess
from pathlib import Path

import pytest

import built
import yaml

import urtwin_ctypes as urt

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("URT_BUILD", ROOT / "build"))
URT_CONFIG = BUILD / "tools" / "urt_config"
URT_SIM = BUILD / "tools" / "urt_sim"
URTWIN = BUILD / "tools" / "urtwin"
UR5 = ROOT / "config" / "ur5.yaml"

built.require(URT_CONFIG)

OVERLAY = """\
overlay: {name: test, base: ur5.yaml, tool: "hand", note: "a test"}
set:
  joints.1.friction.f_c: {value: 7.2, unit: "N m", from: [no1.csv, no4_acc.csv], residual: 0.12}
  joints[4].motor.kt: 0.09
  arm.links.5.mass: {value: 0.25}
"""


def run(tool, *args):
    return subprocess.run([str(tool), *map(str, args)], capture_output=True, text=True,
                          timeout=60)


def model(*args):
    res = run(URT_CONFIG, "--json", *args)
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout)


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def refused(tool, *args):
    res = run(tool, *args)
    assert res.returncode == 2, (res.returncode, res.stdout, res.stderr)
    return res.stderr.strip().removeprefix("urtwin: ")


def test_overlay__values_land_in_the_model(tmp_path):
    ov = write(tmp_path, "o.yaml", OVERLAY)
    m = model("--overlay", ov, UR5)
    assert m["joints"][1]["friction"]["f_c"] == 7.2
    assert m["joints"][4]["motor"]["kt"] == 0.09
    assert m["arm"]["links"][5]["mass"] == 0.25
    assert m["joints"][0]["friction"]["f_c"] == 8  # untouched


def test_overlay__applied_in_order_and_before_set(tmp_path):
    a = write(tmp_path, "a.yaml", "set:\n  joints.1.friction.f_c: 5.0\n  joints.2.friction.f_c: 5.0\n")
    b = write(tmp_path, "b.yaml", "set:\n  joints.1.friction.f_c: 6.0\n")
    m = model("--overlay", a, "--overlay", b, "--set", "joints.2.friction.f_c=4.0", UR5)
    assert m["joints"][1]["friction"]["f_c"] == 6.0
    assert m["joints"][2]["friction"]["f_c"] == 4.0
    m = model("--overlay", b, "--overlay", a, UR5)
    assert m["joints"][1]["friction"]["f_c"] == 5.0


def test_overlay__through_urt_sim_and_ctypes(tmp_path):
    ov = write(tmp_path, "o.yaml", OVERLAY)
    res = run(URT_SIM, "--config", UR5, "--overlay", ov, "--print-model", "--json")
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["joints"][1]["friction"]["f_c"] == 7.2
    lib = urt.load_library()
    with urt.Model(lib, UR5, overlays=[ov]) as m:
        assert m.ptr
    with pytest.raises(RuntimeError, match="unknown key"):
        urt.Model(lib, UR5, overlays=[write(tmp_path, "x.yaml", "set:\n  joints.1.nope: 1\n")])


def test_overlay__include_in_an_overlay_is_relative_and_first(tmp_path):
    (tmp_path / "sub").mkdir()
    write(tmp_path, "sub/base.yaml", "set:\n  joints.1.friction.f_c: 5.0\n  joints.2.friction.f_c: 5.0\n")
    top = write(tmp_path, "top.yaml",
                "set:\n  joints.1.friction.f_c: 6.0\ninclude: sub/base.yaml\n")
    m = model("--overlay", top, UR5)
    assert m["joints"][1]["friction"]["f_c"] == 6.0  # the includer's own set wins
    assert m["joints"][2]["friction"]["f_c"] == 5.0


def test_include__config_on_top_of_ur5_with_an_overlay(tmp_path):
    write(tmp_path, "o.yaml", OVERLAY)
    cfg = write(tmp_path, "robot.yaml",
                f"include: [{UR5}, o.yaml]\nname: MyUR5\nsimulation: {{seed: 7}}\n")
    m = model(cfg)
    assert m["name"] == "MyUR5"
    assert m["simulation"]["seed"] == 7
    assert m["simulation"]["dt"] == 5e-05  # the rest of the map from ur5.yaml
    assert m["joints"][1]["friction"]["f_c"] == 7.2


def test_include__errors_name_the_file_the_value_came_from(tmp_path):
    cfg = write(tmp_path, "robot.yaml", f"include: {UR5}\nsimulation:\n  seed: -3\n")
    err = refused(URT_CONFIG, cfg)
    assert err.startswith(f"{cfg}:3: simulation.seed: must be an integer")
    # a value left from ur5.yaml is reported at ur5.yaml's line
    cfg = write(tmp_path, "robot2.yaml", f"include: {UR5}\nsimulation:\n  sneed: 1\n")
    assert refused(URT_CONFIG, cfg) == f"{cfg}:3: simulation.sneed: unknown key"
    cfg = write(tmp_path, "robot3.yaml", "include: nowhere.yaml\n")
    assert refused(URT_CONFIG, cfg).startswith(f"{tmp_path}/nowhere.yaml: cannot open")
    loop = write(tmp_path, "loop.yaml", "include: loop.yaml\n")
    assert "nested deeper than 16" in refused(URT_CONFIG, loop)
    ov_first = write(tmp_path, "ovfirst.yaml", "include: o2.yaml\n")
    write(tmp_path, "o2.yaml", "set:\n  joints.1.friction.f_c: 5.0\n")
    assert refused(URT_CONFIG, ov_first) == \
        f"{ov_first}:1: include: {tmp_path}/o2.yaml is an overlay: include a config before it"


@pytest.mark.parametrize("text,line,msg", [
    ("set:\n  joints.1.friction.f_cc: 7.0\n", 2, "joints[1].friction.f_cc: unknown key"),
    ("set:\n  joints.1.friction.f_c: -1.0\n", 2,
     "joints[1].friction.f_c: must be > 0 (got -1.0)"),
    ("set:\n  joints.1.motor.kt: {value: 0.1, unit: \"N m\"}\n", 2,
     "joints[1].motor.kt: unit \"N m\" does not match the key's unit \"N m/A\""),
    ("set:\n  x: 1\n  joints.9.motor.kt: 0.1\n", 3,
     "joints[9]: index out of range (list has 6 elements)"),
    ("set:\n  joints..kt: 0.1\n", 2,
     "joints..kt: malformed key (write a.b.c, list elements as a.1.b or a[1].b)"),
    ("set:\n  joints.1.motor.kt: {value: 0.1, units: \"N m/A\"}\n", 2,
     "joints[1].motor.kt.units: unknown key (an entry has value, unit, from, residual)"),
    ("set:\n  joints.1.motor.kt: {value: 0.1, residual: -2}\n", 2,
     "joints[1].motor.kt.residual: must be a finite number >= 0"),
    ("overlay: {name: x}\nsets:\n  a: 1\n", 2,
     "sets: unknown key (an overlay has overlay, include and set)"),
    ("set: [1, 2]\n", 1, "set: must be a map of key: value"),
    ("set:\n  joints.1.motor.kt: \"0.1\"\n", 2,
     "joints[1].motor.kt: must be a number, not a quoted string (got \"0.1\")"),
    ("set:\n  arm.links.0.inertia: {value: [5, 5, 5, 0, 0, 0], unit: \"kg m^2\"}\n", 2,
     "arm.links[0].inertia: moments must be <= mass * 1 m^2 (3.7 kg m^2): a value not in kg m^2, "
     "or a missing 1e-4?"),
])
def test_overlay__refusals_read_file_line_key_reason(tmp_path, text, line, msg):
    ov = write(tmp_path, "bad.yaml", text)
    for tool, args in ((URT_CONFIG, ("--overlay", ov, UR5)),
                       (URT_SIM, ("--config", UR5, "--overlay", ov, "--print-model"))):
        assert refused(tool, *args) == f"{ov}:{line}: {msg}"


def test_overlay__unit_after_its_remark_and_syntax_errors(tmp_path):
    ov = write(tmp_path, "ok.yaml",
               "set:\n  arm.links.5.inertia: {value: [1e-4, 1e-4, 1e-4, 0, 0, 0], unit: \"kg m^2\"}\n")
    assert model("--overlay", ov, UR5)["arm"]["links"][5]["inertia"][0] == 1e-4
    bad = write(tmp_path, "syntax.yaml", "set:\n  a: [1, 2\n")
    assert refused(URT_CONFIG, "--overlay", bad, UR5).startswith(f"{bad}:3: syntax error")
    assert refused(URT_CONFIG, "--overlay", tmp_path / "none.yaml", UR5).startswith(
        f"{tmp_path}/none.yaml: cannot open")


def test_overlay__urtwin_refuses_a_bad_overlay_before_serving(tmp_path):
    built.require(URTWIN)
    ov = write(tmp_path, "bad.yaml", "set:\n  joints.1.friction.f_c: 0\n")
    err = refused(URTWIN, "--config", UR5, "--overlay", ov, "--port-offset", "23456")
    assert err == f"{ov}:2: joints[1].friction.f_c: must be > 0 (got 0)"


def leaves(node, path=""):
    if isinstance(node, dict):
        for k, v in node.items():
            yield from leaves(v, f"{path}.{k}" if path else k)
    elif isinstance(node, list) and node and isinstance(node[0], dict):
        for i, v in enumerate(node):
            yield from leaves(v, f"{path}.{i}")
    else:
        yield path


def test_units__every_key_of_ur5_has_the_unit_urt_config_prints():
    lib = urt.load_library()
    printed = model(UR5)["units"]
    cfg = yaml.safe_load(UR5.read_text())
    # the file's layout → the printed one: shared sections live in each joint there
    moved = {"gear_sizes.A.": "joints[].gear.", "gear_sizes.B.": "joints[].gear.",
             "friction_common.": "joints[].friction."}
    checked = 0
    for key in leaves(cfg):
        unit = lib.urt_config_key_unit(key.encode())
        assert unit is not None, f"{key}: no unit in core/model_units.cpp"
        generic = ".".join("[]" if p.isdigit() else p for p in key.split(".")).replace(".[]", "[]")
        for a, b in moved.items():
            generic = generic.replace(a, b) if generic.startswith(a) else generic
        if generic in printed:
            assert unit.decode() == printed[generic], key
            checked += 1
    assert checked > 60
    assert lib.urt_config_key_unit(b"joints.1.friction.f_c") == b"N m"
    assert lib.urt_config_key_unit(b"joints[1].friction.f_c") == b"N m"
    assert lib.urt_config_key_unit(b"joints.1.friction.nope") is None
