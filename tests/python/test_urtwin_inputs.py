# SPDX-License-Identifier: Apache-2.0
"""The control box's inputs, set from outside (`urtwin --io FILE`, tools/io_script.h): each
change shows from the first tick at or after its time in RTDE, on 30003 and on the primary
interface, and in URScript; a bad script is refused with file:line: key: reason, exit 2.
(The LCM channel URTWIN_IO is tested in test_lcm.py.)"""

import struct
import subprocess
import threading
import time

from rtde_client import RtdeClient
from urtwin_proc import CONFIG, URTWIN, Emulator, PrimaryReader, RtReader

PERIOD = 0.002
# at 0.6 s: standard 0 and 3, configurable 2, tool 1 high, analog 4.25 V and 7.5 V (tool 1);
# at 1.0 s: standard 3 low again, standard analog 1 at 0.125 V
SCRIPT = """# a test rig's inputs
- t: 0.6
  standard_digital_in: {0: true, 3: true}
  configurable_digital_in: {2: true}
  tool_digital_in: {1: true}
  standard_analog_in: {0: 4.25}
  tool_analog_in: {1: 7.5}
- t: 1.0
  standard_digital_in: {3: false}
  standard_analog_in: {1: 0.125}
"""
BITS_1 = 1 << 0 | 1 << 3 | 1 << (8 + 2) | 1 << (16 + 1)
BITS_2 = BITS_1 & ~(1 << 3)


def rtde_samples(host, seconds, out):
    names = ["timestamp", "actual_digital_input_bits", "standard_analog_input0",
             "standard_analog_input1", "tool_analog_input0", "tool_analog_input1",
             "analog_io_types", "tool_analog_input_types"]
    with RtdeClient(host).connect() as c:
        c.negotiate_protocol_version(2)
        c.setup_outputs(names, frequency=500)
        c.start()
        t_end = time.monotonic() + seconds
        while time.monotonic() < t_end:
            out.append(c.receive(timeout=2).values)


def rt_samples(host, seconds, out):
    with RtReader(host) as rt:
        t_end = time.monotonic() + seconds
        while time.monotonic() < t_end:
            p = rt.read_decoded()
            out.append((p["time"], int(p["digital_inputs"])))


def primary_io(host):
    """(digital input bits, analog in 0, 1, tool analog in 0, 1) from one robot state message."""
    with PrimaryReader(host) as pr:
        for _ in range(200):
            kind, body = pr.read()
            if kind != 16:
                continue
            mb = tool = None
            off = 0
            while off + 5 <= len(body):
                size, sub = struct.unpack_from(">iB", body, off)
                if sub == 3:
                    mb = struct.unpack_from(">IIBBdd", body, off + 5)
                elif sub == 2:
                    tool = struct.unpack_from(">bbdd", body, off + 5)
                off += size
            if mb and tool:
                return mb[0], mb[4], mb[5], tool[2], tool[3]
    raise AssertionError("no robot state with masterboard and tool data")


def first_time(samples, pred):
    return next((t for t, v in samples if pred(v)), None)


def test_io_script_sets_inputs_from_the_tick_of_their_time_in_rtde_30003_primary_and_script(
        tmp_path):
    io = tmp_path / "rig.yaml"
    io.write_text(SCRIPT)
    rtde, rt = [], []
    with Emulator("--io", str(io)) as emu:
        threads = [threading.Thread(target=rtde_samples, args=(emu.host, 1.6, rtde)),
                   threading.Thread(target=rt_samples, args=(emu.host, 1.6, rt))]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        prim = primary_io(emu.host)
        # URScript reads the same inputs: it writes what it sees to output registers
        emu.send_script("def io():\n"
                        "  n = 1\n"
                        "  if get_standard_digital_in(0):\n    n = n + 2\n  end\n"
                        "  if get_standard_digital_in(3):\n    n = n + 4\n  end\n"
                        "  if get_tool_digital_in(1):\n    n = n + 8\n  end\n"
                        "  write_output_integer_register(0, n)\n"
                        "  write_output_float_register(0, get_standard_analog_in(0))\n"
                        "  write_output_float_register(1, get_tool_analog_in(1))\n"
                        "  write_output_float_register(2, get_analog_in(3))\n"
                        "end\n")
        time.sleep(0.3)
        with RtdeClient(emu.host).connect() as c:
            c.negotiate_protocol_version(2)
            c.setup_outputs(["output_int_register_0", "output_double_register_0",
                             "output_double_register_1", "output_double_register_2"],
                            frequency=125)
            c.start()
            regs = c.receive(timeout=2).values
    log = emu.err.decode(errors="replace")

    ts = [(p["timestamp"], p) for p in rtde]
    on = first_time(ts, lambda p: p["actual_digital_input_bits"] == BITS_1)
    off = first_time(ts, lambda p: p["actual_digital_input_bits"] == BITS_2)
    an1 = first_time(ts, lambda p: p["standard_analog_input1"] == 0.125)
    rt_on = first_time(rt, lambda b: b == BITS_1)
    rt_off = first_time(rt, lambda b: b == BITS_2)
    print(f"\n--io: RTDE shows the 0.6 s change at {on} s, the 1.0 s change at {off} s "
          f"(analog 1 at {an1} s); 30003 at {rt_on} s and {rt_off} s; primary {prim}; "
          f"URScript registers {regs}")
    # before its time nothing is set, from the first tick at or after it everything is
    before = [p for t, p in ts if t < 0.6 - 1e-9]
    assert before and all(p["actual_digital_input_bits"] == 0 and p["standard_analog_input0"] == 0
                          for p in before)
    assert on is not None and 0.6 - 1e-9 <= on <= 0.6 + PERIOD + 1e-9
    assert off is not None and 1.0 - 1e-9 <= off <= 1.0 + PERIOD + 1e-9
    assert an1 == off
    p_on = dict(ts)[on]
    assert p_on["standard_analog_input0"] == 4.25 and p_on["tool_analog_input1"] == 7.5
    assert p_on["standard_analog_input1"] == 0.0 and p_on["tool_analog_input0"] == 0.0
    assert p_on["analog_io_types"] == 3 and p_on["tool_analog_input_types"] == 3
    assert rt_on is not None and abs(rt_on - on) < 1e-9  # the same tick on 30003
    assert rt_off is not None and abs(rt_off - off) < 1e-9
    assert prim == (BITS_2, 4.25, 0.125, 0.0, 7.5)
    assert regs["output_int_register_0"] == 1 + 2 + 8  # input 0 and tool 1 high, input 3 low
    assert regs["output_double_register_0"] == 4.25
    assert regs["output_double_register_1"] == 7.5 and regs["output_double_register_2"] == 7.5
    assert "--io: 2 of 2 input changes played, 0 dropped" in log


BAD = [
    ("- t: 0.5\n  standard_digital_in: {8: true}\n", ":2: standard_digital_in: pin '8'"),
    ("- t: 0.5\n  tool_digital_in: {0: yes}\n", ":2: tool_digital_in.0: expected true or false"),
    ("- t: 0.5\n  standard_analog_in: {0: 11}\n", ":2: standard_analog_in.0: outside [0, 10] V"),
    ("- t: 0.5\n  standard_analog_in: {0: .nan}\n", ":2: standard_analog_in.0: expected a number"),
    ("- t: 0.5\n  standard_digitl_in: {0: true}\n", ":2: standard_digitl_in: unknown key"),
    ("- t: 1.0\n  tool_digital_in: {0: true}\n- t: 0.5\n  tool_digital_in: {0: false}\n",
     ":3: t: times must not decrease"),
    ("- standard_digital_in: {0: true}\n", ":1: t: missing"),
    ("- t: 0.5\n", ":1: (entry): changes no input"),
    ("t: 0.5\n", ":1: (top): expected a list"),
    ("- t: [0.5\n", ":"),  # not YAML: the parser's own message, with the file and line
]


def test_io_script_errors_name_file_line_and_key_and_exit_2(tmp_path):
    for k, (text, want) in enumerate(BAD):
        f = tmp_path / f"bad{k}.yaml"
        f.write_text(text)
        p = subprocess.run([URTWIN, "--config", CONFIG, "--bind", "127.0.0.1", "--io", str(f)],
                           capture_output=True, text=True, timeout=20)
        assert p.returncode == 2, (text, p.stderr)
        assert f"urtwin: --io: {f}{want}" in p.stderr, (text, p.stderr)
    p = subprocess.run([URTWIN, "--config", CONFIG, "--io", str(tmp_path / "absent.yaml")],
                       capture_output=True, text=True, timeout=20)
    assert p.returncode == 2 and "absent.yaml: cannot read" in p.stderr, p.stderr
