# SPDX-License-Identifier: Apache-2.0
"""python-urx 0.11.0 from PyPI, unmodified, against urtwin emulating a CB3.

urx 0.11.0 picks its robot-mode layout by size and only knows the 3.0 and 3.2 sizes, so it
works against controllers up to 3.4 (as against real ones; clients.md §5.2): we emulate 3.4."""

import math
import os
import time

import pytest

import built

from urtwin_proc import Emulator, RtReader, URTWIN

import urx
built.require(URTWIN)


def test_urx_getj_movej_and_realtime_monitor():
    with Emulator(version="3.4") as emu:
        rob = urx.URRobot(emu.host, use_rt=True)
        try:
            with RtReader(emu.host) as rt:
                q_state = rt.read_decoded()["q_actual"]
            q = rob.getj()
            print(f"\nurx getj {['%.6f' % x for x in q]}")
            assert max(abs(a - b) for a, b in zip(q, q_state)) < 1e-4
            assert rob.is_running()

            target = list(q)
            target[0] += 0.2
            target[2] -= 0.1
            t0 = time.monotonic()
            rob.movej(target, acc=1.0, vel=0.5, wait=True)
            took = time.monotonic() - t0
            time.sleep(0.5)  # urx returns at 80 % of the way (its threshold); let it settle
            q_end = rob.getj()
            err = max(abs(a - b) for a, b in zip(q_end, target))
            print(f"urx movej returned after {took:.2f} s, error after settling {err:.2e} rad")
            assert err < 1e-3  # urx's own joint data is float-rounded to 6 digits in the script

            # the real-time monitor (30003) reads q as well
            q_rt = rob.rtmon.q_actual(wait=True)
            print(f"urx rtmon q {['%.6f' % x for x in q_rt]}")
            assert max(abs(a - b) for a, b in zip(q_rt, target)) < 1e-3
        finally:
            rob.close()
