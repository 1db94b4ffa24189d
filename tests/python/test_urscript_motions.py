# SPDX-License-Identifier: Apache-2.0
"""Blend radius, movep, movec and optimovel from a URScript program uploaded on 30002, judged on
the 30003 stream (core/motion_path.cpp): a movel corner with r passes inside the radius without
the target speed reaching 0, the last move (r > 0 too) stops at its target before the program
reports STOPPED, movec's points lie on the circle through its three points, and optimovel and
movep arrive."""

import math
import time

from urtwin_proc import Emulator, RtReader

WORK = [0.0, -1.9, 1.9, -1.57, -1.57, 0.0]


def fmt(x):
    return ", ".join(f"{v:.10f}" for v in x)


def run_program(emu, rt, text, t_max=20.0):
    """send the program, read 30003 until it has run and stopped; the packets while it ran"""
    emu.send_script(text)
    packets, started = [], False
    t_end = time.monotonic() + t_max
    while time.monotonic() < t_end:
        p = rt.read_decoded()
        packets.append(p)
        if p["program_state"] == 2:
            started = True
        elif started and p["program_state"] == 1:
            return packets
    raise AssertionError("the program did not run to its end")


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a[:3], b[:3])))


def test_blends_movep_movec_optimovel_from_a_program():
    with Emulator(version="5.21") as emu, RtReader(emu.host) as rt:
        run_program(emu, rt, f"def home():\n  movej([{fmt(WORK)}], a=3, v=2)\nend\n")
        p0 = rt.read_decoded()["tool_vector_target"]
        via = list(p0)
        via[0] += 0.15
        to = list(via)
        to[1] += 0.15
        r = 0.04
        packets = run_program(emu, rt, (
            "def corner():\n"
            f"  movel(p[{fmt(via)}], a=1.2, v=0.25, r={r})\n"
            f"  movel(p[{fmt(to)}], a=1.2, v=0.25, r=0.02)\n"
            "end\n"))
        near = [p for p in packets if dist(p["tool_vector_target"], via) < r]
        closest = min(dist(p["tool_vector_target"], via) for p in packets)
        slowest = min(math.sqrt(sum(v * v for v in p["tcp_speed_target"][:3])) for p in near)
        end = packets[-1]["tool_vector_target"]
        print(f"\nmovel corner r {r}: {len(near)} packets within r, closest {closest:.4f} m, "
              f"slowest TCP target speed there {slowest:.4f} m/s, end off {dist(end, to):.2e} m")
        assert near and 0.2 * r < closest < r
        assert slowest > 0.1
        # the last move (r 0.02, nothing after it) stopped at its target before STOPPED
        assert dist(end, to) < 1e-6
        assert max(abs(v) for v in packets[-1]["qd_target"]) == 0.0

        # movec: start, via at 60° and to at 150° on a circle of radius 0.06 in the x-y plane
        p0 = rt.read_decoded()["tool_vector_target"]
        rho = 0.06
        c = [p0[0] - rho, p0[1], p0[2]]
        mid = [c[0] + rho * math.cos(math.pi / 3), c[1] + rho * math.sin(math.pi / 3), c[2],
               0, 0, 0]
        end_c = list(p0)
        end_c[0] = c[0] + rho * math.cos(5 * math.pi / 6)
        end_c[1] = c[1] + rho * math.sin(5 * math.pi / 6)
        back = list(end_c)
        back[2] += 0.05
        packets = run_program(emu, rt, (
            "def arc():\n"
            f"  movec(p[{fmt(mid)}], p[{fmt(end_c)}], a=1.0, v=0.1, mode=1)\n"
            f"  optimovel(p[{fmt(back)}], a=0.5, v=0.2)\n"
            f"  movep(p[{fmt(end_c)}], a=1.0, v=0.1)\n"
            "end\n"))
        arc = []
        for p in packets:
            x = p["tool_vector_target"]
            if abs(x[2] - c[2]) < 1e-9:
                arc.append(abs(dist(x, c) - rho))
        end = packets[-1]["tool_vector_target"]
        print(f"movec: {len(arc)} packets in the circle's plane, off the circle {max(arc):.2e} m; "
              f"optimovel and movep back: end off {dist(end, end_c):.2e} m")
        assert len(arc) > 100
        assert max(arc) < 1e-6
        assert dist(end, end_c) < 1e-6


def test_urcls_motion_sequence_blends_through_optimovej_into_optimovel():
    """URCL's InstructionExecutorTest.execute_motion_sequence_success, as its external-control
    script runs it on 5.21 and later: movel with r into optimovej(a=0.4, v=0.7, r=0.1) into
    optimovel. Before, the arm stopped on the torque limit where the fast joint blend handed
    over to the tool move (the path speed stepped down at once to what the joints allow along
    the line; the set-point's joint accelerations jumped to 600 rad/s²); now it brakes. The
    largest set-point acceleration was then still 102.7 rad/s²: wrist 3 where the two movels'
    arc handed over to the second, which does not turn the tool (the arc turned it at a rate of
    its own, stepping to none). The arc now runs from one move's angular velocity to the other's
    (core/motion_path_geometry.inc): 39.9 rad/s², the optimovel's own braking."""
    seq = [
        "movej([-1.57, -1.57, 0, 0, 0, 0], t=5, r=0.1)",
        "movej([-1.57, -1.6, 1.6, -0.7, 0.7, 0.2], t=5, r=0.1)",
        "movel(p[-0.203, 0.263, 0.559, 0.68, -1.083, -2.076], t=2, r=0.1)",
        "movel(p[-0.203, 0.463, 0.559, 0.68, -1.083, -2.076], t=2, r=0.1)",
        "optimovej([-1.57, -1.57, 1.6, -0.5, 0.4, 0.3], a=0.4, v=0.7, r=0.1)",
        "optimovel(p[-0.203, 0.263, 0.559, 0.68, -1.083, -2.076], a=0.4, v=0.7, r=0.1)",
    ]
    with Emulator(version="5.25.1") as emu, RtReader(emu.host) as rt:
        packets = run_program(emu, rt, "def sequence():\n" + "".join(f"  {s}\n" for s in seq)
                              + "end\n", t_max=40.0)
        worst = max(max(abs(a) for a in p["qdd_target"]) for p in packets)
        stops = sum(p["safety_mode"] != 1 for p in packets)
        end = packets[-1]["tool_vector_target"]
        print(f"\nURCL's sequence: {len(packets)} packets, largest set-point acceleration "
              f"{worst:.1f} rad/s², packets not in normal safety mode {stops}, end off "
              f"{dist(end, [-0.203, 0.263, 0.559]):.2e} m")
        assert stops == 0
        assert worst < 60.0
        assert dist(end, [-0.203, 0.263, 0.559]) < 1e-5
