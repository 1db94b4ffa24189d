# SPDX-License-Identifier: Apache-2.0
"""URScript sockets end to end: a program sent to a running urtwin dials a peer on 127.0.0.1,
talks to it in lines and big-endian int32s, and its socket closes when the program ends; a host
outside loopback is a runtime exception on the primary interface naming it (nothing is dialled)
and the emulator keeps serving; --script-allow-host is taken, and bounded."""

import socket
import struct
import subprocess

from urtwin_proc import CONFIG, URTWIN, Emulator, PrimaryReader, RtReader, recv_exact


def peer():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(1)
    s.settimeout(10)
    return s, s.getsockname()[1]


def test_program_talks_to_a_local_peer_and_its_socket_closes_at_the_end():
    srv, port = peer()
    with Emulator() as emu, srv:
        emu.send_script(
            "def talk():\n"
            f'  if not socket_open("127.0.0.1", {port}, "pc"):\n'
            '    popup("no peer")\n'
            "  end\n"
            '  socket_send_line("hello", "pc")\n'
            '  r = socket_read_binary_integer(2, "pc", 5)\n'
            '  socket_send_int(r[1] + r[2], "pc")\n'
            '  textmsg(socket_read_line("pc", 5))\n'
            "end\n")
        conn, _ = srv.accept()
        with conn:
            conn.settimeout(10)
            assert recv_exact(conn, 6) == b"hello\n"
            conn.sendall(struct.pack(">ii", 40, 2))
            assert struct.unpack(">i", recv_exact(conn, 4))[0] == 42
            conn.sendall(b"bye\r\n")
            assert conn.recv(1) == b""  # the program ended: the runner closed its socket
        assert emu.alive()


def test_non_loopback_host_is_a_runtime_exception_and_the_emulator_keeps_serving():
    with Emulator() as emu:
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()  # version message
            emu.send_script('def far():\n  socket_open("192.0.2.7", 30002)\nend\n', port=30001)
            msgs = pr.robot_messages(1.0)
        exc = [m for m in msgs if m["type"] == 10]
        print(f"\nruntime exception: {exc}")
        assert exc and '"192.0.2.7"' in exc[0]["text"] and "--script-allow-host" in exc[0]["text"]
        assert exc[0]["line"] == 2
        with RtReader(emu.host) as rt:
            assert rt.read_decoded()["program_state"] == 1  # STOPPED
        assert emu.alive()


def test_script_allow_host_is_taken_and_bounded():
    srv, port = peer()
    with Emulator("--script-allow-host", "robot.lab", "--script-allow-host", "10.0.0.9") as emu, srv:
        # loopback still works beside the allowed hosts (which are not dialled here)
        emu.send_script(f'def p():\n  socket_open("localhost", {port})\n  socket_send_string("x")\nend\n')
        conn, _ = srv.accept()
        with conn:
            conn.settimeout(10)
            assert recv_exact(conn, 1) == b"x"
    args = [URTWIN, "--config", CONFIG, "--bind", "127.0.0.1", "--port-offset", "23000"]
    for k in range(17):
        args += ["--script-allow-host", f"h{k}.lab"]
    r = subprocess.run(args, capture_output=True, timeout=30)
    assert r.returncode == 2 and b"at most 16" in r.stderr
