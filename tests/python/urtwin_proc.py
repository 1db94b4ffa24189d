# SPDX-License-Identifier: Apache-2.0
"""Start and stop a real urtwin process for end-to-end tests, and read its wire formats with
small clean-room decoders written from protocols.md (not from any client library).

Each emulator gets its own loopback address (127.0.0.N): clients such as python-urx hard-code
the UR ports, and distinct addresses let several emulators and test runs share the host."""

import itertools
import os
import signal
import socket
import struct
import subprocess
import time

BUILD = os.environ.get("URT_BUILD", os.path.join(os.path.dirname(__file__), "..", "..", "build"))
URTWIN = os.path.join(BUILD, "tools", "urtwin")
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
CONFIG = os.path.join(ROOT, "config", "ur5.yaml")



def _realtime_permitted():
    """Whether this user may run threads under SCHED_FIFO (root with CAP_SYS_NICE, or an
    RLIMIT_RTPRIO): chrt is util-linux's, present on every Debian."""
    try:
        return subprocess.run(["chrt", "-f", "1", "true"], capture_output=True,
                              timeout=5).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


# The emulators run in their real-time configuration when the machine permits it (as root here
# and in CI): a real controller runs the script and the streams in its own cycle, while urtwin's
# script and I/O threads are ordinary threads that, under SCHED_OTHER on a loaded 2-core box,
# now and then wake a tick late (an interpreted servoj loop then falls behind controller time).
# Set URT_TEST_RT=0 to test the default scheduling.
RT_ARGS = (["--rt-priority", "80"]
           if os.environ.get("URT_TEST_RT", "1") != "0" and _realtime_permitted() else [])

# a different loopback address per emulator started by this process (and per pytest worker)
_hosts = itertools.count(2 + (os.getpid() % 50) * 4)


def next_host():
    n = next(_hosts)
    return f"127.0.{(n // 250) % 250 + 1}.{n % 250 + 2}"


def wait_port(host, port, timeout=5.0):
    """Seconds until host:port accepts a connection; raises TimeoutError."""
    t0 = time.monotonic()
    while True:
        try:
            with socket.create_connection((host, port), timeout=0.2):
                return time.monotonic() - t0
        except OSError:
            if time.monotonic() - t0 > timeout:
                raise TimeoutError(f"{host}:{port} did not open within {timeout} s")
            time.sleep(0.005)


class Emulator:
    """A running urtwin. Use as a context manager; args are extra command-line options."""

    def __init__(self, *args, host=None, version="5.19", nofile=None):
        self.host = host or next_host()
        self.version = version
        self.nofile = nofile  # a descriptor limit (soft = hard) for the emulator, or None
        self.args = [URTWIN, "--config", CONFIG, "--bind", self.host, "--controller-version",
                     version, "--stats-every", "0", *RT_ARGS, *args]
        self.proc = None
        self.start_time = None

    def __enter__(self):
        self.start_time = time.monotonic()
        limit = None
        if self.nofile:
            import resource
            n = self.nofile

            def limit():
                resource.setrlimit(resource.RLIMIT_NOFILE, (n, n))
        self.proc = subprocess.Popen(self.args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     cwd=ROOT, preexec_fn=limit)
        try:
            # every port a test may dial first (the emulator opens them one after another:
            # ur_rtde dials 30004 first, and found it closed once after 30003 had opened)
            for port in (30001, 30002, 30003, 30004, 29999):
                wait_port(self.host, port)
        except TimeoutError:
            self.__exit__(None, None, None)
            raise
        self.ready_after = time.monotonic() - self.start_time
        return self

    def __exit__(self, *exc):
        died = self.proc.poll() if self.proc else None
        if died is not None:
            # the emulator must outlive every client and every input: an exit before the test
            # stops it is a failure of its own, reported with what it printed
            self.out, self.err = self.proc.communicate()
            self.returncode = died
            raise AssertionError(f"urtwin exited by itself with {died}: "
                                 f"{self.err.decode(errors='replace')[-2000:]}")
        if self.proc and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.out, self.err = self.proc.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.out, self.err = self.proc.communicate()
        self.returncode = self.proc.returncode if self.proc else None
        if exc and exc[0] is not None and self.err:
            # a failing test shows what the emulator said (captured, printed in the report)
            print(f"urtwin on {self.host} exited {self.returncode}; its stderr:\n"
                  f"{self.err.decode(errors='replace')[-3000:]}")

    @property
    def period(self):
        return 0.002 if self.version.startswith("5") else 0.008

    def alive(self):
        return self.proc.poll() is None

    def send_script(self, text, port=30002):
        with socket.create_connection((self.host, port), timeout=2) as s:
            s.sendall(text.encode() + (b"" if text.endswith("\n") else b"\n"))
            time.sleep(0.05)


def recv_exact(sock, n):
    buf = bytearray()
    while len(buf) < n:
        chunk = sock.recv(n - len(buf))
        if not chunk:
            raise ConnectionError("peer closed")
        buf += chunk
    return bytes(buf)


# ---- port 30003 (protocols.md §1.2) ----

RT_FIELDS = {  # name: (offset, count)
    "time": (4, 1), "q_target": (12, 6), "qd_target": (60, 6), "qdd_target": (108, 6),
    "i_target": (156, 6), "m_target": (204, 6), "q_actual": (252, 6), "qd_actual": (300, 6),
    "i_actual": (348, 6), "i_control": (396, 6), "tool_vector_actual": (444, 6),
    "tcp_speed_actual": (492, 6), "tcp_force": (540, 6), "tool_vector_target": (588, 6),
    "tcp_speed_target": (636, 6), "digital_inputs": (684, 1), "motor_temperatures": (692, 6),
    "controller_timer": (740, 1), "robot_mode": (756, 1), "joint_modes": (764, 6),
    "safety_mode": (812, 1), "speed_scaling": (940, 1), "v_main": (972, 1), "v_robot": (980, 1),
    "i_robot": (988, 1), "v_actual": (996, 6), "digital_outputs": (1044, 1),
    "program_state": (1052, 1), "elbow_position": (1060, 3), "elbow_velocity": (1084, 3),
    "safety_status": (1108, 1),
}


def decode_rt(packet):
    out = {"size": struct.unpack_from(">i", packet, 0)[0]}
    for name, (off, n) in RT_FIELDS.items():
        if off + 8 * n <= len(packet):
            v = struct.unpack_from(f">{n}d", packet, off)
            out[name] = v[0] if n == 1 else list(v)
    return out


class RtReader:
    """A raw 30003 client."""

    def __init__(self, host, port=30003, timeout=2.0):
        self.sock = socket.create_connection((host, port), timeout=timeout)

    def read(self):
        size = struct.unpack(">i", recv_exact(self.sock, 4))[0]
        return struct.pack(">i", size) + recv_exact(self.sock, size - 4)

    def read_decoded(self):
        return decode_rt(self.read())

    def close(self):
        self.sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def rt_now(host):
    """the newest 30003 packet: a fresh connection, so nothing stale is buffered"""
    with RtReader(host) as rt:
        return rt.read_decoded()


# ---- ports 30001/30002 (protocols.md §4) ----

class PrimaryReader:
    """A raw primary/secondary client: yields (type, body) messages."""

    def __init__(self, host, port=30001, timeout=2.0):
        self.sock = socket.create_connection((host, port), timeout=timeout)

    def read(self):
        size, kind = struct.unpack(">iB", recv_exact(self.sock, 5))
        return kind, recv_exact(self.sock, size - 5)

    def robot_messages(self, seconds):
        """Every ROBOT_MESSAGE (type 20) decoded, for `seconds` of wall time."""
        out = []
        t_end = time.monotonic() + seconds
        while time.monotonic() < t_end:
            kind, body = self.read()
            if kind == 20:
                out.append(decode_robot_message(body))
        return out

    def messages_until(self, mtype, timeout, then):
        """Robot messages until one of type mtype has come (or timeout [s] has passed), and
        those of `then` seconds more."""
        msgs = []
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end and not any(m["type"] == mtype for m in msgs):
            msgs += self.robot_messages(0.2)
        return msgs + self.robot_messages(then)

    def close(self):
        self.sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def decode_robot_message(body):
    ts, source, mtype = struct.unpack_from(">QbB", body, 0)
    rest = body[10:]
    msg = {"timestamp": ts, "source": source, "type": mtype}
    if mtype == 0:
        msg["text"] = rest.decode(errors="replace")
    elif mtype == 7:
        code, arg, tlen = struct.unpack_from(">iiB", rest, 0)
        msg.update(code=code, argument=arg, title=rest[9:9 + tlen].decode(),
                   text=rest[9 + tlen:].decode(errors="replace"))
    elif mtype == 10:
        line, col = struct.unpack_from(">II", rest, 0)
        msg.update(line=line, column=col, text=rest[8:].decode(errors="replace"))
    elif mtype == 6:
        code, arg, level, dtype, data = struct.unpack_from(">iiiII", rest, 0)
        msg.update(code=code, argument=arg, level=level, text=rest[20:].decode(errors="replace"))
    elif mtype == 5:
        code, arg, mode = struct.unpack_from(">iiB", rest, 0)
        msg.update(code=code, argument=arg, safety_mode=mode)
    elif mtype == 3:
        n = rest[0]
        msg.update(project=rest[1:1 + n].decode(), major=rest[1 + n], minor=rest[2 + n])
    return msg


# ---- port 29999 ----

class Dashboard:
    """A dashboard client: one request line, one reply line."""

    def __init__(self, host, port=29999, timeout=2.0):
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.f = self.sock.makefile("rwb")
        assert self.f.readline().startswith(b"Connected: Universal Robots Dashboard Server")

    def ask(self, line):
        self.f.write(line.encode() + b"\n")
        self.f.flush()
        return self.f.readline().decode().strip()

    def wait_mode(self, mode, timeout=2.0):
        """Poll robotmode until it reads `mode`; False after `timeout` s."""
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            if self.ask("robotmode") == f"Robotmode: {mode}":
                return True
            time.sleep(0.002)
        return False

    def close(self):
        self.f.close()
        self.sock.close()
