# SPDX-License-Identifier: Apache-2.0
"""The clean-room RTDE test client: its encoders against protocols.md §2.7a, and one loopback
exchange with a scripted peer that replays the example's server bytes."""

import socket
import struct
import threading

import pytest

import rtde_client as rc


def test_rtde_client__encoders_match_the_worked_example():
    rc.selftest()


def _scripted_server(listener, replies, received):
    conn, _ = listener.accept()
    with conn:
        buf = b""
        for reply in replies:
            while True:
                pk, buf = rc.split_packages(buf)
                if pk:
                    received.extend(pk)
                    break
                chunk = conn.recv(4096)
                if not chunk:
                    return
                buf += chunk
            conn.sendall(reply)


def test_rtde_client__handshake_and_data_over_loopback():
    h = bytes.fromhex
    data = rc.pack_package(rc.U_DATA_PACKAGE, b"\x01" + struct.pack(">d6d", 42.0, *range(6)))
    replies = [h("00045601"), h("001376" "00000005" "00000013" "00000000" "00127907"),
               h("00134F01") + b"DOUBLE,VECTOR6D", h("00114901") + b"UINT32,DOUBLE",
               h("00045301") + data]
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    received = []
    t = threading.Thread(target=_scripted_server, args=(listener, replies, received), daemon=True)
    t.start()
    with rc.RtdeClient("127.0.0.1", listener.getsockname()[1]) as c:
        assert c.negotiate_protocol_version(2)
        assert c.get_controller_version() == (5, 19, 0, 1210631)
        out = c.setup_outputs(["timestamp", "actual_q"], 500.0)
        assert out.id == 1 and out.types == ["DOUBLE", "VECTOR6D"]
        inp = c.setup_inputs(["speed_slider_mask", "speed_slider_fraction"])
        assert inp.id == 1
        assert c.start()
        pkg = c.receive()
        assert pkg.recipe_id == 1
        assert pkg.values["timestamp"] == 42.0
        assert pkg.values["actual_q"] == (0, 1, 2, 3, 4, 5)
    t.join(2)
    listener.close()
    assert [chr(t) for t, _ in received] == ["V", "v", "O", "I", "S"]


def test_rtde_client__not_found_raises_recipe_error():
    c = rc.RtdeClient()
    with pytest.raises(rc.RecipeError) as e:
        c._check_types(["timestamp", "actual_qdd"], b"DOUBLE,NOT_FOUND", "setup outputs")
    assert e.value.types == ["DOUBLE", "NOT_FOUND"]
    with pytest.raises(rc.RtdeError):
        c._check_types(["timestamp"], b"DOUBLE,", "setup outputs")  # trailing comma
