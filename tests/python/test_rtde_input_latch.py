# SPDX-License-Identifier: Apache-2.0
"""RTDE input registers latched once per controller tick (net/server/input_latch.c): a program
that copies input_double_register_0 to output_double_register_0 every tick, and counts its ticks
in output_int_register_0, read in its slice of tick k exactly the input that tick k's data
package shows, whenever its runner thread got to the tick, with a client writing several times
per tick, also beside two busy processes. (The slice of tick k runs between ticks k and k + 1;
its outputs reach package k + 1, or a later one when the runner thread was late: the count says
which slice a package's outputs are from.)"""

import collections
import subprocess
import sys
import threading
import time

import pytest

from rtde_client import RtdeClient
from urtwin_proc import Emulator

ECHO = """def echo():
  n = 0
  while True:
    n = n + 1
    write_output_float_register(0, read_input_float_register(0))
    write_output_integer_register(0, n)
    sync()
  end
end
"""


def writer(host, stop, count):
    """input_double_register_0 = 1, 2, 3 … as fast as the socket takes them (several per tick)"""
    with RtdeClient(host).connect() as c:
        c.negotiate_protocol_version(2)
        recipe = c.setup_inputs(["input_double_register_0"])
        c.start()
        n = 0
        while not stop.is_set():
            n += 1
            c.send_inputs(recipe, {"input_double_register_0": float(n)})
            if n % 4 == 0:
                time.sleep(0.0005)
        count.append(n)


@pytest.mark.parametrize("hogs", [0, 2])
def test_a_program_reads_the_inputs_its_tick_held(hogs):
    with Emulator() as emu:
        with RtdeClient(emu.host).connect() as r:
            r.negotiate_protocol_version(2)
            r.setup_outputs(["timestamp", "input_double_register_0", "output_double_register_0",
                             "output_int_register_0"], frequency=500)
            r.start()
            emu.send_script(ECHO, port=30003)
            stop, count = threading.Event(), []
            w = threading.Thread(target=writer, args=(emu.host, stop, count), daemon=True)
            w.start()
            busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                    for _ in range(hogs)]
            packages = []
            try:
                t_end = time.monotonic() + 3.0
                while time.monotonic() < t_end:
                    packages.append(r.receive(timeout=2).values)
            finally:
                stop.set()
                w.join(timeout=5)
                for p in busy:
                    p.kill()
                    p.wait()
    ticks = [round(p["timestamp"] / 0.002) for p in packages]
    assert all(b - a == 1 for a, b in zip(ticks, ticks[1:])), "a package went missing"
    input_at = {k: p["input_double_register_0"] for k, p in zip(ticks, packages)}
    # package k + 1 carries slice k's outputs when the runner was on time: the tick of slice n
    slices = [(k, p) for k, p in zip(ticks, packages) if p["output_int_register_0"] > 0]
    assert len(slices) > 1000, "the program did not run"
    offsets = collections.Counter(k - 1 - p["output_int_register_0"] for k, p in slices)
    k0, on_time = offsets.most_common(1)[0]
    judged = [(k0 + p["output_int_register_0"], p["output_double_register_0"]) for _, p in slices
              if k0 + p["output_int_register_0"] in input_at]
    wrong = [(k * 0.002, input_at[k], v) for k, v in judged if input_at[k] != v]
    changes = sum(1 for a, b in zip(packages, packages[1:])
                  if a["input_double_register_0"] != b["input_double_register_0"])
    print(f"\n{hogs} hogs: {count[0] if count else 0} input packages written, the latched input "
          f"changed in {changes} of {len(packages)} ticks; {len(slices) - on_time} packages carried "
          f"an older slice's outputs (the runner late); the input a slice read differs from its "
          f"tick's package in {len(wrong)} of {len(judged)}: {wrong[:5]}")
    assert changes > len(packages) // 2
    assert wrong == []
