# SPDX-License-Identifier: Apache-2.0
"""urt_config, the config CLI: exit status, the "file:line: key: reason" messages on stderr for
bad files and overrides, and the resolved model it prints (YAML and JSON, the same tree, the
values of config/ur5.yaml in SI units plus the derived ones).

Bad files are config/ur5.yaml with one edit, so the expected line numbers follow the real file.
"""

import json
import math
import os
import re
import subprocess
from pathlib import Path

import pytest

import built
import yaml

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("URT_BUILD", ROOT / "build"))
URT_CONFIG = BUILD / "tools" / "urt_config"
UR5 = ROOT / "config" / "ur5.yaml"

built.require(URT_CONFIG)


def run(*args):
    return subprocess.run([str(URT_CONFIG), *map(str, args)], capture_output=True, text=True,
                          timeout=60)


def edit(anchor, needle, repl):
    """config/ur5.yaml with the first `needle` after `anchor` replaced; and the needle's line."""
    text = UR5.read_text()
    start = text.index(anchor) if anchor else 0
    off = text.index(needle, start)
    return text[:off] + repl + text[off + len(needle):], text.count("\n", 0, off) + 1


@pytest.fixture(scope="module")
def resolved_json():
    p = run("--json", UR5)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


@pytest.fixture(scope="module")
def config():
    return yaml.safe_load(UR5.read_text())


# ---- the good file ------------------------------------------------------------------------

def test_good_file_prints_yaml_and_exits_0():
    p = run(UR5)
    assert p.returncode == 0, p.stderr
    assert p.stderr == ""
    doc = yaml.safe_load(p.stdout)
    assert doc["name"] == "UR5"
    assert len(doc["joints"]) == 6
    # derived values are marked, with their unit
    assert re.search(r"^\s+i_max: 11\.0011\S*\s+# \[A\] derived$", p.stdout, re.M)


def test_print_flag_is_the_default():
    assert run("--print", UR5).stdout == run(UR5).stdout


def test_check_validates_without_printing_the_model():
    p = run("--check", UR5)
    assert p.returncode == 0, p.stderr
    assert p.stdout == f"{UR5}: ok\n"


def test_json_has_the_arm_layout_the_pinocchio_check_reads(resolved_json):
    arm = resolved_json["arm"]
    assert len(arm["gravity"]) == 3 and len(arm["tcp"]) == 6
    assert len(arm["links"]) == 6
    for link in arm["links"]:
        for key in ("a", "alpha", "beta", "d", "theta", "mass"):
            assert isinstance(link[key], (int, float)), key
        assert len(link["com"]) == 3
        assert len(link["inertia"]) == 6
    # Table 4 in SI: mm → m, deg → rad; Table 5 link 1 with its ×1e-4 restored
    assert arm["links"][0]["a"] == pytest.approx(0.110e-3, abs=1e-15)
    assert arm["links"][0]["alpha"] == pytest.approx(math.radians(89.905), abs=1e-15)
    assert arm["links"][4]["alpha"] == pytest.approx(math.radians(-90.013), abs=1e-15)
    assert arm["links"][1]["a"] == -0.425156
    assert arm["links"][0]["inertia"] == [67e-4, 64e-4, 67e-4, 0, 0, 0]
    assert arm["gravity"] == [0, 0, -9.81]


def test_json_joints_carry_every_block_and_the_derived_values(resolved_json):
    joints = resolved_json["joints"]
    assert [j["name"] for j in joints] == ["base", "shoulder", "elbow", "wrist1", "wrist2",
                                           "wrist3"]
    assert [j["size"] for j in joints] == ["A", "A", "A", "B", "B", "B"]
    for j in joints:
        for block in ("motor", "gear", "control", "friction", "sensors"):
            assert isinstance(j[block], dict), block
        for key in ("q_min", "q_max", "qd_max", "qdd_max", "torque_max", "q0"):
            assert isinstance(j[key], (int, float)), key
        assert j["motor"]["ke"] == j["motor"]["kt"]
        assert j["gear"]["ratio"] == pytest.approx(101.0)
        assert j["control"]["v_net"] == 48
        assert j["control"]["i_max"] == pytest.approx(
            j["torque_max"] / (j["motor"]["kt"] * 101), rel=1e-12)
        assert j["sensors"]["lsb_q"] == pytest.approx(2 * math.pi / 2**18, rel=1e-12)
        assert j["sensors"]["lsb_w"] == pytest.approx(2 * math.pi / 2**18 / 5e-5, rel=1e-12)
        assert j["sensors"]["lsb_i"] == pytest.approx(3 * j["control"]["i_max"] / 4096,
                                                       rel=1e-12)
    # model.md §1.2: i_max = [11.00, 10.91, 10.96, 2.90, 3.20, 3.10] A
    assert [round(j["control"]["i_max"], 2) for j in joints] == [11.00, 10.91, 10.96, 2.90, 3.20,
                                                                  3.10]
    sim = resolved_json["simulation"]
    assert sim == {"dt": 5e-5, "seed": 1, "drives_engaged": True, "substep_h_max": 5e-6,
                   "substep_ratio": 0.015, "refine_every": 0}
    assert resolved_json["units"]["joints[].motor.kt"] == "N m/A"
    assert "joints[].control.i_max" in resolved_json["derived"]
    assert "joints[].motor.kt" not in resolved_json["derived"]


def test_yaml_and_json_outputs_are_the_same_tree(resolved_json):
    doc = yaml.safe_load(run(UR5).stdout)
    want = {k: v for k, v in resolved_json.items() if k not in ("units", "derived")}
    assert doc == want


def test_printed_values_are_the_files_values(resolved_json, config):
    # every given value of the file reaches the model unchanged (the loader maps, never scales)
    for got, link in zip(resolved_json["arm"]["links"], config["arm"]["links"]):
        for key, value in link.items():
            assert got[key] == value, key
    for got, j in zip(resolved_json["joints"], config["joints"]):
        for key in ("name", "size", "q_min", "q_max", "qd_max", "qdd_max", "torque_max", "q0",
                    "current_offset"):
            assert got[key] == j[key], key
        for block in ("control", "motor", "friction"):
            for key, value in j[block].items():
                assert got[block][key] == value, f"{block}.{key}"
        for key, value in config["gear_sizes"][j["size"]].items():
            assert got["gear"][key] == value, f"gear.{key}"
        for key, value in config["friction_common"].items():
            assert got["friction"][key] == value, f"friction.{key}"
        for key, value in config["thermal"][j["size"]].items():
            assert got["thermal"][key] == value, f"thermal.{key}"
        assert got["thermal"]["t_amb"] == config["thermal"]["t_amb"]
    assert resolved_json["payload"] == config["payload"]


def test_config_numbers_read_as_numbers_in_yaml_1_1(config):
    # PyYAML (YAML 1.1) reads 2e5 as a string; the file must write 2.0e+5
    def walk(x, path):
        if isinstance(x, dict):
            for k, v in x.items():
                yield from walk(v, f"{path}.{k}" if path else k)
        elif isinstance(x, list):
            for i, v in enumerate(x):
                yield from walk(v, f"{path}[{i}]")
        elif isinstance(x, str) and re.match(r"^[-+.0-9]", x):
            yield path, x
    assert list(walk(config, "")) == []


def test_set_overrides_in_both_list_syntaxes():
    p = run("--json", "--set", "joints.1.motor.kt=0.2", "-s", "joints[2].motor.kt=0.3",
            "--set", "arm.gravity=[0, 0, -9.8]", UR5)
    assert p.returncode == 0, p.stderr
    doc = json.loads(p.stdout)
    assert doc["joints"][1]["motor"]["kt"] == 0.2
    assert doc["joints"][2]["motor"]["kt"] == 0.3
    assert doc["arm"]["gravity"] == [0, 0, -9.8]


# ---- errors: exit 2 and the exact message ---------------------------------------------------

BAD_FILES = [
    # (anchor, needle, replacement, "key: reason")
    ("name: shoulder", "kt: 0.1361", "kt: -0.1", "joints[1].motor.kt: must be > 0 (got -0.1)"),
    ("name: shoulder", "kt: 0.1361", "k_t: 0.1361", "joints[1].motor.k_t: unknown key"),
    ("name: shoulder", "kt: 0.1361", "kt: abc", "joints[1].motor.kt: must be a number (got 'abc')"),
    ("name: wrist1", "size: B", "size: C", "joints[3].size: must be A or B (got 'C')"),
    (None, "gravity: [0.0, 0.0, -9.81]", "gravity: [0.0, -9.81]",
     "arm.gravity: must be a list of 3 (got 2)"),
    (None, "alpha: 1.569138264005502", "alpha: 89.905",
     "arm.links[0].alpha: must be in [-pi, pi] rad (got 89.905)"),
    (None, "drives_engaged: true", "drives_engaged: yes",
     "simulation.drives_engaged: must be true or false (got 'yes')"),
    ("name: shoulder", "kt: 0.1361", "kt: 0.1361: 2", "syntax error: illegal map value"),
    ("payload:", "mass: 0.0", "mass: 6.0", "payload.mass: must be in [0, 5] (got 6.0)"),
]


@pytest.mark.parametrize("anchor,needle,repl,message", BAD_FILES,
                         ids=[b[3].split(":")[0] + "-" + str(i) for i, b in enumerate(BAD_FILES)])
def test_bad_file_exits_2_with_file_line_key_reason(tmp_path, anchor, needle, repl, message):
    text, line = edit(anchor, needle, repl)
    bad = tmp_path / "bad.yaml"
    bad.write_text(text)
    p = run(bad)
    assert p.returncode == 2
    assert p.stdout == ""
    assert p.stderr == f"{bad}:{line}: {message}\n"


def test_missing_key_is_reported_at_the_parent_maps_line(tmp_path):
    text = UR5.read_text()
    start = text.index("name: shoulder")
    motor_line = text.count("\n", 0, text.index("motor:", start)) + 1
    kt = text.index("kt: 0.1361", start)
    line_start, line_end = text.rindex("\n", 0, kt) + 1, text.index("\n", kt) + 1
    bad = tmp_path / "bad.yaml"
    bad.write_text(text[:line_start] + text[line_end:])
    p = run("--check", bad)
    assert p.returncode == 2
    assert p.stderr == f"{bad}:{motor_line}: joints[1].motor.kt: missing key\n"


def test_bad_override_exits_2_and_says_override():
    p = run("--set", "joints.1.motor.kt=-0.1", UR5)
    assert p.returncode == 2
    assert p.stderr == f"{UR5}:override: joints[1].motor.kt: must be > 0 (got -0.1)\n"


def test_malformed_override_exits_2():
    p = run("--set", "joints.1.motor.kt", UR5)
    assert p.returncode == 2
    assert p.stderr == f"{UR5}:override: joints.1.motor.kt: expected key=value\n"


def test_missing_file_exits_2(tmp_path):
    missing = tmp_path / "nope.yaml"
    p = run(missing)
    assert p.returncode == 2
    assert p.stderr == f"{missing}: cannot open: No such file or directory\n"


def test_usage_error_exits_1():
    assert run().returncode == 1
    assert run("--no-such-flag", UR5).returncode == 1
    assert run(UR5, UR5).returncode == 1
