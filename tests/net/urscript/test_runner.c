/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/test_runner.c — the program runner thread with a fake controller:
 * program lifecycle messages, replacement, secondary programs, stop, compile errors. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "fake_host.h"
#include "test_support.h"
#include "urt/errors.h"

static fake_host F;
static urt_script_host_t H;
static urt_runner_t *R;

static int setup(void **state) {
  fake_init(&F, &H);
  urt_runner_config_t cfg = {.step_budget = 20000, .wait_timeout_ms = 1};
  assert_int_equal(urt_runner_create(&H, &cfg, &R), 0);
  return 0;
}

static int teardown(void **state) {
  urt_runner_destroy(R);
  R = NULL;
  return 0;
}

static void submit(const char *text) { assert_int_equal(urt_runner_submit(R, text, strlen(text)), 0); }

static void wait_idle(void) { assert_true(urt_runner_wait_idle(R, 5000)); }

/* wait (real time) until the fake saw n messages */
static void wait_msgs(int n) {
  for (int k = 0; k < 5000; k++) {
    pthread_mutex_lock(&F.mu);
    int have = F.n_msg;
    pthread_mutex_unlock(&F.mu);
    if (have >= n) return;
    usleep(1000);
  }
  fail_msg("only %d of %d messages", F.n_msg, n);
}

static void assert_key(int k, const char *title, const char *text) {
  assert_true(k < F.n_msg);
  assert_int_equal(F.msg[k].kind, URT_SCRIPT_MSG_KEY);
  assert_string_equal(F.msg[k].title, title);
  assert_string_equal(F.msg[k].text, text);
}

static void test_runner__program_reports_started_text_stopped(void **state) {
  // URCL's test_program_execution
  submit("def test_fun():\n  textmsg(\"still running\")\n  sleep(0.1)\n  sync()\nend");
  wait_idle();
  assert_int_equal(F.n_msg, 3);
  assert_key(0, "PROGRAM_XXX_STARTED", "test_fun");
  assert_int_equal(F.msg[1].kind, URT_SCRIPT_MSG_TEXT);
  assert_string_equal(F.msg[1].text, "still running");
  assert_key(2, "PROGRAM_XXX_STOPPED", "test_fun");
  // program state PLAYING, then HALT and STOPPED at the end
  int k = fake_find_cmd(&F, URT_CTRL_PROGRAM_STATE, 0);
  assert_true(k >= 0);
  assert_int_equal(F.cmd[k].index, URT_PROGRAM_PLAYING);
  int h = fake_find_cmd(&F, URT_CTRL_HALT, k);
  int s = fake_find_cmd(&F, URT_CTRL_PROGRAM_STATE, k + 1);
  assert_true(h > k && s > h);
  assert_int_equal(F.cmd[s].index, URT_PROGRAM_STOPPED);
  assert_int_equal(urt_runner_state(R), URT_PROGRAM_STOPPED);
  assert_int_equal(F.s.program_state, URT_PROGRAM_STOPPED);
}

static void test_runner__last_blended_move_is_waited_for_through_a_host_stall(void **state) {
  // the program's last move is still on its path when the program ends (a blend radius let it
  // go on), and the controller then does not tick for 30 timeouts (a busy host): the program's
  // HALT waits for the path's end all the same. A single timeout used to end the wait, and the
  // HALT stopped a movel 27 mm short (test_urscript_motions.py, in a fresh clone)
  pthread_mutex_lock(&F.mu);
  const uint64_t t0 = F.s.tick;
  F.s.motion = URT_MOTION_PATH;
  F.path_until = t0 + 60;
  F.stall_at = t0 + 40;
  F.stall_waits = 30;
  pthread_mutex_unlock(&F.mu);
  submit("def p():\n  textmsg(\"end\")\nend");
  wait_idle();
  int h = fake_find_cmd(&F, URT_CTRL_HALT, 0);
  assert_true(h >= 0);
  assert_int_equal(F.stall_waits, 0);  // the stall happened while the program waited
  assert_true(F.cmd_tick[h] >= t0 + 60);
}

static void test_runner__a_controller_that_stops_ticking_ends_the_wait_for_the_path(
    void **state) {
  // no tick at all after the program's end: the wait gives up after FINISH_STALL_MS (1 s)
  pthread_mutex_lock(&F.mu);
  F.s.motion = URT_MOTION_PATH;
  F.path_until = F.s.tick + 1000000;
  F.stall_at = F.s.tick + 20;
  F.stall_waits = 1 << 30;
  pthread_mutex_unlock(&F.mu);
  submit("def p():\n  textmsg(\"end\")\nend");
  wait_idle();
  int h = fake_find_cmd(&F, URT_CTRL_HALT, 0);
  assert_true(h >= 0);
  assert_int_equal(F.s.motion, URT_MOTION_PATH);
  assert_int_equal(urt_runner_state(R), URT_PROGRAM_STOPPED);
}

static void test_runner__program_before_the_first_tick_waits_for_it(void **state) {
  // urtwin's ports open before the physics publishes its first tick, whose snapshot is all
  // zeros: a program that came then had its first move refused ("robot is not running")
  pthread_mutex_lock(&F.mu);
  F.s.robot_mode = URT_ROBOT_MODE_DISCONNECTED;
  F.running_from = 1;
  pthread_mutex_unlock(&F.mu);
  submit("def home():\n  movej([0,0,0,0,0,0])\nend");
  wait_idle();
  assert_int_equal(F.n_msg, 2);
  assert_key(0, "PROGRAM_XXX_STARTED", "home");
  assert_key(1, "PROGRAM_XXX_STOPPED", "home");
  int k = fake_find_cmd(&F, URT_CTRL_PROGRAM_STATE, 0);
  assert_true(k >= 0);
  assert_true(F.cmd_vm_tick[k] >= 1);  // PLAYING only once the controller has ticked
}

static void test_runner__unknown_function_is_reported_and_nothing_runs(void **state) {
  // URCL's test_program_execution_reports_exception
  submit("def illegal_fun():\n  movej([0,0,0,0,0,0])\n  calldoesntexist()\nend");
  wait_idle();
  assert_int_equal(F.n_msg, 1);
  assert_int_equal(F.msg[0].kind, URT_SCRIPT_MSG_RUNTIME_EXCEPTION);
  assert_int_equal(F.msg[0].line, 3);
  assert_int_equal(F.msg[0].column, 3);
  assert_string_equal(F.msg[0].text, "compile_error_name_not_found:calldoesntexist:");
  assert_int_equal(F.n_cmd, 0);  // nothing submitted, nothing moved
}

static void test_runner__runtime_error_is_reported_then_stopped(void **state) {
  submit("def bad():\n  textmsg(\"a\")\n  x = [1][3]\nend\n");
  wait_idle();
  assert_int_equal(F.n_msg, 4);
  assert_key(0, "PROGRAM_XXX_STARTED", "bad");
  assert_int_equal(F.msg[2].kind, URT_SCRIPT_MSG_RUNTIME_EXCEPTION);
  assert_int_equal(F.msg[2].line, 3);
  assert_key(3, "PROGRAM_XXX_STOPPED", "bad");
}

static void test_runner__new_program_stops_the_running_one(void **state) {
  F.motion_ticks = 1000000;  // a move that never ends by itself
  submit("def first():\n  movej([1, 0, 0, 0, 0, 0])\n  textmsg(\"never\")\nend\n");
  wait_msgs(1);
  submit("def second():\n  textmsg(\"second\")\nend\n");
  wait_idle();
  assert_int_equal(F.n_msg, 5);
  assert_key(0, "PROGRAM_XXX_STARTED", "first");
  assert_key(1, "PROGRAM_XXX_STOPPED", "first");
  assert_key(2, "PROGRAM_XXX_STARTED", "second");
  assert_string_equal(F.msg[3].text, "second");
  assert_key(4, "PROGRAM_XXX_STOPPED", "second");
  // the abort halted the arm before the second program started
  int h = fake_find_cmd(&F, URT_CTRL_HALT, 0);
  int mv = fake_find_cmd(&F, URT_CTRL_MOVEJ, 0);
  assert_true(mv >= 0 && h > mv);
}

static void test_runner__single_statement_aborts_the_program(void **state) {
  F.motion_ticks = 1000000;
  submit("def long():\n  movej([1, 0, 0, 0, 0, 0])\nend\n");
  wait_msgs(1);
  submit("digital_out[2]=True\n");
  wait_idle();
  assert_key(1, "PROGRAM_XXX_STOPPED", "long");
  assert_key(2, "PROGRAM_XXX_STARTED", "statement");
  assert_true(F.s.digital_out & (1u << 2));
}

static void test_runner__sec_program_runs_alongside(void **state) {
  F.motion_ticks = 300;
  F.tick_sleep_us = 1000;  // 0.3 s of real time for the move
  submit("def mover():\n  movej([1, 0, 0, 0, 0, 0])\n  textmsg(\"moved\")\nend\n");
  wait_msgs(1);
  submit("sec setup():\n  set_payload(1.0, [0, 0, 0.1])\n  set_digital_out(5, True)\nend\n");
  wait_idle();
  // the main program was not stopped: it finished its move and printed
  assert_int_equal(F.n_msg, 3);
  assert_key(0, "PROGRAM_XXX_STARTED", "mover");
  assert_string_equal(F.msg[1].text, "moved");
  assert_key(2, "PROGRAM_XXX_STOPPED", "mover");
  int pl = fake_find_cmd(&F, URT_CTRL_SET_PAYLOAD, 0);
  int mv = fake_find_cmd(&F, URT_CTRL_MOVEJ, 0);
  int h = fake_find_cmd(&F, URT_CTRL_HALT, 0);
  assert_true(pl > mv && h > pl);  // ran while the move was under way
  assert_true(F.s.digital_out & (1u << 5));
}

static void test_runner__sec_program_errors_are_secondary_exceptions(void **state) {
  submit("sec s():\n  movej([0, 0, 0, 0, 0, 0])\nend\n");
  wait_idle();
  assert_int_equal(F.n_msg, 1);
  assert_key(0, "SECONDARY_PROGRAM_EXCEPTION_XXX", "movej is not allowed in a secondary program");
  assert_int_equal(fake_find_cmd(&F, URT_CTRL_MOVEJ, 0), -1);
}

static void test_runner__sec_program_computes_past_a_slice_within_its_cycle(void **state) {
  // ~70000 steps, more than a slice (20000 here): a secondary program is not preempted (it has
  // one cycle), only the whole budget (20 slices) stops it
  submit("sec s():\n  i = 0\n  while i < 10000:\n    i = i + 1\n  end\n"
         "  set_standard_digital_out(2, True)\nend\n");
  wait_idle();
  assert_int_equal(F.n_msg, 0);
  assert_true(F.s.digital_out & (1u << 2));
  submit("sec s():\n  while True:\n  end\nend\n");
  wait_idle();
  assert_int_equal(F.n_msg, 1);
  assert_key(0, "SECONDARY_PROGRAM_EXCEPTION_XXX", "Runtime is too much behind");
}

static void test_runner__stop_ends_the_program(void **state) {
  submit("def forever():\n  while True:\n    sync()\n  end\nend\n");
  wait_msgs(1);
  assert_int_equal(urt_runner_state(R), URT_PROGRAM_PLAYING);
  urt_runner_stop(R);
  wait_idle();
  assert_key(1, "PROGRAM_XXX_STOPPED", "forever");
  assert_int_equal(urt_runner_state(R), URT_PROGRAM_STOPPED);
}

static void test_runner__busy_loop_is_too_much_behind(void **state) {
  submit("def spin():\n  x = 0\n  while True: x = 1 end\nend\n");
  wait_idle();
  assert_int_equal(F.n_msg, 3);
  assert_int_equal(F.msg[1].kind, URT_SCRIPT_MSG_RUNTIME_EXCEPTION);
  assert_string_equal(F.msg[1].text, "Runtime is too much behind");
  assert_key(2, "PROGRAM_XXX_STOPPED", "spin");
  // 19 slices preempted, the 20th the error (script_vm.h: TOO_MUCH_BEHIND_SLICES)
  urt_runner_tick_stats_t st;
  urt_runner_tick_stats(R, &st);
  assert_int_equal(st.preempted, 19);
}

static void test_runner__motion_ids_increase_across_programs(void **state) {
  submit("movej([0, 0, 0, 0, 0, 0])\n");
  wait_idle();
  submit("def two():\n  movel(p[0.1, 0, 0.3, 0, 3.14, 0])\n  movej([0, 0, 0, 0, 0, 0])\nend\n");
  wait_idle();
  uint64_t last = 0;
  int n = 0;
  for (int k = 0; k < F.n_cmd; k++) {
    if (is_motion(F.cmd[k].kind)) {
      assert_true(F.cmd[k].id > last);
      last = F.cmd[k].id;
      n++;
    }
  }
  assert_int_equal(n, 3);
}

static void test_runner__submit_refuses_bad_units(void **state) {
  assert_int_equal(urt_runner_submit(R, "", 0), URT_EINVAL);
  assert_int_equal(urt_runner_submit(R, "x", URT_SCRIPT_MAX_TEXT + 1), URT_EINVAL);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_runner__program_reports_started_text_stopped, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__program_before_the_first_tick_waits_for_it, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__last_blended_move_is_waited_for_through_a_host_stall, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__a_controller_that_stops_ticking_ends_the_wait_for_the_path, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__unknown_function_is_reported_and_nothing_runs, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__runtime_error_is_reported_then_stopped, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__new_program_stops_the_running_one, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__single_statement_aborts_the_program, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__sec_program_runs_alongside, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__sec_program_errors_are_secondary_exceptions, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__sec_program_computes_past_a_slice_within_its_cycle, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__stop_ends_the_program, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__busy_loop_is_too_much_behind, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__motion_ids_increase_across_programs, setup, teardown),
      cmocka_unit_test_setup_teardown(test_runner__submit_refuses_bad_units, setup, teardown),
  };
  return cmocka_run_group_tests_name("net/urscript/runner", tests, NULL, NULL);
}
