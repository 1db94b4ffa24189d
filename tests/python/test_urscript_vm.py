# SPDX-License-Identifier: Apache-2.0
"""The URScript VM in a real urtwin process: threads of one program run per controller tick, and a
thread that loops without yielding gets UR's runtime error, the program stops, and every port
keeps serving (net/urscript/script_sched.c); a protective stop met while running pauses the
program instead (net/urscript/script_controller.c)."""

import re
import socket
import time

from urtwin_proc import Dashboard, Emulator, PrimaryReader, RtReader, rt_now

RUNAWAY = """def runaway():
  thread spin():
    x = 0
    while True:
      x = x + 1
    end
  end
  textmsg("started")
  run spin()
  while True:
    sync()
  end
end
"""

TWO_THREADS = """def two():
  global n = 0
  thread a():
    i = 0
    while i < 50:
      set_standard_digital_out(0, i % 2 == 0)
      sync()
      i = i + 1
    end
    n = n + 1
  end
  thread b():
    i = 0
    while i < 25:
      set_standard_digital_out(1, i % 2 == 0)
      sleep(0.004)
      i = i + 1
    end
    n = n + 1
  end
  ta = run a()
  tb = run b()
  join ta
  join tb
  textmsg("joined ", n)
end
"""


def serves_every_port(host):
    """each port answers as a controller does: version on 30001/30002, a packet on 30003, the
    dashboard's reply, and RTDE's protocol-version reply on 30004"""
    for port in (30001, 30002):
        with PrimaryReader(host, port) as pr:
            assert pr.read()[0] == 20
    with RtReader(host) as rt:
        rt.read_decoded()
    with socket.create_connection((host, 29999), timeout=2) as s:
        s.recv(1024)  # greeting
        s.sendall(b"robotmode\n")
        assert s.recv(1024).startswith(b"Robotmode:")
    with socket.create_connection((host, 30004), timeout=2) as s:
        s.sendall(bytes([0, 5, ord("V"), 0, 2]))  # REQUEST_PROTOCOL_VERSION 2
        reply = s.recv(64)
        assert reply[2] == ord("V") and reply[3] == 1
    return True


def test_runaway_thread_is_too_much_behind_and_the_emulator_keeps_serving():
    with Emulator() as emu:
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()
            emu.send_script(RUNAWAY, port=30001)
            msgs = pr.robot_messages(1.5)
        texts = [m["text"] for m in msgs if m["type"] == 0]
        exc = [m for m in msgs if m["type"] == 10]
        keys = [(m["title"], m["text"]) for m in msgs if m["type"] == 7]
        print(f"\nruntime exception: {exc}, keys {keys}")
        assert any("started" in t for t in texts)
        assert len(exc) == 1 and exc[0]["text"] == "Runtime is too much behind"
        assert exc[0]["line"] in (4, 5)  # inside spin's loop
        assert ("PROGRAM_XXX_STOPPED", "runaway") in keys
        with RtReader(emu.host) as rt:
            assert rt.read_decoded()["program_state"] == 1  # STOPPED
        assert serves_every_port(emu.host)
        # and the next program runs
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()
            emu.send_script('def after():\n  textmsg("next one")\nend\n', port=30001)
            assert any("next one" in m.get("text", "") for m in pr.robot_messages(1.0))
        assert emu.alive()


def test_two_threads_run_side_by_side_and_join():
    with Emulator() as emu:
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()
            t0 = time.monotonic()
            emu.send_script(TWO_THREADS, port=30001)
            msgs = pr.robot_messages(1.0)
        texts = [m["text"] for m in msgs if m["type"] == 0]
        keys = [(m["title"], m["text"]) for m in msgs if m["type"] == 7]
        print(f"\ntexts {texts}, keys {keys}, {time.monotonic() - t0:.2f} s")
        # both threads ran their 50 ticks side by side (100 ms), n is the program's variable
        assert "joined 2" in texts
        assert ("PROGRAM_XXX_STOPPED", "two") in keys
        assert not [m for m in msgs if m["type"] == 10]


def test_vm_cost_per_tick_is_counted_for_every_tick_of_a_program():
    """urtwin's exit line "urscript per tick": one sample per controller tick a main program ran
    (tools/bench_urcl_vm.py reads it under URCL's script)"""
    ticks = 100
    prog = (f"def counted():\n  i = 0\n  while i < {ticks}:\n    sync()\n    i = i + 1\n  end\n"
            '  textmsg("counted done")\nend\n')
    with Emulator() as emu:
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()
            emu.send_script(prog, port=30001)
            msgs = pr.robot_messages(1.5)
        assert any("counted done" in m.get("text", "") for m in msgs if m["type"] == 0)
    log = emu.err.decode(errors="replace")
    m = re.search(r"urscript per tick: cpu p50 ([\d.]+) us p99 ([\d.]+) us p99\.9 ([\d.]+) us "
                  r"max ([\d.]+) us over (\d+) ticks", log)
    assert m, log[-800:]
    p50, p99, p999, mx = map(float, m.groups()[:4])
    n = int(m.group(5))
    print(f"\n{m.group(0)}")
    # the slice of the program's first tick, then one per sync()
    assert n == ticks + 1
    assert 0 < p50 <= p99 <= p999 <= mx


# ---- a protective stop pauses the program (net/urscript/README.md) ----

TARGET = [0.3, -1.2, 1.0, -1.4, -1.5, 0.3]
WALK = f"""def walk():
  movej({TARGET}, a=1.0, v=0.3)
  textmsg("arrived")
end
"""



def test_a_protective_stop_pauses_the_program_and_play_runs_the_move_again():
    """A secondary program's protective_stop() during a movej: C209A0, no runtime exception, the
    program paused (30003 program_state 4) and still paused after the unlock, the arm held; the
    dashboard's play resumes it and the movej runs again from where the arm stopped to its
    target, and the program ends normally."""
    with Emulator() as emu:
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()
            emu.send_script(WALK, port=30001)
            time.sleep(0.5)
            emu.send_script("sec stopper():\n  protective_stop()\nend\n", port=30002)
            stop_msgs = pr.robot_messages(0.5)
            assert rt_now(emu.host)["safety_mode"] == 3
            emu.send_script("set unlock protective stop\n", port=30001)
            time.sleep(0.3)
            held = [rt_now(emu.host) for _ in range(2)]
            d = Dashboard(emu.host)
            assert d.ask("programState").startswith("PAUSED")
            assert d.ask("play") == "Starting program"
            d.close()
            run_msgs = []
            t_end = time.monotonic() + 10
            # until the program's end is announced too: its key message follows "arrived" and
            # may come in a later read
            while time.monotonic() < t_end and not any(
                    m["type"] == 7 and m["title"] == "PROGRAM_XXX_STOPPED" for m in run_msgs):
                run_msgs += pr.robot_messages(0.2)
            end = rt_now(emu.host)
    errors = [(m["code"], m["argument"], m["level"]) for m in stop_msgs if m["type"] == 6]
    print(f"\nerror codes {errors}; held at {held[1]['q_actual']}; ended at {end['q_actual']}")
    assert errors == [(209, 0, 2)]
    assert not [m for m in stop_msgs + run_msgs if m["type"] == 10]  # no runtime exception
    for h in held:
        assert h["safety_mode"] == 1 and h["program_state"] == 4  # unlocked, still paused
    assert max(abs(a - b) for a, b in zip(held[0]["q_actual"], held[1]["q_actual"])) < 1e-4
    assert max(abs(a - b) for a, b in zip(held[1]["q_actual"], TARGET)) > 0.05  # stopped midway
    keys = [(m["title"], m["text"]) for m in run_msgs if m["type"] == 7]
    assert any(m["type"] == 0 and m["text"] == "arrived" for m in run_msgs)
    assert ("PROGRAM_XXX_STOPPED", "walk") in keys
    assert max(abs(a - b) for a, b in zip(end["q_actual"], TARGET)) < 1e-3


def test_a_line_out_of_the_workspace_is_a_warning_and_a_paused_program():
    """URCL's test_send_script_blocking_fail_on_robot_errors in small: movel(p[10,0,0,0,0,0]) is
    a protective stop with the error code C153A0 at WARNING level and no runtime exception;
    `stop program` ends the paused program."""
    with Emulator() as emu:
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()
            emu.send_script("def out():\n  movel(p[10, 0, 0, 0, 0, 0])\nend\n", port=30001)
            msgs = pr.robot_messages(0.6)
            paused = rt_now(emu.host)
            emu.send_script("stop program\n", port=30001)
            after = pr.robot_messages(0.5)
            stopped = rt_now(emu.host)
    errors = [(m["code"], m["argument"], m["level"]) for m in msgs if m["type"] == 6]
    print(f"\nerror codes {errors}")
    assert errors == [(153, 0, 2)]
    assert [m["safety_mode"] for m in msgs if m["type"] == 5] == [3]
    assert not [m for m in msgs + after if m["type"] == 10]
    assert paused["program_state"] == 4 and paused["safety_mode"] == 3
    assert ("PROGRAM_XXX_STOPPED", "out") in [(m["title"], m["text"]) for m in after if m["type"] == 7]
    assert stopped["program_state"] == 1


def test_a_dashboard_pause_freezes_the_program_and_its_sleep():
    """dashboard pause 0.2 s into a 0.6 s sleep, 1 s long: nothing runs while paused (no
    "woke"), and after play the sleep still has its 0.4 s to go (script_sched.c frozen_at)"""
    with Emulator() as emu:
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()
            d = Dashboard(emu.host)
            emu.send_script('def slow():\n  sleep(0.6)\n  textmsg("woke")\nend\n', port=30001)
            time.sleep(0.2)
            assert d.ask("pause") == "Pausing program"
            t_pause = time.monotonic()
            paused_msgs = pr.robot_messages(1.0)
            state = rt_now(emu.host)["program_state"]
            assert d.ask("play") == "Starting program"
            t_play = time.monotonic()
            woke_at = None
            t_end = t_play + 3.0
            while woke_at is None and time.monotonic() < t_end:
                for m in pr.robot_messages(0.05):
                    if m["type"] == 0 and m["text"] == "woke":
                        woke_at = time.monotonic()
            d.close()
    print(f"\npaused {t_play - t_pause:.2f} s; woke {woke_at - t_play if woke_at else None} s after play")
    assert state == 4
    assert not [m for m in paused_msgs if m["type"] == 0 and m["text"] == "woke"]
    assert woke_at is not None
    assert 0.25 <= woke_at - t_play <= 1.5  # the 0.4 s the sleep had left (wall time, loaded host)


def test_an_rtde_watchdog_with_pause_pauses_the_program_until_play():
    """rtde_set_watchdog(register, 4 Hz, "pause") with no writes: the program pauses (30003
    program_state 4) and does not end; after play it runs again and, still without writes, the
    watchdog pauses it again (script_service.c)"""
    prog = ('def watched():\n  rtde_set_watchdog("input_int_register_0", 4, "pause")\n'
            '  while True:\n    sync()\n  end\nend\n')
    with Emulator() as emu:
        with PrimaryReader(emu.host, 30001) as pr:
            pr.read()
            emu.send_script(prog, port=30001)
            time.sleep(0.8)
            first = rt_now(emu.host)["program_state"]
            d = Dashboard(emu.host)
            assert d.ask("play") == "Starting program"
            t_end = time.monotonic() + 1.0  # the resume takes effect at the next tick
            playing = rt_now(emu.host)["program_state"]
            while playing != 2 and time.monotonic() < t_end:
                playing = rt_now(emu.host)["program_state"]
            time.sleep(0.8)
            again = rt_now(emu.host)["program_state"]
            assert d.ask("stop") == "Stopped"
            d.close()
            msgs = pr.robot_messages(0.3)
    print(f"\nprogram_state: {first} after 0.8 s, {playing} after play, {again} 0.8 s later")
    assert (first, playing, again) == (4, 2, 4)
    assert not [m for m in msgs if m["type"] == 10]
