# SPDX-License-Identifier: Apache-2.0
"""RTDE on a running urtwin, byte by byte, with the clean-room client written from UR's RTDE
guide (rtde_client.py): protocol v1 and v2, NOT_FOUND, IN_USE across connections, per-client
frequencies, malformed packages."""

import os
import socket
import struct
import time

import pytest

import built

from rtde_client import RecipeError, RtdeClient, pack_package
from urtwin_proc import Emulator, URTWIN

built.require(URTWIN)


def count_for(client, seconds):
    n, t_end = 0, time.monotonic() + seconds
    stamps = []
    while time.monotonic() < t_end:
        stamps.append(client.receive().values["timestamp"])
        n += 1
    return n, stamps


def test_v1_and_v2_handshakes_version_and_frequencies():
    with Emulator() as emu:
        with RtdeClient(emu.host) as v1:  # protocol 1: never sends V; 500 Hz, no recipe ids
            assert v1.get_controller_version()[:2] == (5, 19)
            v1.setup_outputs(["timestamp", "actual_q"])
            assert v1.start()
            n1, s1 = count_for(v1, 1.0)
        with RtdeClient(emu.host) as v2:
            assert v2.negotiate_protocol_version(2)
            v2.setup_outputs(["timestamp", "actual_q"], frequency=125)
            assert v2.start()
            n2, s2 = count_for(v2, 1.0)
            assert v2.pause()
    steps1 = {round((b - a) / 0.002) for a, b in zip(s1, s1[1:])}
    steps2 = {round((b - a) / 0.008) for a, b in zip(s2, s2[1:])}
    print(f"\nv1: {n1} packages/s (steps {steps1}); v2 at 125 Hz: {n2} packages/s (steps {steps2})")
    assert abs(n1 - 500) <= 10 and steps1 == {1}
    assert abs(n2 - 125) <= 3 and steps2 == {1}


def test_not_found_and_in_use():
    with Emulator() as emu:
        with RtdeClient(emu.host) as a, RtdeClient(emu.host) as b:
            for c in (a, b):
                assert c.negotiate_protocol_version(2)
            with pytest.raises(RecipeError) as e:
                a.setup_outputs(["timestamp", "no_such_variable"], frequency=10)
            assert e.value.types[1] == "NOT_FOUND"
            a.setup_inputs(["input_int_register_5", "speed_slider_mask"])
            with pytest.raises(RecipeError) as e:
                b.setup_inputs(["input_int_register_5"])
            assert e.value.types == ["IN_USE"]
            # the same input again on the first connection is fine (ur_rtde's overlapping recipes)
            r2 = a.setup_inputs(["input_int_register_5", "input_double_register_3"])
            assert r2.id == 2
            b.setup_inputs(["input_int_register_6"])  # another register is free


def test_malformed_packages_leave_the_session_usable():
    with Emulator() as emu:
        with RtdeClient(emu.host) as c:
            assert c.negotiate_protocol_version(2)
            c.send_raw(pack_package(ord("Z"), b"unknown type"))       # skipped
            c.send_raw(pack_package(ord("U"), b"\x09" + b"\x00" * 7))  # no such recipe
            c.send_raw(pack_package(ord("M"), b"\x05hello\x03urt\x01"))  # a text message: no reply
            assert c.get_controller_version()[:2] == (5, 19)       # still answering in order
            c.setup_outputs(["timestamp"], frequency=500)
            assert c.start()
            c.receive()
        # a size below the header closes that connection only
        s = socket.create_connection((emu.host, 30004), timeout=2)
        s.sendall(struct.pack(">HB", 1, ord("V")))
        s.settimeout(2)
        assert s.recv(100) == b""
        s.close()
        with RtdeClient(emu.host) as c:
            assert c.negotiate_protocol_version(2)


def test_inputs_sent_just_before_a_close_still_reach_the_controller():
    """A client that writes inputs and closes at once (URCL's rtde_client_example sets the slider
    back to 100 % and exits): the inputs after the period's first waited for the tick in the
    session, which the close freed, and the slider stayed at the first value of the burst."""
    with Emulator() as emu:
        with RtdeClient(emu.host) as watch:
            assert watch.negotiate_protocol_version(2)
            watch.setup_outputs(["timestamp", "target_speed_fraction"], frequency=500)
            assert watch.start()
            for final in (0.3, 0.6, 0.45):
                with RtdeClient(emu.host) as c:
                    assert c.negotiate_protocol_version(2)
                    inp = c.setup_inputs(["speed_slider_mask", "speed_slider_fraction"])
                    for value in (0.9, 0.8, final):  # one send each, microseconds apart
                        c.send_inputs(inp, {"speed_slider_mask": 1, "speed_slider_fraction": value})
                # closed: the slider must end at the burst's last value
                seen = None
                for _ in range(250):  # 0.5 s of packages
                    seen = watch.receive().values["target_speed_fraction"]
                    if abs(seen - final) < 1e-12:
                        break
                assert seen == pytest.approx(final, abs=1e-12), (final, seen)
