/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/test_script_sched.c — the VM's threads and controller-clocked scheduling
 * against the fake controller: each tick every runnable thread runs (in creation order) until
 * it consumes time; shared globals, own locals; run/join/kill; critical sections; a thread that
 * uses up its slice computing is preempted, one that never yields is UR's runtime error; the per-tick command stream is the same however late the
 * runner is. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fake_host.h"
#include "script.h"
#include "test_support.h"

static fake_host F;
static urt_script_host_t H;
static uint64_t motion_id;
static us_err E;
static uint64_t late_slices, late_max;

static int run_text(const char *text, int64_t budget) {
  us_prog *p = NULL;
  if (urt__us_parse(text, strlen(text), &p, &E) != 0) {
    fail_msg("parse: %u:%u %s", E.line, E.column, E.text);
  }
  us_hooks h = {.host = &H, .motion_id = &motion_id, .step_budget = budget ? budget : 100000,
                .wait_timeout_ms = 1, .late_slices = &late_slices, .late_max = &late_max};
  int rc = urt__us_run(p, &h, &E);
  urt__us_prog_free(p);
  return rc;
}

static void must_run(const char *text) {
  if (run_text(text, 0) != 0) {
    fail_msg("run: %u:%u %s", E.line, E.column, E.text);
  }
}

static int setup(void **state) {
  fake_init(&F, &H);
  motion_id = 0;
  late_slices = late_max = 0;
  memset(&E, 0, sizeof E);
  return 0;
}

/* two threads streaming servoj at one tick per iteration, the body joining both */
static const char kTwoThreads[] =
    "def two():\n"
    "  global done = 0\n"
    "  thread a():\n"
    "    i = 0\n"
    "    while i < 20:\n"
    "      servoj([1, i, 0, 0, 0, 0], t=0.002)\n"
    "      i = i + 1\n"
    "    end\n"
    "    done = done + 1\n"  /* free: the program's variable (UR's scoping rules) */
    "  end\n"
    "  thread b():\n"
    "    global done\n"
    "    i = 0\n"
    "    while i < 10:\n"
    "      set_standard_digital_out(i % 8, True)\n"
    "      sleep(0.004)\n"
    "      i = i + 1\n"
    "    end\n"
    "    done = done + 1\n"
    "  end\n"
    "  ta = run a()\n"
    "  tb = run b()\n"
    "  join ta\n"
    "  join tb\n"
    "  set_standard_digital_out(7, done == 2)\n"
    "end\n";

static void test_sched__threads_interleave_one_tick_per_wait(void **state) {
  must_run(kTwoThreads);
  // a: 20 servoj on 20 consecutive ticks; b: an output every 2 ticks; both start in tick 0
  int na = 0, nb = 0;
  uint64_t first_a = 0, last_a = 0;
  for (int k = 0; k < F.n_cmd; k++) {
    if (F.cmd[k].kind == URT_CTRL_SERVOJ) {
      if (na == 0) first_a = F.cmd_vm_tick[k];
      assert_int_equal(F.cmd_vm_tick[k], first_a + (uint64_t)na);
      assert_near(F.cmd[k].q[1], na, 0);
      last_a = F.cmd_vm_tick[k];
      na++;
    } else if (F.cmd[k].kind == URT_CTRL_SET_DIGITAL_OUT && nb < 10) {
      assert_int_equal(F.cmd_vm_tick[k], first_a + 2u * (uint64_t)nb);
      nb++;
    }
  }
  assert_int_equal(na, 20);
  assert_int_equal(nb, 10);
  assert_int_equal(last_a - first_a, 19);
  // in a tick where both act, a (created first) comes first
  int ka = fake_find_cmd(&F, URT_CTRL_SERVOJ, 0), kb = fake_find_cmd(&F, URT_CTRL_SET_DIGITAL_OUT, 0);
  assert_true(ka < kb);
  // both threads' `done` is the program's variable, each thread's `i` its own
  const urt_ctrl_cmd_t *last = &F.cmd[F.n_cmd - 1];
  assert_int_equal(last->kind, URT_CTRL_SET_DIGITAL_OUT);
  assert_int_equal(last->index, 7);
  assert_int_equal(last->value, 1);
}

static uint64_t stream_hash(const fake_host *f) {
  uint64_t h = 1469598103934665603ull;
  for (int k = 0; k < f->n_cmd; k++) {
    const urt_ctrl_cmd_t *c = &f->cmd[k];
    double q[7] = {c->q[0], c->q[1], c->q[2], c->value, c->t, (double)c->index, (double)c->kind};
    uint64_t tick = f->cmd_vm_tick[k];
    const unsigned char *b = (const unsigned char *)q;
    for (size_t j = 0; j < sizeof q; j++) h = (h ^ b[j]) * 1099511628211ull;
    b = (const unsigned char *)&tick;
    for (size_t j = 0; j < sizeof tick; j++) h = (h ^ b[j]) * 1099511628211ull;
  }
  return h;
}

static void test_sched__same_stream_however_late_the_runner_is(void **state) {
  must_run(kTwoThreads);
  uint64_t on_time = stream_hash(&F);
  int n_on_time = F.n_cmd;
  uint64_t ticks_on_time = F.s.tick;
  assert_int_equal(late_slices, 0);  // on time: no slice taken after its tick
  // again, the controller 1–4 ticks ahead at every wait and the runner descheduled meanwhile
  setup(state);
  F.jump_seed = 12345;
  F.tick_sleep_us = 50;
  must_run(kTwoThreads);
  assert_int_equal(F.n_cmd, n_on_time);
  assert_true(stream_hash(&F) == on_time);
  assert_true(F.s.tick > ticks_on_time);  // the clock really ran ahead of the runner
  // and the runner counted it: each jump of 1-4 ticks leaves the slices after it late
  assert_true(late_slices > 0);
  assert_true(late_max >= 1 && late_max <= 3);  // a jump of 4 ticks leaves the slice 3 behind
}

static void test_sched__readings_are_their_ticks_however_late_the_runner_is(void **state) {
  // get_joint_positions() and the force history behind tool_contact, with readings that
  // change every tick: a late runner's slices and service ticks read their own ticks
  static const char *kReadings = "def p():\n"
                                 "  i = 0\n"
                                 "  while i < 20:\n"
                                 "    q = get_joint_positions()\n"
                                 "    textmsg(q[0])\n"
                                 "    sync()\n"
                                 "    i = i + 1\n"
                                 "  end\n"
                                 "  textmsg(tool_contact([0, 0, 1, 0, 0, 0]))\n"
                                 "end\n";
  F.ramp = true;
  must_run(kReadings);
  static fake_host on_time;
  on_time = F;
  assert_int_equal(on_time.n_msg, 21);
  setup(state);
  F.ramp = true;
  F.jump_seed = 777;
  must_run(kReadings);
  assert_true(late_slices > 0);
  assert_int_equal(F.n_msg, on_time.n_msg);
  for (int k = 0; k < F.n_msg; k++) {
    assert_string_equal(F.msg[k].text, on_time.msg[k].text);
  }
}

static void test_sched__runaway_thread_is_too_much_behind_and_stops_the_program(void **state) {
  int rc = run_text("def p():\n"
                    "  thread spin():\n"
                    "    x = 0\n"
                    "    while True:\n"
                    "      x = x + 1\n"
                    "    end\n"
                    "  end\n"
                    "  run spin()\n"
                    "  while True:\n"
                    "    sync()\n"
                    "  end\n"
                    "end\n",
                    1000);
  assert_int_equal(rc, -1);
  assert_int_equal(E.kind, US_ERR_RUNTIME);
  assert_string_equal(E.text, "Runtime is too much behind");
  assert_true(E.line >= 4 && E.line <= 5);  // inside spin's loop
}

static void test_sched__a_computing_thread_is_preempted_and_the_others_run_in_its_frame(void **state) {
  // UR's rule: a thread that uses up its slice computing is parked until the next frame, the
  // others run in this one. URCL's script_commands thread loops on a read of its socket that
  // fails at once when URCL closed it, until the body (reverse socket) ends the program; here
  // spin polls a flag that count sets after it
  int rc = run_text("def p():\n"
                    "  global stop = False\n"
                    "  thread spin():\n"
                    "    while not stop:\n"
                    "    end\n"
                    "    set_standard_digital_out(1, True)\n"
                    "  end\n"
                    "  thread count():\n"
                    "    set_standard_digital_out(0, True)\n"
                    "    stop = True\n"
                    "  end\n"
                    "  a = run spin()\n"
                    "  b = run count()\n"
                    "  join a\n"
                    "  join b\n"
                    "end\n",
                    1000);
  if (rc != 0) {
    fail_msg("run: %u:%u %s", E.line, E.column, E.text);
  }
  int c = fake_find_cmd(&F, URT_CTRL_SET_DIGITAL_OUT, 0), s = fake_find_cmd(&F, URT_CTRL_SET_DIGITAL_OUT, c + 1);
  assert_true(c >= 0 && s > c);
  assert_int_equal(F.cmd[c].index, 0);  // count ran in the frame where spin was preempted …
  assert_int_equal(F.cmd[s].index, 1);  // … and spin saw the flag in the next one
  assert_int_equal(F.cmd_vm_tick[s], F.cmd_vm_tick[c] + 1);
}

static void test_sched__kill_stops_a_thread_and_join_returns(void **state) {
  must_run("def p():\n"
           "  thread t():\n"
           "    while True:\n"
           "      servoj([0, 0, 0, 0, 0, 0], t=0.002)\n"
           "    end\n"
           "  end\n"
           "  h = run t()\n"
           "  sleep(0.01)\n"
           "  kill h\n"
           "  join h\n"
           "  set_standard_digital_out(1, True)\n"
           "  sleep(0.01)\n"
           "end\n");
  int last_servo = -1, out = fake_find_cmd(&F, URT_CTRL_SET_DIGITAL_OUT, 0);
  int n_servo = 0;
  for (int k = 0; k < F.n_cmd; k++) {
    if (F.cmd[k].kind == URT_CTRL_SERVOJ) {
      last_servo = k;
      n_servo++;
    }
  }
  assert_true(out > last_servo);
  // the thread ran in the 5 ticks of sleep(0.01) and the tick of the kill (it runs after the
  // body in a tick, and the body killed it before its turn)
  assert_int_equal(n_servo, 5);
}

/* the index of the first servoj whose q[0] is v, from command from */
static int find_servoj(double v, int from) {
  for (int k = from; k < F.n_cmd; k++) {
    if (F.cmd[k].kind == URT_CTRL_SERVOJ && F.cmd[k].q[0] == v) {
      return k;
    }
  }
  return -1;
}

static void test_sched__critical_section_holder_runs_first_after_its_wait(void **state) {
  // t waits inside its critical section; in the next tick it runs before the body, which is
  // older and would otherwise run first
  must_run("def p():\n"
           "  thread t():\n"
           "    enter_critical\n"
           "    sync()\n"
           "    servoj([9, 0, 0, 0, 0, 0], t=0.002)\n"
           "    exit_critical\n"
           "  end\n"
           "  h = run t()\n"
           "  i = 0\n"
           "  while i < 4:\n"
           "    servoj([i, 0, 0, 0, 0, 0], t=0.002)\n"
           "    i = i + 1\n"
           "  end\n"
           "  join h\n"
           "end\n");
  int t9 = find_servoj(9, 0), b1 = find_servoj(1, 0), b0 = find_servoj(0, 0);
  assert_true(b0 >= 0 && t9 >= 0 && b1 >= 0);
  assert_true(b0 < t9);                                  // tick 0: the body, then t enters
  assert_int_equal(F.cmd_vm_tick[t9], F.cmd_vm_tick[b1]);  // tick 1: both …
  assert_true(t9 < b1);                                  // … the holder first
}

static void test_sched__a_wait_inside_a_critical_section_lets_the_others_run(void **state) {
  // URCL's pattern: the body waits inside a critical section (there a socket read), a thread
  // keeps commanding every tick meanwhile
  must_run("def p():\n"
           "  thread t():\n"
           "    while True:\n"
           "      set_standard_digital_out(0, True)\n"
           "      sync()\n"
           "    end\n"
           "  end\n"
           "  h = run t()\n"
           "  sync()\n"
           "  enter_critical\n"
           "  servoj([1, 0, 0, 0, 0, 0], t=0.002)\n"
           "  servoj([2, 0, 0, 0, 0, 0], t=0.002)\n"
           "  servoj([3, 0, 0, 0, 0, 0], t=0.002)\n"
           "  exit_critical\n"
           "  sync()\n"
           "  kill h\n"
           "end\n");
  int first = find_servoj(1, 0), third = find_servoj(3, 0);
  assert_true(first > 0 && third > first);
  assert_int_equal(F.cmd_vm_tick[third] - F.cmd_vm_tick[first], 2);
  int between = 0;
  for (int k = first; k < third; k++) {
    between += F.cmd[k].kind == URT_CTRL_SET_DIGITAL_OUT;
  }
  assert_int_equal(between, 2);  // t ran in each of the two ticks the body waited in
}

static void test_sched__halt_in_a_thread_ends_the_program(void **state) {
  must_run("def p():\n"
           "  thread t():\n"
           "    sleep(0.004)\n"
           "    halt\n"
           "  end\n"
           "  run t()\n"
           "  while True:\n"
           "    servoj([0, 0, 0, 0, 0, 0], t=0.002)\n"
           "  end\n"
           "end\n");
  assert_int_equal(E.kind, US_ERR_NONE);
  assert_true(F.n_cmd >= 2 && F.n_cmd <= 4);
}

static void test_sched__error_in_a_thread_stops_every_thread(void **state) {
  int rc = run_text("def p():\n"
                    "  thread t():\n"
                    "    sync()\n"
                    "    x = [1, 2][5]\n"
                    "  end\n"
                    "  run t()\n"
                    "  while True:\n"
                    "    sync()\n"
                    "  end\n"
                    "end\n",
                    0);
  assert_int_equal(rc, -1);
  assert_int_equal(E.line, 4);
  assert_non_null(strstr(E.text, "Index out of bounds"));
}

static void test_sched__recursion_limit_in_a_thread(void **state) {
  int rc = run_text("def p():\n"
                    "  def f(n):\n"
                    "    return f(n + 1)\n"
                    "  end\n"
                    "  thread t():\n"
                    "    f(0)\n"
                    "  end\n"
                    "  join run t()\n"
                    "end\n",
                    0);
  assert_int_equal(rc, -1);
  assert_non_null(strstr(E.text, "Stack overflow"));
}

static void test_sched__secondary_program_may_not_start_threads(void **state) {
  us_prog *p = NULL;
  const char *text = "sec s():\n  thread t():\n  end\n  run t()\nend\n";
  assert_int_equal(urt__us_parse(text, strlen(text), &p, &E), 0);
  us_hooks h = {.host = &H, .motion_id = &motion_id, .step_budget = 1000, .wait_timeout_ms = 1};
  assert_int_equal(urt__us_run(p, &h, &E), -1);
  assert_non_null(strstr(E.text, "secondary"));
  urt__us_prog_free(p);
}

/* the host learns of each tick's slice (tick_done: the emulator keeps that slice's RTDE
 * registers for the tick's package, port_rtde.c): the VM reports every tick
 * it processed, in order, after that tick's commands, first the tick before its first slice,
 * and at the end that no program runs; a secondary program reports nothing */
static struct {
  int n, n_cmd_at[256];
  uint64_t tick[256];
  bool running[256];
} R;

static void record_tick_done(void *ctx, uint64_t tick, bool running) {
  fake_host *f = ctx;
  if (R.n < 256) {
    R.tick[R.n] = tick;
    R.running[R.n] = running;
    R.n_cmd_at[R.n] = f->n_cmd;
    R.n++;
  }
}

static void test_sched__reports_each_ticks_slice_to_the_controller(void **state) {
  memset(&R, 0, sizeof R);
  H.tick_done = record_tick_done;
  F.s.tick = 10;  // a controller that has run a while
  uint64_t start = F.s.tick;
  must_run("def p():\n"
           "  i = 0\n"
           "  while i < 5:\n"
           "    set_standard_digital_out(i, True)\n"
           "    sync()\n"
           "    i = i + 1\n"
           "  end\n"
           "end\n");
  assert_true(R.n >= 7);
  assert_true(R.running[0]);
  assert_int_equal(R.tick[0], start - 1);
  assert_int_equal(R.n_cmd_at[0], 0);
  for (int k = 1; k < R.n - 1; k++) {
    assert_true(R.running[k]);
    assert_int_equal(R.tick[k], start + (uint64_t)(k - 1));
    if (k <= 5) {
      assert_int_equal(R.n_cmd_at[k], k);  // tick k-1's output is submitted before its report
    }
  }
  assert_false(R.running[R.n - 1]);
  int n = R.n;
  assert_int_equal(run_text("sec s():\n  set_standard_digital_out(1, False)\nend\n", 0), 0);
  assert_int_equal(R.n, n);
}

/* a dashboard pause freezes the program: no thread runs and sleep's time stands still, so a
 * 0.1 s sleep (50 ticks) begun at tick 0 and paused for ticks 10-39 ends at tick 80, not 50 */
static void test_sched__a_paused_program_is_frozen_with_its_timeouts(void **state) {
  F.s.program_state = URT_PROGRAM_PLAYING;
  F.pause_from = 10;
  F.resume_at = 40;
  must_run("thread t():\n  sleep(0.04)\n  set_standard_digital_out(1, True)\nend\n"
           "run t()\nsleep(0.1)\nset_standard_digital_out(0, True)\n");
  int k0 = fake_find_cmd(&F, URT_CTRL_SET_DIGITAL_OUT, 0);
  int k1 = fake_find_cmd(&F, URT_CTRL_SET_DIGITAL_OUT, k0 + 1);
  assert_true(k0 >= 0 && k1 > k0);
  assert_int_equal(F.cmd[k0].index, 1);
  assert_int_equal(F.cmd_vm_tick[k0], 50);  // the thread's 20 ticks: 10 before, 10 after
  assert_int_equal(F.cmd[k1].index, 0);
  assert_int_equal(F.cmd_vm_tick[k1], 80);
}

/* a pause that comes with a protective stop is not frozen: the threads run on (URCL's
 * read_error_code needs the external-control program to read its STOP after the unlock) */
static void test_sched__a_pause_with_a_protective_stop_is_not_frozen(void **state) {
  F.s.program_state = URT_PROGRAM_PLAYING;
  F.pstop_at = 10;
  F.unlock_at = 40;
  F.resume_at = 40;
  must_run("sleep(0.1)\nset_standard_digital_out(0, True)\n");
  int k = fake_find_cmd(&F, URT_CTRL_SET_DIGITAL_OUT, 0);
  assert_true(k >= 0);
  assert_int_equal(F.cmd_vm_tick[k], 50);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_sched__threads_interleave_one_tick_per_wait, setup),
      cmocka_unit_test_setup(test_sched__same_stream_however_late_the_runner_is, setup),
      cmocka_unit_test_setup(test_sched__readings_are_their_ticks_however_late_the_runner_is, setup),
      cmocka_unit_test_setup(test_sched__runaway_thread_is_too_much_behind_and_stops_the_program, setup),
      cmocka_unit_test_setup(test_sched__a_computing_thread_is_preempted_and_the_others_run_in_its_frame, setup),
      cmocka_unit_test_setup(test_sched__kill_stops_a_thread_and_join_returns, setup),
      cmocka_unit_test_setup(test_sched__critical_section_holder_runs_first_after_its_wait, setup),
      cmocka_unit_test_setup(test_sched__a_wait_inside_a_critical_section_lets_the_others_run, setup),
      cmocka_unit_test_setup(test_sched__halt_in_a_thread_ends_the_program, setup),
      cmocka_unit_test_setup(test_sched__error_in_a_thread_stops_every_thread, setup),
      cmocka_unit_test_setup(test_sched__recursion_limit_in_a_thread, setup),
      cmocka_unit_test_setup(test_sched__secondary_program_may_not_start_threads, setup),
      cmocka_unit_test_setup(test_sched__reports_each_ticks_slice_to_the_controller, setup),
      cmocka_unit_test_setup(test_sched__a_paused_program_is_frozen_with_its_timeouts, setup),
      cmocka_unit_test_setup(test_sched__a_pause_with_a_protective_stop_is_not_frozen, setup),
  };
  return cmocka_run_group_tests_name("net/urscript/script_sched", tests, NULL, NULL);
}
