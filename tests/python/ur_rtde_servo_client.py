#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""A ur_rtde servoJ client in a process of its own, for test_ur_rtde_control.py's tracking test:
streams a sine on the base joint at 500 Hz (initPeriod / servoJ / waitPeriod, ur_rtde's own
loop) and prints, as JSON on its last line, what it sent: [(controller time at send, base angle)].
The test runs it under SCHED_FIFO where permitted, as a servo loop runs beside a real robot, so
that what is judged is the emulator's tracking and not a Python client's wake-ups on a loaded
machine.

    ur_rtde_servo_client.py HOST SECONDS LOOKAHEAD GAIN AMP FREQ
"""

import json
import math
import sys

import rtde_control
import rtde_receive


def main():
    host = sys.argv[1]
    seconds, lookahead, gain, amp, freq = map(float, sys.argv[2:7])
    period = 0.002
    c = rtde_control.RTDEControlInterface(host)
    # the controller time of each send, from ur_rtde's own C++ receive thread (no GIL)
    clock = rtde_receive.RTDEReceiveInterface(host, 500.0, ["timestamp", "actual_q"])
    q0 = clock.getActualQ()
    sent = []
    for k in range(int(seconds / period)):
        t_cycle = c.initPeriod()
        q = list(q0)
        q[0] = q0[0] + amp * math.sin(2 * math.pi * freq * k * period)
        sent.append((clock.getTimestamp(), q[0]))
        c.servoJ(q, 0.5, 0.5, period, lookahead, gain)
        c.waitPeriod(t_cycle)
    c.servoStop()
    c.stopScript()
    c.disconnect()
    clock.disconnect()
    print(json.dumps(sent))


if __name__ == "__main__":
    main()
