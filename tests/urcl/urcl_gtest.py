# SPDX-License-Identifier: Apache-2.0
"""tests/urcl/urcl_gtest.py — running URCL's programs bounded in time: an example (its exit
code), an integration binary followed through gtest's progress lines and read back from its
JSON (a test that hangs is killed and recorded, a crash is recorded)."""

import json
import os
import re
import signal
import subprocess
import time

def run_bounded(cmd, cwd, timeout, log_path, stdin=subprocess.DEVNULL):
    """Run cmd (own process group) with output to log_path; returns (returncode or None on
    timeout, seconds)."""
    t0 = time.monotonic()
    with open(log_path, "w") as log:
        p = subprocess.Popen(cmd, cwd=cwd, stdout=log, stderr=subprocess.STDOUT, stdin=stdin,
                             start_new_session=True)
        try:
            rc = p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
            rc = None
    return rc, time.monotonic() - t0


def run_program(cmd, cwd, timeout, log_path):
    """An example or one of our programs, bounded: its record (passed when it exits 0)."""
    rc, secs = run_bounded(cmd, cwd, timeout, log_path)
    status = "passed" if rc == 0 else "timeout" if rc is None else "failed"
    rec = {"status": status, "seconds": round(secs, 2)}
    if rc != 0:
        rec["message"] = (f"killed after {timeout} s" if rc is None else f"exit {rc}") + \
            "; " + last_lines(log_path)
    return rec


def list_tests(binary):
    out = subprocess.run([binary, "--gtest_list_tests"], capture_output=True, text=True,
                         timeout=30).stdout
    names, suite = [], None
    for line in out.splitlines():
        if not line.strip():
            continue
        if not line.startswith(" "):
            suite = line.split()[0]
        else:
            names.append(suite + line.split()[0])
    return names


RESULT = re.compile(r"^\[\s*(OK|FAILED|SKIPPED)\s*\] (\S+)(?: \((\d+) ms\))?")
SUITE_FAILED = re.compile(r"^\[\s*FAILED\s*\] (\S+): SetUpTestSuite or TearDownTestSuite")


def watch_gtest(cmd, cwd, timeout, log_path, got):
    """Run a gtest binary, following its output: fills got[test] with status, seconds and
    message; kills the process when a test runs longer than timeout."""
    status_of = {"OK": "passed", "FAILED": "failed", "SKIPPED": "skipped"}
    current, started, pos, notes = None, 0.0, 0, []
    suite_failed = {}
    last_failure = []
    with open(log_path, "w") as log:
        p = subprocess.Popen(cmd, cwd=cwd, stdout=log, stderr=subprocess.STDOUT,
                             stdin=subprocess.DEVNULL, start_new_session=True)

        def scan():
            nonlocal current, started, pos
            with open(log_path, errors="replace") as f:
                f.seek(pos)
                chunk = f.read()
            # only whole lines
            cut = chunk.rfind("\n") + 1
            pos += len(chunk[:cut].encode("utf-8", "replace"))
            for line in chunk[:cut].splitlines():
                if line.startswith("[ RUN      ] "):
                    current, started = line[13:].strip(), time.monotonic()
                    last_failure.clear()
                    continue
                m = SUITE_FAILED.match(line)
                if m:
                    suite_failed[m.group(1)] = " | ".join(notes[-2:])
                    continue
                m = RESULT.match(line)
                if m and m.group(3) is not None and m.group(2) not in got:
                    rec = {"status": status_of[m.group(1)],
                           "seconds": round(time.monotonic() - started, 2)}
                    if last_failure:
                        rec["message"] = " | ".join(last_failure)[:400]
                    got[m.group(2)] = rec
                    if m.group(2) == current:
                        current = None
                    continue
                if "Failure" in line or "exception" in line.lower():
                    (last_failure if current else notes).append(line.strip()[:200])

        rc = None
        while rc is None:
            try:
                rc = p.wait(timeout=0.25)
            except subprocess.TimeoutExpired:
                pass
            scan()
            if rc is None and current and time.monotonic() - started > timeout:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
                got[current] = {"status": "timeout", "seconds": round(timeout, 1),
                                "message": f"killed after {timeout} s; " + last_lines(log_path)}
                current = None
                return
        scan()
    if current and current not in got:
        got[current] = {"status": "crashed", "seconds": round(time.monotonic() - started, 2),
                        "message": f"exit {rc}; " + last_lines(log_path)}
    # a suite whose SetUpTestSuite failed: gtest marks its tests skipped, yet they failed
    for suite, why in suite_failed.items():
        for test, rec in got.items():
            if test.startswith(suite + ".") and rec["status"] == "skipped":
                rec["status"] = "failed"
                rec["message"] = "SetUpTestSuite failed: " + why


def failures_from_json(json_path, got):
    """Take each failed test's first failure message from gtest's JSON, when it was written."""
    try:
        with open(json_path) as f:
            data = json.load(f)
    except (OSError, ValueError):
        return
    for suite in data.get("testsuites", []):
        for t in suite.get("testsuite", []):
            key = f"{suite.get('name')}.{t.get('name')}"
            if key in got and t.get("failures") and got[key]["status"] == "failed":
                got[key]["message"] = t["failures"][0].get("failure", "")[:400]


def last_lines(path, n=3):
    try:
        with open(path, errors="replace") as f:
            lines = [l.rstrip() for l in f if l.strip()]
    except OSError:
        return ""
    return " | ".join(lines[-n:])[-400:]
