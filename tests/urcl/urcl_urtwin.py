# SPDX-License-Identifier: Apache-2.0
"""tests/urcl/urcl_urtwin.py — the urtwin that URCL's tests and examples run against: its
network (loopback, ports), its process (started, watched, restarted, stopped) and what it
tells about a failure (controller log, dashboard state)."""

import fcntl
import os
import re
import signal
import socket
import struct
import subprocess
import time

from urcl_lists import PORTS, ROBOT_IP, ROOT

def loopback_up():
    """Bring lo up in a fresh network namespace (SIOCSIFFLAGS; no iproute2 needed)."""
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        IFF_UP, IFF_LOOPBACK, IFF_RUNNING = 0x1, 0x8, 0x40
        ifr = struct.pack("16sH14s", b"lo", IFF_UP | IFF_LOOPBACK | IFF_RUNNING, b"")
        fcntl.ioctl(s, 0x8914, ifr)
    finally:
        s.close()


def wait_port(host, port, timeout):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        try:
            with socket.create_connection((host, port), timeout=0.2):
                return True
        except OSError:
            time.sleep(0.02)
    return False


def realtime_permitted():
    try:
        return subprocess.run(["chrt", "-f", "1", "true"], capture_output=True,
                              timeout=5).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


class Urtwin:
    def __init__(self, urtwin, version, programs, log_path):
        self.args = [urtwin, "--config", os.path.join(ROOT, "config", "ur5.yaml"),
                     "--bind", ROBOT_IP, "--controller-version", version,
                     "--programs-dir", programs, "--stats-every", "0",
                     # URSim keeps the programs in /ursim/programs, and URCL's tests, written
                     # against it, load by that absolute name (load_program_in_subdir_works)
                     "--programs-alias", "/ursim/programs",
                     # URCL's CI runs against URSim, whose sensors are ideal: its driver tests
                     # compare actual_q at rest before and after a refused command with
                     # EXPECT_FLOAT_EQ (target_outside_limits_servoj/_pose). With the encoders'
                     # white noise (σ 1e-5 rad against a 2.4e-5 rad count) a joint at rest reads
                     # one count off now and then; the quantisation stays.
                     "--set", "sensors.noise=false"]
        # the dashboard's saveLog, flight report and support file (URCL's dashboard tests)
        # write the controller's log here
        log_dir = os.path.join(os.path.dirname(os.path.abspath(log_path)), "controller_log")
        os.makedirs(log_dir, exist_ok=True)
        self.args += ["--log-dir", log_dir]
        if version.startswith("5."):
            # as URCL's CI URSim: remote control disabled in Settings (the factory default), so
            # `is in remote control` answers false and the dashboard refuses nothing
            self.args += ["--no-remote-control"]
        if os.environ.get("URT_TEST_RT", "1") != "0" and realtime_permitted():
            self.args += ["--rt-priority", "80"]
        self.log_path = log_path
        self.proc = None
        self.restarts = 0

    def start(self):
        log = open(self.log_path, "a")
        log.write(f"---- start: {' '.join(self.args)}\n")
        log.flush()
        self.proc = subprocess.Popen(self.args, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT)
        log.close()
        for port in PORTS:
            if not wait_port(ROBOT_IP, port, 10.0):
                self.stop()
                raise SystemExit(f"urtwin did not open {ROBOT_IP}:{port} (log: {self.log_path})")

    def alive(self):
        return self.proc is not None and self.proc.poll() is None

    @staticmethod
    def dashboard(*queries):
        """The dashboard's answers to queries, one connection (OSError when it cannot)."""
        with socket.create_connection((ROBOT_IP, 29999), timeout=2) as s:
            s.recv(256)  # the banner
            answers = []
            for query in queries:
                s.sendall(query.encode() + b"\n")
                answers.append(s.recv(256).decode(errors="replace").strip())
            return answers

    def save_log(self):
        """The dashboard's saveLog: the controller log (program messages, runtime errors, safety
        events with a protective stop's causes) lands in logs/controller_log/log_history.txt,
        each line once, so a failed test's program end can be read after the run."""
        try:
            self.dashboard("saveLog")
        except OSError as e:
            print(f"  (controller log not saved: {e})")

    def log_file(self):
        return os.path.join(os.path.dirname(os.path.abspath(self.log_path)), "controller_log",
                            "log_history.txt")

    def log_excerpt(self, n=8):
        """The controller's log lines since the last saveLog (saveLog appends only what is new),
        the last n of them that say why a program ended (errors, stops, safety events, the
        program's own end): what a failed test's record carries, so that CI's output names the
        cause without the run's files."""
        if not self.alive():
            return []
        path = self.log_file()
        start = os.path.getsize(path) if os.path.exists(path) else 0
        self.save_log()
        try:
            with open(path, errors="replace") as f:
                f.seek(start)
                lines = f.read().splitlines()
        except OSError:
            return []
        telling = [ln.strip() for ln in lines
                   if re.search(r"ERROR|WARN|STOPPED|[Pp]rotective|safety|fault|violation", ln)]
        return telling[-n:] + [f"(now) {self.dashboard_state()}"]

    def dashboard_state(self):
        """programState, robotmode and safetymode as the dashboard answers them now: whether a
        failed test's program still runs (a hang) or ended (a stop)."""
        try:
            return "; ".join(self.dashboard("programState", "robotmode", "safetymode"))
        except OSError as e:
            return f"dashboard: {e}"

    def stop(self):
        if self.proc is None:
            return
        if self.proc.poll() is None:
            self.save_log()
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None
