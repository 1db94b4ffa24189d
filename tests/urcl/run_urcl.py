# SPDX-License-Identifier: Apache-2.0
"""Run UR's own client library (URCL 2.14.0) against urtwin: its integration tests and its
examples, once with urtwin claiming e-Series 5.x and once CB3 3.15 (issue 9, Acceptance).

What it does, per controller version:
  * copies URCL's source tree into the build folder (its tests write ../test_artifacts and
    urscript.XXXXXX beside themselves, its examples read relative resource paths; the shared
    copy stays read-only) and uses the copy's tests/resources/dockerursim/programs/<series>/
    as urtwin's --programs-dir;
  * starts one urtwin bound to 127.0.0.2 (URCL's default robot address in our patched copy,
    ../shared/clients/PATCHES.md), so that tests expecting nothing on 127.0.0.1 and URCL's own
    fake servers can run;
  * runs every test of every integration binary (tests/CMakeLists.txt: the _headless and
    _urcap variants with --headless true|false) one at a time, as ctest would, each bounded by
    a timeout and read back from gtest's JSON; then every example in the order and with the
    argument URCL's CI gives them (run_examples.sh ROBOT 1; external_control.md §4.2), bounded
    too.
Each version runs in its own network namespace when the machine allows it (unshare -n, as
root): only a loopback device exists there, so nothing a test or URCL's servers (they bind
0.0.0.0) do can reach beyond this host, the two versions can run side by side, and other
emulators on the host do not collide with URCL's fixed ports. Otherwise they run one after the
other in the host's namespace. Everything runs under flock /tmp/urcl.lock.

Tests in exclusions.txt are never run (the reason is printed). With --check, the run fails
if any test listed in expected_pass.txt did not pass; tests that pass and are not listed are
printed, so the list can ratchet up (--write-expected rewrites it from this run).

If ../shared (URCL's sources) is absent, everything is skipped with a message.
"""

import argparse
import fcntl
import glob
import json
import os
import re
import shutil
import subprocess
import sys
import time

from urcl_gtest import failures_from_json, last_lines, list_tests, run_program, watch_gtest
from urcl_lists import (BINARIES, EXAMPLE_ARGS, HERE, LOCK, OURS, ROBOT_IP, ROOT, VERSIONS,
                        default_src, example_order, match, read_expected, read_patterns)
from urcl_urtwin import Urtwin, loopback_up, realtime_permitted


def run_version(args, name):
    version, series = VERSIONS[name]
    if args.netns:
        loopback_up()
    # the robot model, as URCL's CI matrix gives it to its tests (ur5 with CB3, ur5e with
    # e-Series): PrimaryClientTest.test_robot_type compares the robot type against it
    os.environ["ROBOT_MODEL"] = "ur5" if series == "cb3" else "ur5e"
    work = os.path.join(args.work, name)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(os.path.dirname(work), exist_ok=True)
    # a writable copy of the source tree: tests and examples write and read beside themselves
    subprocess.run(["cp", "-r", "--no-preserve=mode", args.src, work], check=True)
    os.makedirs(os.path.join(work, "test_artifacts"), exist_ok=True)
    logs = os.path.join(work, "logs")
    os.makedirs(logs)
    programs = os.path.join(work, "tests", "resources", "dockerursim", "programs", series)
    bindir = os.path.join(args.build, "tests")
    exdir = os.path.join(args.build, "examples")
    patterns = read_patterns(args.exclusions)
    results = {}
    runs = {}
    robot = Urtwin(args.urtwin, version, programs, os.path.join(logs, "urtwin.log"))
    # held shared while this version runs URCL's tests and examples; our timing programs take
    # it exclusively (below), so that they run once no other version's run is left beside them
    busy = open(os.path.join(args.work, "busy.lock"), "w")
    fcntl.flock(busy, fcntl.LOCK_SH)
    robot.start()
    filt = re.compile(args.filter) if args.filter else None
    # --only-expected (make test): just the tests expected_pass.txt lists for this version, so
    # that CI's time stays bounded; tests that do not pass yet hang until their timeouts (up
    # to 120 s each), and the full run (make urcl-report) is where newly passing ones show
    only = ({t.split("/", 1)[1] for t in read_expected(args.expected) if t.startswith(name + "/")}
            if args.only_expected else None)

    def skipped_by_only(test_id):
        """--only-expected runs what expected_pass.txt lists, and the watched tests"""
        return (only is not None and test_id not in only
                and not match(patterns, f"{name}/{test_id}", "watch"))

    def after(test_id, rec):
        watched = match(patterns, f"{name}/{test_id}", "watch")
        if watched and rec["status"] != "passed":
            rec["watched"] = watched
        if rec["status"] not in ("passed", "skipped"):
            # what the controller logged since the previous failure (or the start): the window
            # holds this test, and the lines say why its program ended, if it did
            rec["controller_log"] = robot.log_excerpt()
        if robot.proc is not None and not robot.alive():
            rec["note"] = "urtwin exited during this test; restarted"
            robot.restarts += 1
            robot.start()
        elif watched and rec["status"] != "passed":
            # a test that does not gate leaves nothing to the gated ones after it (a protective
            # stop, a program still running): a fresh urtwin, as after a crash
            rec["note"] = "watched test failed; urtwin restarted"
            robot.stop()
            robot.restarts += 1
            robot.start()
        results[test_id] = rec
        if args.verbose:
            print(f"  {name}/{test_id}: {rec['status']} ({rec['seconds']:.1f} s)", flush=True)

    def run_batch(binary, extra, timeout, tests):
        """All of tests in one process, as `./binary` would (a suite's SetUpTestSuite, e.g. the
        robot connection, runs once), watched through gtest's progress lines: a test that
        runs longer than timeout is killed and recorded, a crash is recorded, and the tests
        after it run in a new process."""
        path = os.path.join(bindir, binary)
        got = {}
        remaining = list(tests)
        rounds = 0
        while remaining:
            rounds += 1
            runs[binary] = runs.get(binary, 0) + 1  # one log per process, never overwritten
            stem = os.path.join(logs, f"{binary}.{runs[binary]}")
            cmd = [path, "--gtest_filter=" + ":".join(remaining),
                   f"--gtest_output=json:{stem}.json", "--robot_ip", ROBOT_IP, *extra]
            before = len(got)
            watch_gtest(cmd, os.path.join(work, "tests"), timeout, stem + ".log", got)
            failures_from_json(stem + ".json", got)
            if robot.proc is not None and not robot.alive():
                last = next(reversed(got), None)
                if last:
                    got[last]["note"] = "urtwin exited during this test; restarted"
                robot.restarts += 1
                robot.start()
            remaining = [t for t in remaining if t not in got]
            if len(got) == before:  # the binary dies before its first test: stop there
                for t in remaining:
                    got[t] = {"status": "crashed", "seconds": 0.0,
                              "message": "binary exited before running it; " +
                                         last_lines(stem + ".log")}
                remaining = []
        for test in tests:
            rec = got[test]
            test_id = f"{binary}/{test}"
            known = match(patterns, test_id, "known")
            if known and rec["status"] != "passed":
                rec["known"] = known
            results[test_id] = rec
            if args.verbose:
                print(f"  {name}/{test_id}: {rec['status']} ({rec['seconds']:.1f} s)", flush=True)

    try:
        later, alone = [], []
        for binary, extra, timeout in BINARIES:
            path = os.path.join(bindir, binary)
            if not os.path.exists(path):
                raise SystemExit(f"{path} missing: build URCL first (make urcl)")
            now = []
            for test in list_tests(path):
                test_id = f"{binary}/{test}"
                if filt and not filt.search(test_id):
                    continue
                if skipped_by_only(test_id):
                    continue
                reason = match(patterns, test_id, "exclude")
                if reason:
                    results[test_id] = {"status": "excluded", "seconds": 0.0, "note": reason}
                elif match(patterns, test_id, "norobot"):
                    later.append((binary, extra, timeout, test))
                elif match(patterns, test_id, "isolate"):
                    alone.append(test)
                else:
                    now.append(test)
            # one process per gtest suite, as a suite's fixture shares one robot connection
            # (SetUpTestSuite) but the next suite expects a fresh process: UrDriverTest's
            # global ExampleRobotWrapper keeps 50001-50004 and the RTDE inputs until exit, which
            # UrDriverInitTest's own drivers then cannot bind (URCL's ctest runs every test in
            # a process of its own)
            suites = {}
            for test in now:
                suites.setdefault(test.split(".", 1)[0], []).append(test)
            for group in suites.values():
                run_batch(binary, extra, timeout, group)
            for test in alone:
                run_batch(binary, extra, timeout, [test])
                results[f"{binary}/{test}"]["note"] = "run in a process of its own"
            alone = []
        if later:
            # URCL's fake-server tests serve the robot's ports themselves: urtwin stopped
            robot.stop()
            for binary, extra, timeout, test in later:
                run_batch(binary, extra, timeout, [test])
                results[f"{binary}/{test}"]["note"] = "run with urtwin stopped"
            robot.start()
        if args.examples:
            for example, timeout in example_order():
                test_id = f"examples/{example}"
                if filt and not filt.search(test_id):
                    continue
                if skipped_by_only(test_id):
                    continue
                reason = match(patterns, test_id, "exclude")
                if reason:
                    results[test_id] = {"status": "excluded", "seconds": 0.0, "note": reason}
                    continue
                rec = run_program([os.path.join(exdir, example), ROBOT_IP, *EXAMPLE_ARGS], work,
                                  timeout, os.path.join(logs, f"example_{example}.log"))
                known = match(patterns, test_id, "known")
                if known and rec["status"] != "passed":
                    rec["known"] = known
                after(test_id, rec)
            ours = os.path.join(os.path.dirname(os.path.abspath(args.build)), "ours")
            rt = ["chrt", "-f", "50"] if realtime_permitted() else []
            ours_run = [(prog, extra, timeout) for prog, extra, timeout, versions in OURS
                        if name in versions and not (filt and not filt.search(f"urtwin/{prog}"))
                        and not skipped_by_only(f"urtwin/{prog}")]
            if ours_run:
                # the ROS 2 pattern holds a 10 ms receive deadline on a 2-core machine: with
                # the other version's urtwin and URCL run beside it, this client went 12-20 ms
                # without a package in every attempt of one gated run (session 16); it waits
                # here until the other versions are done
                fcntl.flock(busy, fcntl.LOCK_UN)
                fcntl.flock(busy, fcntl.LOCK_EX)
            for prog, extra, timeout in ours_run:
                test_id = f"urtwin/{prog}"
                after(test_id, run_program([*rt, os.path.join(ours, prog), ROBOT_IP, *extra],
                                           work, timeout,
                                           os.path.join(logs, f"urtwin_{prog}.log")))
    finally:
        robot.stop()
        busy.close()
    return {"version": version, "series": series, "urtwin_restarts": robot.restarts,
            "results": results, "timing": timing_lines(os.path.join(logs, "urtwin.log"))}


def timing_lines(log_path):
    """what urtwin printed of its own timing at each exit (late program slices, physics
    overruns) and whether its real-time priorities were refused: printed beside a failure, so
    that CI's output says whether the host kept up"""
    keep = []
    try:
        with open(log_path, errors="replace") as f:
            for line in f:
                if re.search(r"taken late|overruns|program start|accept|SCHED_FIFO|---- start", line):
                    line = line.strip()
                    if line.startswith("---- start"):
                        line = "start, " + ("--rt-priority" if "--rt-priority" in line
                                            else "no real-time priority")
                    keep.append(line[:160])
    except OSError:
        pass
    return keep[-12:]


# ---------------------------------------------------------------------------------------------
# the whole run


def netns_available():
    if os.environ.get("URT_URCL_NETNS", "1") == "0":
        return False
    try:
        return subprocess.run(["unshare", "-n", "true"], capture_output=True,
                              timeout=10).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


def suite_of(test_id):
    return test_id.split("/", 1)[0]


def summarise(parts):
    """Per version and suite: counts by status."""
    table = {}
    for name, part in parts.items():
        for test_id, rec in part["results"].items():
            row = table.setdefault(name, {}).setdefault(suite_of(test_id), {})
            row[rec["status"]] = row.get(rec["status"], 0) + 1
    return table


def print_table(table):
    statuses = ["passed", "failed", "timeout", "crashed", "skipped", "excluded"]
    for name, suites in table.items():
        print(f"\nURCL against urtwin as {name}:")
        print(f"  {'suite':44s} " + " ".join(f"{s:>8s}" for s in statuses))
        total = {s: 0 for s in statuses}
        for suite, row in suites.items():
            print(f"  {suite:44s} " + " ".join(f"{row.get(s, 0):8d}" for s in statuses))
            for s in statuses:
                total[s] += row.get(s, 0)
        ran = sum(total[s] for s in statuses if s != "excluded")
        print(f"  {'total':44s} " + " ".join(f"{total[s]:8d}" for s in statuses) +
              f"   ({total['passed']} of {ran} run pass)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--src", default=os.environ.get("URT_URCL_SRC") or default_src())
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "urcl", "build"),
                    help="URCL's CMake build folder")
    ap.add_argument("--urtwin", default=os.path.join(ROOT, "build", "tools", "urtwin"))
    ap.add_argument("--work", default=os.path.join(ROOT, "build", "urcl", "work"))
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "urcl", "summary.json"))
    ap.add_argument("--versions", default="e-series,cb3")
    ap.add_argument("--filter", help="regex over <binary>/<Suite.test> and examples/<name>")
    ap.add_argument("--no-examples", dest="examples", action="store_false")
    ap.add_argument("--exclusions", default=os.path.join(HERE, "exclusions.txt"))
    ap.add_argument("--expected", default=os.path.join(HERE, "expected_pass.txt"))
    ap.add_argument("--check", action="store_true",
                    help="fail if a test in --expected did not pass")
    ap.add_argument("--only-expected", action="store_true",
                    help="run only the tests expected_pass.txt lists (make test: bounded time)")
    ap.add_argument("--write-expected", action="store_true",
                    help="rewrite --expected with the tests that passed in this run")
    ap.add_argument("--retries", type=int, choices=(0, 1, 2), default=None,
                    help="a listed test that fails runs again, after every version's run, "
                    "alone on a fresh urtwin, at most this many times until it passes, and the "
                    "last result counts (default: 2 with --only-expected, else 0)")
    ap.add_argument("--jobs", type=int, default=2, help="versions run side by side (netns only)")
    ap.add_argument("--verbose", "-v", action="store_true")
    ap.add_argument("--one", help=argparse.SUPPRESS)       # child: run this version only
    ap.add_argument("--netns", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.retries is None:
        args.retries = 2 if args.only_expected else 0

    if args.one:
        part = run_version(args, args.one)
        with open(args.out, "w") as f:
            json.dump(part, f, indent=1)
        return 0

    if not os.path.isdir(args.src):
        print(f"SKIPPED: URCL's sources are not at {args.src} (../shared absent): "
              "URCL's integration tests and examples did not run")
        return 0

    names = [n.strip() for n in args.versions.split(",") if n.strip()]
    for n in names:
        if n not in VERSIONS:
            raise SystemExit(f"unknown version {n!r}: {', '.join(VERSIONS)}")
    os.makedirs(args.work, exist_ok=True)
    for old in glob.glob(os.path.join(args.work, "retry[0-9]*")):
        shutil.rmtree(old, ignore_errors=True)  # an earlier run's retries
    netns = netns_available()
    jobs = max(1, args.jobs) if netns else 1
    rt_state = ("off (URT_TEST_RT=0)" if os.environ.get("URT_TEST_RT", "1") == "0" else
                "on" if realtime_permitted() else "off (SCHED_FIFO not permitted here)")
    print(f"URCL run: versions {', '.join(names)}; "
          f"{'one network namespace each' if netns else 'host network namespace'}, "
          f"{jobs} at a time; urtwin's real-time priorities {rt_state}; waiting for {LOCK}",
          flush=True)

    def child(n, part_path, filt, work=None):
        """the command that runs version n (only what filt matches) into part_path, in
        work/<n> (default: --work)"""
        if os.path.exists(part_path):
            os.unlink(part_path)
        cmd = [sys.executable, os.path.abspath(__file__), "--one", n, "--out", part_path,
               "--src", args.src, "--build", args.build, "--urtwin", args.urtwin,
               "--work", work or args.work, "--exclusions", args.exclusions]
        if filt:
            cmd += ["--filter", filt]
        if not args.examples:
            cmd += ["--no-examples"]
        if args.only_expected:
            cmd += ["--only-expected", "--expected", args.expected]
        if args.verbose:
            cmd += ["--verbose"]
        return ["unshare", "-n", *cmd, "--netns"] if netns else cmd

    lock = open(LOCK, "w")
    fcntl.flock(lock, fcntl.LOCK_EX)
    t0 = time.monotonic()
    parts, pending, running = {}, list(names), []
    try:
        while pending or running:
            while pending and len(running) < jobs:
                n = pending.pop(0)
                part_path = os.path.join(args.work, f"{n}.part.json")
                running.append((n, part_path, subprocess.Popen(child(n, part_path, args.filter)),
                                time.monotonic()))
            time.sleep(0.5)
            for item in list(running):
                n, part_path, p, started = item
                if p.poll() is None:
                    continue
                running.remove(item)
                if p.returncode != 0 or not os.path.exists(part_path):
                    raise SystemExit(f"the {n} run failed (exit {p.returncode})")
                with open(part_path) as f:
                    parts[n] = json.load(f)
                parts[n]["seconds"] = round(time.monotonic() - started, 1)
        # A listed test that failed runs again, alone (no other version beside it), on a
        # fresh urtwin, up to --retries times until it passes, and the last run counts; the
        # earlier attempts stay in its record. Why: on this shared 2-core VM (and CI's) a host
        # stall fails a timing-bound test now and then, most often with the other version's
        # urtwin and URCL running beside it (README.md); a test that fails for a cause of
        # urtwin's fails every time.
        expected = read_expected(args.expected) if args.retries > 0 else set()
        retry_no = 0
        for n in names:
            for test_id, rec in list(parts[n]["results"].items()):
                if (rec["status"] in ("passed", "skipped", "excluded") or "watched" in rec
                        or f"{n}/{test_id}" not in expected):
                    continue
                earlier = [{k: rec[k] for k in ("status", "seconds", "message") if k in rec}]
                for _ in range(args.retries):
                    # each retry in a work folder of its own: the first attempt's logs stay in
                    # work/<n>, and those of every retry beside them
                    retry_no += 1
                    retry_work = os.path.join(args.work, f"retry{retry_no}")
                    part_path = os.path.join(retry_work, f"{n}.retry.json")
                    os.makedirs(retry_work, exist_ok=True)
                    started = time.monotonic()
                    rc = subprocess.run(child(n, part_path, "^" + re.escape(test_id) + "$",
                                              retry_work)).returncode
                    again = None
                    if rc == 0 and os.path.exists(part_path):
                        with open(part_path) as f:
                            retry_part = json.load(f)
                        again = retry_part["results"].get(test_id)
                        if again is not None:
                            again["timing"] = retry_part.get("timing", [])
                    if again is None:
                        again = {"status": "crashed",
                                 "seconds": round(time.monotonic() - started, 1),
                                 "message": f"the retry's run exited {rc} without this test's record"}
                    again["first_attempt"] = earlier[0]
                    again["earlier_attempts"] = list(earlier)
                    parts[n]["results"][test_id] = again
                    parts[n]["seconds"] = round(parts[n]["seconds"] + time.monotonic() - started, 1)
                    again["retry_logs"] = os.path.relpath(os.path.join(retry_work, n, "logs"), ROOT)
                    if args.verbose:
                        print(f"  {n}/{test_id}: retried alone, {again['status']}", flush=True)
                    if again["status"] == "passed":
                        break
                    earlier.append({k: again[k] for k in ("status", "seconds", "message")
                                    if k in again})
    finally:
        for _, _, p, _ in running:
            p.kill()
        fcntl.flock(lock, fcntl.LOCK_UN)
        lock.close()
    wall = time.monotonic() - t0

    table = summarise(parts)
    print_table(table)
    for n, part in parts.items():
        print(f"\n{n}: {part['seconds']} s, urtwin restarts: {part['urtwin_restarts']}")
        for test_id, rec in part["results"].items():
            if rec["status"] not in ("passed", "excluded", "skipped"):
                cause = (f" [known: {rec['known']}]" if "known" in rec else
                         f" [watched, not gating: {rec['watched'][:100]}]" if "watched" in rec
                         else "")
                # the head says how it ended, the tail what it printed last
                msg = rec.get("message", "")
                shown = msg if len(msg) <= 320 else msg[:70] + " ... " + msg[-250:]
                print(f"  {rec['status']:8s} {test_id}{cause}: {shown}")
                for line in rec.get("controller_log", []):
                    print(f"           controller log: {line[:150]}")
        for test_id, rec in part["results"].items():
            first = rec.get("first_attempt")
            if first:
                msg = first.get("message", "")
                shown = msg if len(msg) <= 200 else msg[:50] + " ... " + msg[-150:]
                runs = len(rec.get("earlier_attempts", [first]))
                print(f"  retried  {test_id}: {first['status']} at first ({shown}); "
                      f"{rec['status']} when run again alone on a fresh urtwin"
                      f"{'' if runs == 1 else f' (retry {runs})'} "
                      f"(its logs: {rec.get('retry_logs', '?')})")
    print(f"\nwall time of the URCL run: {wall:.0f} s")

    passed = {f"{n}/{t}" for n, part in parts.items() for t, rec in part["results"].items()
              if rec["status"] == "passed"}
    ran_ids = {f"{n}/{t}" for n, part in parts.items() for t in part["results"]}
    expected = read_expected(args.expected)
    # only what this run covered is judged (a --filter run judges its subset)
    missing = sorted(t for t in expected if t in ran_ids and t not in passed)
    watched = {t for t in ran_ids if match(read_patterns(args.exclusions), t, "watch")}
    new = sorted(passed - expected - watched)
    summary = {"wall_seconds": round(wall, 1), "netns": netns, "jobs": jobs,
               "table": table, "versions": parts, "expected_failed": missing, "newly_passing": new}
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(summary, f, indent=1)
    print(f"summary: {args.out}")
    if new:
        print(f"\n{len(new)} tests pass that {os.path.relpath(args.expected, ROOT)} does not list "
              "(add them: --write-expected):")
        for t in new:
            print(f"  {t}")
    if args.write_expected:
        keep = sorted((expected - ran_ids) | passed)
        with open(args.expected, "w") as f:
            f.write("# URCL tests and examples that pass against urtwin (version/binary/test),\n"
                    "# measured by tests/urcl/run_urcl.py; make test fails if one of them fails.\n")
            f.write("".join(t + "\n" for t in keep))
        print(f"wrote {len(keep)} tests to {args.expected}")
    if args.check and missing:
        print(f"\nFAILED: {len(missing)} tests listed in {os.path.relpath(args.expected, ROOT)} "
              "did not pass:")
        for t in missing:
            n, test_id = t.split("/", 1)
            rec = parts[n]["results"][t.split("/", 1)[1]]
            print(f"  {t}: {rec['status']}")
            # the end of CI's output is what it keeps: each attempt's cause, again, and whether
            # the host kept up with urtwin in that version's run
            attempts = rec.get("earlier_attempts", []) + [rec]
            for k, r in enumerate(attempts):
                msg = r.get("message", "")
                print(f"    attempt {k + 1} of {len(attempts)}: {r['status']}: {msg[-300:]}")
            for line in rec.get("controller_log", [])[-4:]:
                print(f"    controller log: {line[:150]}")
            for line in rec.get("timing", []):
                print(f"    retry's urtwin: {line}")
        for n in sorted({t.split("/", 1)[0] for t in missing}):
            for line in parts[n].get("timing", []):
                print(f"  {n} urtwin: {line}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
