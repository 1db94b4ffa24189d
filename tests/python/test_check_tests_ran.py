# SPDX-License-Identifier: Apache-2.0
"""tools/check_tests_ran.py: a listed test that did not run, or an unlisted one that did, fails."""
import os
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOL = os.path.join(ROOT, "tools", "check_tests_ran.py")


def run(tmp_path, expected, ctest=None, pytest=None, fuzz=None):
    exp = tmp_path / "expected.txt"
    exp.write_text(expected)
    args = [sys.executable, TOOL, "--expected", str(exp)]
    if ctest is not None:
        (tmp_path / "ctest.xml").write_text(junit(ctest, ""))
        args += ["--ctest", str(tmp_path / "ctest.xml")]
    if pytest is not None:
        (tmp_path / "pytest.xml").write_text(junit(pytest, "x"))
        args += ["--pytest", str(tmp_path / "pytest.xml")]
    if fuzz is not None:
        (tmp_path / "tests" / "fuzz").mkdir(parents=True)
        for name, done in fuzz.items():
            exe = tmp_path / "tests" / "fuzz" / f"fuzz_{name}"
            exe.write_text("")
            exe.chmod(0o755)
            (tmp_path / f"fuzz_{name}.log").write_text(
                "#1 INITED\n" + ("Done 1234 runs in 30 second(s)\n" if done else "==ERROR\n"))
        args += ["--fuzz-logs", str(tmp_path)]
    return subprocess.run(args, capture_output=True, text=True)


def junit(cases, name):
    """A JUnit report: ctest puts the test's name in name=, pytest the module in classname=."""
    rows = "".join(f'<testcase classname="{c}" name="{name or c}"/>' for c in cases)
    return f'<testsuite tests="{len(cases)}">{rows}</testsuite>'


LIST = "[ctest]\ncore/a  # comment\ncore/b\n[pytest]\ntest_x.py\n[fuzz]\nrtde\n"


def test_everything_listed_ran_passes(tmp_path):
    r = run(tmp_path, LIST, ctest=["core/a", "core/b"], pytest=["tests.python.test_x"],
            fuzz={"rtde": True})
    assert r.returncode == 0, r.stdout
    assert "ctest release 2/2" in r.stdout and "fuzz 1/1" in r.stdout


def test_a_missing_ctest_binary_fails(tmp_path):
    r = run(tmp_path, LIST, ctest=["core/a"])
    assert r.returncode == 1
    assert "expected but did not run: core/b" in r.stdout


def test_an_unlisted_test_fails(tmp_path):
    r = run(tmp_path, LIST, ctest=["core/a", "core/b", "core/new"])
    assert r.returncode == 1
    assert "not in the expected list: core/new" in r.stdout


def test_a_pytest_file_that_collected_nothing_fails(tmp_path):
    r = run(tmp_path, LIST, pytest=["tests.python.test_y"])
    assert r.returncode == 1
    assert "did not run: test_x.py" in r.stdout and "not in the expected list: test_y.py" in r.stdout


def test_a_fuzzer_that_did_not_finish_fails(tmp_path):
    r = run(tmp_path, LIST, fuzz={"rtde": False})
    assert r.returncode == 1
    assert "built but its run did not finish: rtde" in r.stdout


def test_an_unlisted_fuzzer_fails(tmp_path):
    r = run(tmp_path, LIST, fuzz={"rtde": True, "extra": True})
    assert r.returncode == 1
    assert "not in the expected list: extra" in r.stdout


def test_the_checked_in_list_parses_and_names_every_test_file():
    """Every tests/python/test_*.py is listed, so none can stop being collected unnoticed."""
    sys.path.insert(0, os.path.join(ROOT, "tools"))
    import check_tests_ran
    exp = check_tests_ran.read_expected(os.path.join(ROOT, "tests", "expected_tests.txt"))
    files = sorted(f for f in os.listdir(os.path.join(ROOT, "tests", "python"))
                   if f.startswith("test_") and f.endswith(".py"))
    assert sorted(exp["pytest"]) == files
    assert exp["ctest"] and exp["fuzz"]
