# SPDX-License-Identifier: Apache-2.0
"""The dashboard's saveLog, generate flight report and generate support file write the
controller's log (net/server/ctrl_log.h) into urtwin's --log-dir: what a program said, addToLog
lines and safety events, with their controller times. Without --log-dir they are refused, not
answered as if done. The support file is read back with Python's zipfile (its CRC-32 checked)."""

import re
import time
import zipfile

from urtwin_proc import Dashboard, Emulator


def test_log_commands_write_the_controllers_log_into_the_log_folder(tmp_path):
    with Emulator("--log-dir", str(tmp_path)) as emu:
        d = Dashboard(emu.host)
        assert d.ask("addToLog hello from the test") == "Added log message"
        emu.send_script('def talk():\n  textmsg("program says ", 42)\n  protective_stop()\nend')
        time.sleep(0.5)
        assert d.ask("saveLog") == "Log saved to disk"
        report = d.ask("generate flight report controller")
        support = d.ask("generate support file .")
        assert d.ask("addToLog second") == "Added log message"
        assert d.ask("saveLog") == "Log saved to disk"
        d.close()
    history = (tmp_path / "log_history.txt").read_text()
    print(f"\nlog_history.txt:\n{history}{report}\n{support}")
    lines = history.splitlines()
    # each line once, in order, with a controller time and a level
    assert sum("hello from the test" in x for x in lines) == 1
    assert sum("second" in x for x in lines) == 1
    assert [x for x in lines if "hello" in x or "second" in x][0].count("hello") == 1
    assert any("program says 42" in x for x in lines)
    assert any("safety mode PROTECTIVE_STOP" in x and "WARN" in x for x in lines)
    assert any("C209A0" in x for x in lines)
    times = [float(x.split()[0]) for x in lines]
    assert times == sorted(times) and times[0] > 0
    m = re.fullmatch(r"Flight Report generated with id: (\d+)", report)
    assert m, report
    fr = (tmp_path / f"flight_report_{m.group(1)}.txt").read_text()
    assert "serial number 20235501783" in fr and "hello from the test" in fr
    assert "second" not in fr  # it came after the report
    m = re.fullmatch(r"Completed successfully: (.*ur_support_file_1\.zip)", support)
    assert m, support
    with zipfile.ZipFile(m.group(1)) as z:
        assert z.testzip() is None  # every entry's CRC-32 checks
        assert sorted(z.namelist()) == ["flight_report.txt", "log_history.txt"]
        assert "program says 42" in z.read("log_history.txt").decode()
    assert not list(tmp_path.glob("*.tmp"))


def test_without_a_log_folder_the_log_commands_are_refused():
    with Emulator() as emu:
        d = Dashboard(emu.host)
        replies = [d.ask(c) for c in ("saveLog", "generate flight report controller",
                                      "generate support file .")]
        d.close()
    assert replies == [
        "Could not save log: no log folder (start urtwin with --log-dir DIR)",
        "Flight Report could not be generated: no log folder (start urtwin with --log-dir DIR)",
        "Support file could not be generated: no log folder (start urtwin with --log-dir DIR)"]
