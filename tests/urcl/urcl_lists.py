# SPDX-License-Identifier: Apache-2.0
"""tests/urcl/urcl_lists.py — what run_urcl.py runs against urtwin and what it expects: the
controller versions, URCL's integration binaries and examples (their order, arguments and
timeouts), our own programs on URCL's API, and the readers of exclusions.txt and
expected_pass.txt."""

import fnmatch
import os

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
HERE = os.path.dirname(os.path.abspath(__file__))
URCL_DIR = os.path.join("shared", "clients", "Universal_Robots_Client_Library-2.14.0")


def default_src():
    """../shared beside the checkout (/work/main), or beside its parent (a worktree in
    /work/wt/<name>)."""
    for up in ("..", os.path.join("..", "..")):
        path = os.path.normpath(os.path.join(ROOT, up, URCL_DIR))
        if os.path.isdir(path):
            return path
    return os.path.normpath(os.path.join(ROOT, "..", URCL_DIR))


ROBOT_IP = "127.0.0.2"
LOCK = "/tmp/urcl.lock"

# controller version name -> (urtwin --controller-version, URCL programs folder)
VERSIONS = {"e-series": ("5.19", "e-series"), "cb3": ("3.15", "cb3")}

# integration binaries (tests/CMakeLists.txt), their extra arguments and per-test timeout [s]
BINARIES = [
    ("rtde_tests", [], 60),
    ("dashboard_client_g5_tests", [], 60),
    ("primary_client_test_headless", [], 60),
    ("ur_driver_tests_headless", ["--headless", "true"], 60),
    ("ur_driver_tests_urcap", ["--headless", "false"], 60),
    ("external_control_program_tests_headless", ["--headless", "true"], 60),
    ("external_control_program_tests_urcap", ["--headless", "false"], 60),
    ("spline_tests_headless", ["--headless", "true"], 120),
    ("spline_tests_urcap", ["--headless", "false"], 120),
    ("instruction_executor_test_headless", ["--headless", "true"], 60),
    ("instruction_executor_test_urcap", ["--headless", "false"], 60),
    ("trajectory_streaming_tests_headless", ["--headless", "true"], 60),
    ("ur_driver_deprecated_constructor_test", [], 60),
]

# examples (external_control.md §4.2), as URCL's CI runs them (run_examples.sh ROBOT 1): every
# binary of build/examples in the shell's glob order (alphabetical: example_order()), each with
# the arguments EXAMPLE_ARGS ("1": the seconds to run, for those that read one), one urtwin for
# all. The order matters: the examples leave the arm and the speed slider where they end.
# rtde_client_example sweeps the slider and its final sendSpeedSlider(1) races URCL's
# writer-thread stop and is not sent, so the examples after it run at the slider it left (about
# 0.5), on URSim in URCL's CI as here; spline_example's first point moves wrist 3 to about 0
# within 1 s from wherever the example before it left the arm (send_script's movej, in this
# order). Timeouts [s] allow that slider.
EXAMPLE_ARGS = ["1"]
EXAMPLE_TIMEOUTS = {
    "dashboard_example": 90,
    "direct_torque_control_example": 45,
    "driver_example": 90,
    "external_fts_through_rtde": 45,
    "force_mode_example": 45,
    "freedrive_example": 45,
    "instruction_executor": 180,
    "primary_pipeline_calibration_example": 30,
    "primary_pipeline_example": 30,
    "rtde_client_example": 30,
    "script_command_interface_example": 60,
    "script_sender_example": 30,  # no robot involved: a server on 50002 for 1 s
    "send_script": 90,
    "spline_example": 300,
    "tool_contact_example": 90,
    "trajectory_point_interface_example": 180,
    "trajectory_streaming_example": 120,
}


def example_order():
    """(name, timeout) in run_examples.sh's order: its `for file in build/examples/*` glob sorts
    the names; these 17 sort the same in the C and en_US locales (checked in session 13)."""
    return sorted(EXAMPLE_TIMEOUTS.items())

# our own programs on URCL's public API (tests/urcl/*.cpp, built by `make urcl` into
# build/urcl/ours/): arguments after the robot address, timeout [s], the versions they run on
OURS = [
    # the UR ROS 2 driver's calls (external_control.md §5.1): e-Series, 500 Hz; 30 s of servoj.
    # Its control loop runs at SCHED_FIFO 50 where permitted, as ros2_control's does on a real
    # robot: a 10 ms receive timeout ends the program if the client is descheduled that long
    # (the program then starts the servo phase again, at most 4 times: hence the bound)
    ("ros2_driver_pattern", ["resources/external_control.urscript", "30"], 200, ("e-series",)),
]

PORTS = (30001, 30002, 30003, 30004, 29999)


# ---------------------------------------------------------------------------------------------
# lists


def read_patterns(path):
    """exclusions.txt: `<kind> <pattern> <reason…>` per line, # comments. kind is `exclude`
    (never run), `norobot` (runs with urtwin stopped: it serves the robot's ports itself),
    `isolate` (runs in a process of its own, as ctest runs every URCL test: it depends on what an
    earlier test of the same process did), `known` (runs; when it fails, it is listed with this
    cause outside urtwin) or `watch` (its pattern names the version, `cb3/examples/…`: it runs in
    the gated run too and is reported with its record, but does not gate: it failed where it
    was gated, for a cause not yet found)."""
    out = []
    if not os.path.exists(path):
        return out
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            kind, pattern, reason = (line.split(None, 2) + ["", ""])[:3]
            if kind not in ("exclude", "norobot", "isolate", "known", "watch"):
                raise SystemExit(f"{path}: unknown kind {kind!r} in: {line}")
            out.append((kind, pattern, reason))
    return out


def match(patterns, test_id, kind):
    for k, pattern, reason in patterns:
        if k == kind and fnmatch.fnmatchcase(test_id, pattern):
            return reason
    return None


def read_expected(path):
    if not os.path.exists(path):
        return set()
    with open(path) as f:
        return {l.strip() for l in f if l.strip() and not l.startswith("#")}
