#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Fail `make test` when a test that should have run did not.

ctest runs what CMake registered and pytest what it collects, so a test binary dropped from the
build or a test file that fails to import would otherwise vanish with the suite still green.
This compares what actually ran, read back from the runs' own reports (ctest's and pytest's JUnit
XML, libFuzzer's final statistics), against tests/expected_tests.txt, the checked-in list: every
listed test must have run, and everything that ran must be listed (a new test is added to the list
in the same commit that adds it).

  check_tests_ran.py --expected tests/expected_tests.txt
      --ctest build/ctest-junit.xml            (release CMocka run: every [ctest] name)
      --ctest-asan build-asan/ctest-junit.xml  (ASan run: every [ctest] name but reference/*)
      --ctest-tsan build-tsan/ctest-junit.xml  (ThreadSanitizer run: every [tsan] name)
      --fuzz-logs build-asan                   (fuzz_<name>.log with libFuzzer's 'Done' line)
      --pytest build/pytest-junit.xml          (every [pytest] file with at least one test)

Any of the report options may be left out; its section is then not checked. Exit 1 on a
difference, with each missing or unlisted name printed.
"""
import argparse
import os
import re
import sys
import xml.etree.ElementTree as ET


def read_expected(path):
    """{section: [names]} from the list file: '[section]' headers, '#' comments."""
    sections, cur = {}, None
    with open(path) as f:
        for lineno, raw in enumerate(f, 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            m = re.fullmatch(r"\[(\w[\w-]*)\]", line)
            if m:
                cur = sections.setdefault(m.group(1), [])
            elif cur is None:
                raise SystemExit(f"{path}:{lineno}: a name before any [section]")
            else:
                cur.append(line)
    return sections


def junit_cases(path):
    """[(classname, name, status)] of a JUnit XML report; status is pass, fail or skip."""
    cases = []
    for tc in ET.parse(path).getroot().iter("testcase"):
        if tc.find("failure") is not None or tc.find("error") is not None:
            status = "fail"
        elif tc.find("skipped") is not None:
            status = "skip"
        else:
            status = "pass"
        cases.append((tc.get("classname", ""), tc.get("name", ""), status))
    return cases


def compare(what, expected, ran):
    """Problems (one line each) between the expected names and those that ran."""
    expected, ran = set(expected), set(ran)
    out = [f"{what}: expected but did not run: {n}" for n in sorted(expected - ran)]
    out += [f"{what}: ran but is not in the expected list: {n}" for n in sorted(ran - expected)]
    return out


def ctest_names(path):
    # ctest writes the test's name as the testcase name
    return [name for _, name, _ in junit_cases(path)]


def pytest_files(path):
    """The test files with at least one collected test; classname is 'tests.python.test_x'
    (or 'test_x.Class'), so the module is the last dotted part that starts with test_."""
    files = set()
    for classname, _, _ in junit_cases(path):
        mods = [p for p in classname.split(".") if p.startswith("test_")]
        if mods:
            files.add(mods[0] + ".py")
    return files


def fuzz_run(logdir, names):
    """The fuzz targets whose log in logdir ends a libFuzzer run ('Done N runs')."""
    ran = []
    for n in names:
        log = os.path.join(logdir, f"fuzz_{n}.log")
        try:
            with open(log, errors="replace") as f:
                if re.search(r"^Done \d+ runs", f.read(), re.M):
                    ran.append(n)
        except OSError:
            pass
    return ran


def fuzz_built(logdir):
    """The fuzz targets built into logdir/tests/fuzz (so an unlisted new one is noticed)."""
    d = os.path.join(logdir, "tests", "fuzz")
    if not os.path.isdir(d):
        return []
    return [f[len("fuzz_"):] for f in os.listdir(d)
            if f.startswith("fuzz_") and os.access(os.path.join(d, f), os.X_OK)
            and os.path.isfile(os.path.join(d, f))]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--expected", required=True)
    ap.add_argument("--ctest")
    ap.add_argument("--ctest-asan")
    ap.add_argument("--ctest-tsan")
    ap.add_argument("--fuzz-logs")
    ap.add_argument("--pytest")
    a = ap.parse_args(argv)
    exp = read_expected(a.expected)
    problems, counts = [], []
    if a.ctest:
        names = ctest_names(a.ctest)
        problems += compare("ctest (release)", exp.get("ctest", []), names)
        counts.append(f"ctest release {len(names)}/{len(exp.get('ctest', []))}")
    if a.ctest_asan:
        want = [n for n in exp.get("ctest", []) if not n.startswith("reference/")]
        names = ctest_names(a.ctest_asan)
        problems += compare("ctest (asan)", want, names)
        counts.append(f"ctest asan {len(names)}/{len(want)}")
    if a.ctest_tsan:
        names = ctest_names(a.ctest_tsan)
        problems += compare("ctest (tsan)", exp.get("tsan", []), names)
        counts.append(f"ctest tsan {len(names)}/{len(exp.get('tsan', []))}")
    if a.fuzz_logs:
        want = exp.get("fuzz", [])
        ran = fuzz_run(a.fuzz_logs, want)
        problems += compare("fuzz", want, set(ran) | set(fuzz_built(a.fuzz_logs)))
        problems += [f"fuzz: built but its run did not finish: {n}"
                     for n in sorted(set(want) - set(ran)) if n in fuzz_built(a.fuzz_logs)]
        counts.append(f"fuzz {len(ran)}/{len(want)}")
    if a.pytest:
        files = pytest_files(a.pytest)
        problems += compare("pytest", exp.get("pytest", []), files)
        counts.append(f"pytest files {len(files)}/{len(exp.get('pytest', []))}")
    for p in problems:
        print(p)
    print("tests that ran:", ", ".join(counts) if counts else "nothing checked")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
