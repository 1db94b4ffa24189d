# SPDX-License-Identifier: Apache-2.0
"""python-urx 0.11.0 decodes urtwin's 30002 and 30003 bytes with its own parser classes.

The bytes come from build/tests/net/codec/urt_codec_dump (the fixture snapshot of
tests/net/codec/codec_fixture.h, restated below). The framer check feeds ur_rtde 1.6.5's real
control script (from the installed wheel) through the same tool."""

import os
import struct
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("URT_BUILD", ROOT / "build"))
DUMP = BUILD / "tests" / "net" / "codec" / "urt_codec_dump"

import urx.ursecmon as urx_secmon
import urx.urrtmon as urx_rtmon


def fixture_vec(k, n=6):
    return [k + 0.01 * (j + 1) for j in range(n)]


@pytest.fixture(scope="module")
def dump():
    if not os.access(DUMP, os.X_OK):
        pytest.fail(f"{DUMP} is not built: run make build", pytrace=False)

    def run(kind, version, tmp_path):
        out = tmp_path / f"{kind}-{version}.bin"
        subprocess.run([str(DUMP), kind, version, str(out)], check=True)
        return out.read_bytes()

    return run


def split_messages(data):
    """python-urx's own resynchronising splitter (only type-16 messages ≤ 2000 bytes pass)."""
    parser = urx_secmon.ParserUtils()
    packets = []
    while True:
        ans = parser.find_first_packet(data)
        if not ans:
            return packets
        packets.append(ans[0])
        data = ans[1]


@pytest.mark.parametrize("version, expect_urx_version", [("3.3", (3, 2)), ("3.0", (3, 0))])
def test_secondary_stream_is_read_by_urx_cb3(dump, tmp_path, version, expect_urx_version):
    data = dump("secondary", version, tmp_path)
    packets = split_messages(data)
    assert len(packets) == 1  # version and key messages (type 20) are skipped by urx
    assert len(packets[0]) <= 2000
    parser = urx_secmon.ParserUtils()
    d = parser.parse(packets[0])
    assert parser.version == expect_urx_version

    # RobotModeData and the "running" rule of SecondaryMonitor.run
    rm = d["RobotModeData"]
    assert rm["robotMode"] == 7
    assert rm["isRealRobotEnabled"] is True and rm["isRobotConnected"] is True
    assert rm["isPowerOnRobot"] is True
    assert rm["isEmergencyStopped"] is False and rm["isSecurityStopped"] is False
    assert rm["isProgramRunning"] is True and rm["isProgramPaused"] is False
    assert rm["speedFraction"] == pytest.approx(0.9)
    assert rm["speedScaling"] == pytest.approx(0.8)
    assert rm["timestamp"] == 12_500_000

    # JointData as urx's getj reads it
    jd = d["JointData"]
    q = [jd["q_actual%d" % i] for i in range(6)]
    assert q == fixture_vec(-1)
    assert [jd["q_target%d" % i] for i in range(6)] == fixture_vec(1)
    assert [jd["jointMode%d" % i] for i in range(6)] == [253] * 6
    assert jd["T_motor0"] == pytest.approx(30.01, abs=1e-5)

    # CartesianInfo (getl), MasterBoardData (digital I/O), ToolData
    ci = d["CartesianInfo"]
    assert [ci[k] for k in ("X", "Y", "Z", "Rx", "Ry", "Rz")] == fixture_vec(10)
    if version != "3.0":
        assert ci["tcpOffsetX"] == pytest.approx(18.01)
        assert d["ForceModeData"]["x"] == pytest.approx(12.01)
        assert d["AdditionalInfo"]["teachButtonPressed"] is False
    mb = d["MasterBoardData"]
    assert mb["digitalInputBits"] == 5
    assert mb["digitalOutputBits"] == 0x30002
    assert mb["analogOutput0"] == pytest.approx(0.25)
    assert mb["robotVoltage48V"] == pytest.approx(48.25)
    assert d["ToolData"]["toolMode"] == 253


def test_secondary_stream_e_series_parses_without_error(dump, tmp_path):
    # python-urx 0.11.0 knows no 47-byte robot-mode layout (clients.md §5.2): it falls back to
    # version (0, 0), but every sub-package must still frame cleanly
    data = dump("secondary", "5.19", tmp_path)
    packets = split_messages(data)
    assert len(packets) == 1 and len(packets[0]) <= 2000
    parser = urx_secmon.ParserUtils()
    d = parser.parse(packets[0])
    assert parser.version == (0, 0)
    assert [d["JointData"]["q_actual%d" % i] for i in range(6)] == fixture_vec(-1)


def test_version_and_key_messages_are_read_by_urx(dump, tmp_path):
    data = dump("secondary", "5.19", tmp_path)
    size = struct.unpack("!i", data[:4])[0]
    d = urx_secmon.ParserUtils().parse(data[:size])
    vm = d["VersionMessage"]
    assert vm["projectName"] == b"URControl"
    assert (vm["majorVersion"], vm["minorVersion"], vm["svnRevision"]) == (5, 19, 0)
    assert vm["source"] == -2

    rest = data[size:]
    state_size = struct.unpack("!i", rest[:4])[0]
    d = urx_secmon.ParserUtils().parse(rest[state_size:])
    km = d["keyMessage"]
    assert km["messageTitle"] == b"PROGRAM_XXX_STARTED"
    assert km["messageText"] == b"script_1"


class _Sock:
    def __init__(self, data):
        self.data = data

    def recv(self, n):
        out, self.data = self.data[:n], self.data[n:]
        return out


@pytest.mark.parametrize("version, size", [("3.0", 1044), ("3.3", 1060), ("5.3", 1108),
                                           ("5.19", 1116)])
def test_rt_packet_is_read_by_urx(dump, tmp_path, version, size):
    data = dump("rt", version, tmp_path)
    assert len(data) == size
    mon = urx_rtmon.URRTMonitor("127.0.0.1")  # opens an unconnected socket only
    mon._rtSock.close()
    mon._rtSock = _Sock(data)
    mon._URRTMonitor__recv_rt_data()
    assert list(mon.q_actual()) == fixture_vec(-1)
    assert list(mon.q_target()) == fixture_vec(1)
    assert list(mon.tcf_pose()) == fixture_vec(13)  # urx reads "tool vector target"
    assert list(mon.tcf_force()) == fixture_vec(12)
    assert float(mon._ctrlTimestamp) == 12.5


def _frame(text, max_unit=0):
    if not os.access(DUMP, os.X_OK):
        pytest.fail(f"{DUMP} is not built: run make build", pytrace=False)
    out = subprocess.run([str(DUMP), "frame", str(max_unit)], input=text, check=True,
                         capture_output=True).stdout.decode()
    return [line.split(" ", 5) for line in out.splitlines()]


def test_ur_rtde_control_script_is_one_program():
    import script_client
    body = script_client.ScriptClient("127.0.0.1", 5, 23).getScript()
    # ur_rtde injects the register offsets after the comment, at the start of the next line
    body = body.replace("# float register offset\n", "# float register offset\n0")
    body = body.replace("# int register offset\n", "# int register offset\n0")
    program = "def rtde_control():\n" + body + "end\n"
    units = _frame(program.encode())
    assert len(units) == 1, units[:5]
    kind, command, error, line, length, name = units[0]
    assert kind == "2" and name == "rtde_control" and line == "1"
    assert int(length) == len(program) - 1  # all of it but the final newline

    # the same after a controller command and before a statement, with CRLF line ends
    crlf = ("stop program\n" + program + "textmsg(\"x\")\n").replace("\n", "\r\n")
    units = _frame(crlf.encode())
    assert [u[0] for u in units] == ["1", "2", "4"]
