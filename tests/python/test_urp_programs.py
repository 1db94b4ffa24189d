# SPDX-License-Identifier: Apache-2.0
"""PolyScope programs through a running urtwin's dashboard (29999): a .urp loads, plays and
shows its name as UR does; bad .urp files get UR's load error with the reason while every port
keeps serving; a program holding the External Control node fetches its program from a fake
URCL ScriptSender (127.0.0.1, ephemeral port) with request_program and runs header and body."""

import gzip
import os
import socket
import tempfile
import threading
import time

from urtwin_proc import Emulator, PrimaryReader, RtReader


def urp(body, run_once="true", name="prog"):
    xml = (f'<URProgram name="{name}" installation="default" directory="/programs">'
           '<kinematics status="NOT_INITIALIZED" validChecksum="false"/>'
           '<children><InitVariablesNode/>'
           f'<MainProgram runOnlyOnce="{run_once}" InitVariablesNode="true"><children>{body}'
           '</children></MainProgram></children></URProgram>')
    return gzip.compress(xml.encode(), mtime=0)


class Dashboard:
    def __init__(self, host):
        self.sock = socket.create_connection((host, 29999), timeout=5)
        self.f = self.sock.makefile("rwb")
        assert self.f.readline().startswith(b"Connected: Universal Robots Dashboard Server")

    def cmd(self, line):
        self.f.write(line.encode() + b"\n")
        self.f.flush()
        return self.f.readline().decode().rstrip("\n")

    def wait_state(self, want, timeout=3.0):
        t_end = time.monotonic() + timeout
        while True:
            s = self.cmd("programState")
            if s.startswith(want) or time.monotonic() > t_end:
                return s
            time.sleep(0.02)

    def close(self):
        self.sock.close()


def test_urp_load_play_and_bad_files_keep_every_port_serving():
    with tempfile.TemporaryDirectory() as progs:
        files = {
            "wait.urp": urp('<Wait type="Sleep"><waitTime>0.05</waitTime></Wait>',
                            run_once="false", name="wait"),
            "bad_gzip.urp": b"<URProgram/>",
            "truncated.urp": urp("<Halt/>")[:20],
            "bad_xml.urp": gzip.compress(b"<URProgram><children></URProgram>"),
            "unknown_node.urp": urp('<Folder><children><Timer action="Start"/></children>'
                                    '</Folder>'),
        }
        for name, data in files.items():
            with open(os.path.join(progs, name), "wb") as f:
                f.write(data)
        with Emulator("--programs-dir", progs) as emu:
            d = Dashboard(emu.host)
            assert d.cmd("load wait.urp") == "Loading program: /programs/wait.urp"
            assert d.cmd("get loaded program") == "Loaded program: /programs/wait.urp"
            assert d.cmd("play") == "Starting program"
            assert d.wait_state("PLAYING") == "PLAYING wait.urp"
            assert d.cmd("running") == "Program running: true"

            # bad files while it plays: UR's reply plus the reason; the loaded one stays
            with RtReader(emu.host) as rt, PrimaryReader(emu.host) as primary:
                before = rt.read_decoded()["time"]
                replies = {name: d.cmd(f"load {name}") for name in files if name != "wait.urp"}
                print("\n" + "\n".join(replies.values()))
                assert replies["bad_gzip.urp"] == \
                    "Error while loading program: bad_gzip.urp: not a gzip file"
                assert replies["truncated.urp"].startswith(
                    "Error while loading program: truncated.urp: bad gzip data")
                assert replies["bad_xml.urp"].startswith(
                    "Error while loading program: bad_xml.urp: bad XML at line 1")
                assert replies["unknown_node.urp"] == ("Error while loading program: "
                                                       "unknown_node.urp: unsupported program "
                                                       "node 'Timer'")
                assert d.cmd("get loaded program") == "Loaded program: /programs/wait.urp"
                # every port still serves: 30003 streams on, 30001 sends, 30004/30002 accept
                after = rt.read_decoded()["time"]
                assert after > before
                primary.read()
                for port in (30002, 30004, 29999):
                    socket.create_connection((emu.host, port), timeout=2).close()
            assert d.wait_state("PLAYING") == "PLAYING wait.urp"
            assert d.cmd("stop") == "Stopped"
            assert d.wait_state("STOPPED") == "STOPPED wait.urp"
            d.close()


class FakeScriptSender:
    """URCL's ScriptSender as the URCap sees it: answers request_program with the program and
    keeps the connection open."""

    def __init__(self, program):
        self.program = program
        self.requests = []
        self.srv = socket.create_server(("127.0.0.1", 0))
        self.port = self.srv.getsockname()[1]
        self.srv.settimeout(10)
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.thread.start()

    def serve(self):
        try:
            conn, _ = self.srv.accept()
        except OSError:
            return
        with conn:
            conn.settimeout(5)
            self.requests.append(conn.recv(64))
            conn.sendall(self.program.encode())
            time.sleep(1.0)

    def close(self):
        self.srv.close()
        self.thread.join(timeout=5)


def test_external_control_node_fetches_and_runs_header_and_body():
    sender = FakeScriptSender("# HEADER_BEGIN\n"
                              "global from_header = 7\n"
                              "# HEADER_END\n"
                              "textmsg(\"ec body ran with \", from_header)\n"
                              "sleep(0.5)\n")
    try:
        with tempfile.TemporaryDirectory() as progs:
            with open(os.path.join(progs, "external_control.urp"), "wb") as f:
                f.write(urp('<Contributed strategyClass="com.fzi.externalcontrol.'
                            'ExternalControlNode" strategyProgramNodeType="External Control">'
                            '<dataModel/></Contributed>', name="external_control"))
            with Emulator("--programs-dir", progs, "--external-control-host",
                          f"127.0.0.1:{sender.port}") as emu:
                d = Dashboard(emu.host)
                with PrimaryReader(emu.host) as primary:
                    assert d.cmd("load external_control.urp") == \
                        "Loading program: /programs/external_control.urp"
                    assert d.cmd("play") == "Starting program"
                    assert d.wait_state("PLAYING") == "PLAYING external_control.urp"
                    texts = [m.get("text", "") for m in primary.robot_messages(1.0)]
                assert sender.requests == [b"request_program\n"]
                assert any("ec body ran with 7" in t for t in texts), texts
                assert d.wait_state("STOPPED") == "STOPPED external_control.urp"
                d.close()
    finally:
        sender.close()


def test_programs_alias_names_the_folder_as_clients_see_it():
    # URSim keeps its programs in /ursim/programs; URCL's dashboard test loads by that
    # absolute name. The folder on the host stays --programs-dir; a path outside the alias is
    # still not found, and an alias that is not an absolute path is a usage error (exit 2)
    with tempfile.TemporaryDirectory() as progs:
        with open(os.path.join(progs, "wait.urp"), "wb") as f:
            f.write(urp("<Wait type=\"Sleep\"><waitTime>1.0</waitTime></Wait>"))
        with Emulator("--programs-dir", progs, "--programs-alias", "/ursim/programs") as emu:
            d = Dashboard(emu.host)
            assert d.cmd("load /ursim/programs/wait.urp") == \
                "Loading program: /ursim/programs/wait.urp"
            assert d.cmd("load wait.urp") == "Loading program: /ursim/programs/wait.urp"
            assert d.cmd("load /programs/wait.urp") == "File not found: /programs/wait.urp"
    import subprocess
    from urtwin_proc import URTWIN
    r = subprocess.run([URTWIN, "--programs-alias", "relative/path", "--help-all"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2
    assert "absolute path" in (r.stdout + r.stderr)
