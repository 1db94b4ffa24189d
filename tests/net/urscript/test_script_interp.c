/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/test_script_interp.c — the interpreter against a fake controller:
 * argument mapping and defaults, blocking in controller ticks, errors. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fake_host.h"
#include "script.h"
#include "test_support.h"

typedef struct run {
  fake_host f;
  urt_script_host_t host;
  uint64_t motion_id;
  us_err err;
  int rc;
} run;

static run R;

static int run_text(const char *text, int64_t budget) {
  us_prog *p = NULL;
  if (urt__us_parse(text, strlen(text), &p, &R.err) != 0) {
    fail_msg("parse: %u:%u %s", R.err.line, R.err.column, R.err.text);
  }
  us_hooks h = {.host = &R.host, .motion_id = &R.motion_id, .step_budget = budget ? budget : 100000,
                .wait_timeout_ms = 1};
  R.rc = urt__us_run(p, &h, &R.err);
  urt__us_prog_free(p);
  return R.rc;
}

static int setup(void **state) {
  fake_init(&R.f, &R.host);
  R.motion_id = 0;
  memset(&R.err, 0, sizeof R.err);
  return 0;
}

static void must_run(const char *text) {
  if (run_text(text, 0) != 0) {
    fail_msg("run: %u:%u %s", R.err.line, R.err.column, R.err.text);
  }
}

static void test_interp__movej_python_urx_arguments(void **state) {
  must_run("movej([0.1, -1.5, 1.2, -1.0, -1.5, 0.0], a=0.1, v=0.05, r=0)\n");
  assert_int_equal(R.f.n_cmd, 1);
  const urt_ctrl_cmd_t *c = &R.f.cmd[0];
  assert_int_equal(c->kind, URT_CTRL_MOVEJ);
  assert_int_equal(c->id, 1);
  assert_near(c->q[1], -1.5, 0);
  assert_near(c->a, 0.1, 0);
  assert_near(c->v, 0.05, 0);
  assert_near(c->t, 0, 0);
  assert_near(c->r, 0, 0);
}

static void test_interp__movej_defaults_and_pose_through_ik(void **state) {
  must_run("movej([0, 0, 0, 0, 0, 0])\nmovej(p[0.1, 0, 0, 0, 0, 0], 2, 3, 4, 0.01)\n");
  assert_int_equal(R.f.n_cmd, 2);
  assert_near(R.f.cmd[0].a, 1.4, 0);
  assert_near(R.f.cmd[0].v, 1.05, 0);
  assert_near(R.f.cmd[1].q[0], 100.1, 1e-12);  // the fake IK adds 100
  assert_near(R.f.cmd[1].a, 2, 0);
  assert_near(R.f.cmd[1].v, 3, 0);
  assert_near(R.f.cmd[1].t, 4, 0);
  assert_near(R.f.cmd[1].r, 0.01, 0);
  assert_int_equal(R.f.cmd[1].id, 2);
}

static void test_interp__movel_defaults(void **state) {
  must_run("movel(p[0.1, 0.2, 0.3, 0, 3.14, 0], t=2)\n");
  const urt_ctrl_cmd_t *c = &R.f.cmd[0];
  assert_int_equal(c->kind, URT_CTRL_MOVEL);
  assert_near(c->pose[2], 0.3, 0);
  assert_near(c->a, 1.2, 0);
  assert_near(c->v, 0.25, 0);
  assert_near(c->t, 2, 0);
}

static void test_interp__movel_with_joints_needs_forward_kinematics(void **state) {
  assert_int_equal(run_text("movel([0, 0, 0, 0, 0, 0])\n", 0), -1);
  assert_string_equal(R.err.text, "Forward kinematics is not available");
  assert_int_equal(R.f.n_cmd, 0);
}

static void test_interp__blocking_motion_waits_for_the_controller(void **state) {
  R.f.motion_ticks = 25;
  must_run("movej([0, 0, 0, 0, 0, 0])\n");
  assert_true(R.f.s.tick >= 25);
  assert_int_equal(R.f.s.motion_done_id, 1);
}

static void test_interp__servoj_blocks_t_and_maps_arguments(void **state) {
  must_run("servoj([0.1, -1.5, 1.2, -1.0, -1.5, 0.0], a=0.1, v=0.05, t=0.008, lookahead_time=0.05, gain=500)\n");
  const urt_ctrl_cmd_t *c = &R.f.cmd[0];
  assert_int_equal(c->kind, URT_CTRL_SERVOJ);
  assert_near(c->t, 0.008, 0);
  assert_near(c->lookahead_time, 0.05, 0);
  assert_near(c->gain, 500, 0);
  assert_int_equal(R.f.s.tick, 4);  // 8 ms at 2 ms per tick
  setup(NULL);
  must_run("servoj([0, 0, 0, 0, 0, 0])\n");
  assert_near(R.f.cmd[0].t, 0.002, 0);
  assert_near(R.f.cmd[0].lookahead_time, 0.1, 0);
  assert_near(R.f.cmd[0].gain, 300, 0);
  assert_int_equal(R.f.s.tick, 1);
}

static void test_interp__speedj_with_t_blocks_t(void **state) {
  must_run("speedj([0.1, 0, 0, 0, 0, 0], 0.5, 0.1)\n");
  assert_int_equal(R.f.cmd[0].kind, URT_CTRL_SPEEDJ);
  assert_near(R.f.cmd[0].q[0], 0.1, 0);
  assert_near(R.f.cmd[0].a, 0.5, 0);
  assert_near(R.f.cmd[0].t, 0.1, 0);
  assert_int_equal(R.f.s.tick, 50);
}

/* the slider scales speedj (core/motion_speedj.cpp): its t is motion time, which advances at
 * the controller's speed_scaling per second, so at 0.25 a t = 0.1 s speedj blocks 200 ticks */
static void test_interp__speedj_t_is_motion_time_under_the_slider(void **state) {
  R.f.s.speed_scaling = 0.25;
  R.f.s.motion_rate = 0.25;
  must_run("speedj([0.1, 0, 0, 0, 0, 0], 0.5, 0.1)\nspeedj([0.1, 0, 0, 0, 0, 0], 0.5, 0.002)\n");
  assert_int_equal(R.f.n_cmd, 2);
  assert_int_equal(R.f.s.tick, 204);
}

/* a stream of speedj keeps its motion time: at 0.33, 99 speedj(qd, a, 0.002) take 300 ticks
 * (99 / 0.33), not 99 · ceil(1 / 0.33) = 396 (each at 0.33·qd: 1.32 times the distance);
 * a pause between them (sync) starts the next one afresh */
static void test_interp__a_speedj_stream_keeps_its_motion_time_under_the_slider(void **state) {
  R.f.s.speed_scaling = 0.33;
  R.f.s.motion_rate = 0.33;
  must_run("i = 0\nwhile i < 99:\n  speedj([0.1, 0, 0, 0, 0, 0], 0.5, 0.002)\n  i = i + 1\nend\n");
  assert_int_equal(R.f.n_cmd, 99);
  print_message("99 speedj at 0.33: %llu ticks\n", (unsigned long long)R.f.s.tick);
  assert_true(R.f.s.tick >= 300 && R.f.s.tick <= 301);
  setup(NULL);
  R.f.s.speed_scaling = 0.33;
  R.f.s.motion_rate = 0.33;
  must_run("speedj([0.1, 0, 0, 0, 0, 0], 0.5, 0.002)\nsync()\nspeedj([0.1, 0, 0, 0, 0, 0], 0.5, 0.002)\n");
  assert_int_equal(R.f.s.tick, 4 + 1 + 4);
}

static void test_interp__stopj_and_stopl(void **state) {
  must_run("stopj(2)\nstopl(10)\n");
  assert_int_equal(R.f.cmd[0].kind, URT_CTRL_STOPJ);
  assert_near(R.f.cmd[0].a, 2, 0);
  assert_int_equal(R.f.cmd[1].kind, URT_CTRL_STOPL);
  assert_near(R.f.cmd[1].a_rot, 10, 0);
}

static void test_interp__sleep_counts_controller_ticks(void **state) {
  must_run("sleep(0.1)\n");
  assert_int_equal(R.f.s.tick, 50);
  setup(NULL);
  must_run("sync()\nsync()\n");
  assert_int_equal(R.f.s.tick, 2);
}

static void test_interp__io_and_settings(void **state) {
  must_run("digital_out[2]=True\nset_standard_digital_out(3, True)\n"
           "set_configurable_digital_out(1, True)\nset_tool_digital_out(1, True)\n"
           "set_analog_out(1, 0.25)\nset_tcp(p[0.0, 0.0, 0.1, 0, 0, 0])\n"
           "set_payload(1.5, (0, 0, 0.05))\n"
           "if not get_standard_digital_out(2) or not digital_out[3] then\n  halt\nend\n"
           "set_digital_out(2, False)\n");
  assert_int_equal(R.f.cmd[0].kind, URT_CTRL_SET_DIGITAL_OUT);
  assert_int_equal(R.f.cmd[0].index, 2);
  assert_near(R.f.cmd[0].value, 1, 0);
  assert_int_equal(R.f.cmd[1].index, 3);
  assert_int_equal(R.f.cmd[2].index, 9);
  assert_int_equal(R.f.cmd[3].index, 17);
  assert_int_equal(R.f.cmd[4].kind, URT_CTRL_SET_ANALOG_OUT);
  assert_near(R.f.cmd[4].value, 0.25, 0);
  assert_int_equal(R.f.cmd[5].kind, URT_CTRL_SET_TCP);
  assert_near(R.f.cmd[5].pose[2], 0.1, 0);
  assert_int_equal(R.f.cmd[6].kind, URT_CTRL_SET_PAYLOAD);
  assert_near(R.f.cmd[6].value, 1.5, 0);
  assert_near(R.f.cmd[6].pose[2], 0.05, 0);
  assert_int_equal(R.f.n_cmd, 8);  // the halt did not happen: the reads saw the outputs
  assert_int_equal(R.f.s.digital_out, (1u << 3) | (1u << 9) | (1u << 17));
}

static void test_interp__textmsg_concatenates(void **state) {
  R.f.s.tcp_pose[0] = 0.605825;
  must_run("textmsg(\"log \", get_actual_tcp_pose())\ntextmsg(1)\ntextmsg(str_cat(\"a\", 2.5), True)\n");
  assert_int_equal(R.f.n_msg, 3);
  assert_int_equal(R.f.msg[0].kind, URT_SCRIPT_MSG_TEXT);
  assert_string_equal(R.f.msg[0].text, "log p[0.605825,0,0,0,0,0]");
  assert_string_equal(R.f.msg[1].text, "1");
  assert_string_equal(R.f.msg[2].text, "a2.5True");
}

static void test_interp__functions_scopes_and_control_flow(void **state) {
  must_run("def prog():\n"
           "  global n = 0\n"
           "  def bump(k=1):\n"
           "    global n\n"
           "    n = n + k\n"
           "    local tmp = n * 2\n"
           "    return tmp\n"
           "  end\n"
           "  def fact(x):\n"
           "    if x <= 1: return 1 end\n"
           "    return x * fact(x - 1)\n"
           "  end\n"
           "  i = 0\n"
           "  while True:\n"
           "    i = i + 1\n"
           "    if i > 10: break end\n"
           "    if i % 2 == 0: continue end\n"
           "    r = bump(k=i)\n"
           "  end\n"
           "  l = [1, 2, 3]\n"
           "  l[1] = fact(5)\n"
           "  q = p[0, 0, 0, 0, 0, 0]\n"
           "  q[2] = 0.5\n"
           "  textmsg(n, r)\n"
           "  textmsg(l, q)\n"
           "  textmsg(floor(2.7) + ceil(0.2), sqrt(16.0))\n"
           "  textmsg(7 / 2, 7 % 3)\n"
           "end\n");
  assert_string_equal(R.f.msg[0].text, "2550");  // 1+3+5+7+9 = 25, returns 50
  assert_string_equal(R.f.msg[1].text, "[1,120,3]p[0,0,0.5,0,0,0]");
  assert_string_equal(R.f.msg[2].text, "34");
  assert_string_equal(R.f.msg[3].text, "3.51");
}

static void test_interp__free_variable_in_a_function_is_the_global(void **state) {
  // UR's scoping rules: a free name is the program's variable if one exists, `local` masks it,
  // and a name no program variable has stays local to the call
  must_run("def prog():\n"
           "  count = 0\n"
           "  def bump():\n"
           "    count = count + 1\n"
           "    fresh = 7\n"
           "  end\n"
           "  def shadow():\n"
           "    local count = 100\n"
           "    count = count + 1\n"
           "  end\n"
           "  fresh = 1\n"
           "  bump()\n"
           "  bump()\n"
           "  shadow()\n"
           "  textmsg(count, fresh)\n"
           "end\n");
  assert_string_equal(R.f.msg[0].text, "27");
}

static void test_interp__inverse_kinematics_honours_qnear(void **state) {
  must_run("q = get_inverse_kin(p[0.1, 0, 0, 0, 0, 0], qnear=[1, 2, 3, 4, 5, 6])\n"
           "textmsg(q)\n"
           "textmsg(get_inverse_kin_has_solution(p[0.1, 0, 0, 0, 0, 0]))\n");
  assert_string_equal(R.f.msg[0].text, "[101.1,102,103,104,105,106]");  // fake IK: pose+100+qnear
  assert_string_equal(R.f.msg[1].text, "True");
  // tcp= is honoured: test_script_builtins_client.c checks it against a hand-composed transform
}

static void test_interp__matrices_pose_sub_and_mode_commands(void **state) {
  // a matrix value indexes as m[i, j] and m[i] (row); a list is not a matrix
  assert_int_equal(run_text("l = [1, 2]\nx = l[0, 1]\n", 0), -1);
  assert_non_null(strstr(R.err.text, "no [row, column]"));
  setup(state);
  must_run("d = pose_sub(p[0.3, 0.2, 0.1, 0, 0, 0.5], p[0.1, 0.1, 0.1, 0, 0, 0.2])\n"
           "textmsg(pose_add(d, p[0.1, 0.1, 0.1, 0, 0, 0.2]))\n"
           "force_mode_set_damping(0.1)\n"
           "force_mode(p[0, 0, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0], [0, 0, -5, 0, 0, 0], 2, [0.1, 0.1, 0.1, 0.5, 0.5, 0.5])\n"
           "force_mode_set_gain_scaling(0.5)\n"
           "end_force_mode()\n"
           "set_gravity([0, 0, 9.82])\n"
           "set_target_payload(1.5, [0, 0, 0.05])\n");
  assert_string_equal(R.f.msg[0].text, "p[0.3,0.2,0.1,0,0,0.5]");
  int k = fake_find_cmd(&R.f, URT_CTRL_FORCE_MODE, 0);
  assert_true(k >= 0);
  assert_int_equal(R.f.cmd[k].index, 2);
  assert_near(R.f.cmd[k].q[2], 1, 0);
  assert_near(R.f.cmd[k].tau[2], -5, 0);
  assert_near(R.f.cmd[k].qd[3], 0.5, 0);
  assert_near(R.f.cmd[k].value, 0.1, 0);  // damping set before
  assert_near(R.f.cmd[k].gain, 1.0, 0);   // UR's default gain scaling
  int k2 = fake_find_cmd(&R.f, URT_CTRL_FORCE_MODE, k + 1);  // the active one takes the scaling
  assert_true(k2 > k);
  assert_near(R.f.cmd[k2].gain, 0.5, 0);
  assert_true(fake_find_cmd(&R.f, URT_CTRL_FORCE_MODE_END, k2) > k2);
  int g = fake_find_cmd(&R.f, URT_CTRL_SET_GRAVITY, 0);
  assert_near(R.f.cmd[g].pose[2], -9.82, 0);  // away from the earth → the acceleration
  int pl = fake_find_cmd(&R.f, URT_CTRL_SET_PAYLOAD, 0);
  assert_near(R.f.cmd[pl].value, 1.5, 0);
  assert_near(R.f.cmd[pl].pose[2], 0.05, 0);
  setup(state);
  assert_int_equal(run_text("set_target_payload(1, [0, 0, 0], [0.1, 0, 0, 0, 0, 0])\n", 0), 0);
  pl = fake_find_cmd(&R.f, URT_CTRL_SET_PAYLOAD, 0);
  assert_near(R.f.cmd[pl].tau[0], 0.1, 0);  // the inertia is carried, not refused
  setup(state);
  assert_int_equal(run_text("set_target_payload(1, [0, 0, 0], [-0.1, 0, 0, 0, 0, 0])\n", 0), -1);
  assert_non_null(strstr(R.err.text, "must not be negative"));
}

static void test_interp__halt_inside_a_function_ends_the_program_normally(void **state) {
  must_run("def stop_here():\n  halt\nend\ntextmsg(\"a\")\nx = 1 + stop_here()\ntextmsg(\"b\")\n");
  assert_int_equal(R.f.n_msg, 1);
  assert_int_equal(R.err.kind, US_ERR_NONE);
}

static void test_interp__pose_functions(void **state) {
  must_run("a = p[0.1, 0.2, 0.3, 0, 0, 1.5707963267948966]\n"
           "b = pose_trans(a, p[1, 0, 0, 0, 0, 0])\n"
           "c = pose_trans(a, pose_inv(a))\n"
           "textmsg(b)\ntextmsg(norm(c), pose_add(a, p[1, 1, 1, 0, 0, 0]))\n");
  assert_string_equal(R.f.msg[0].text, "p[0.1,1.2,0.3,0,0,1.5708]");
  assert_non_null(strstr(R.f.msg[1].text, "p[1.1,1.2,1.3,0,0,1.5708]"));
}

static void test_interp__lists_are_vectors(void **state) {
  // URCL's external-control script: extrapolation, spline coefficients, norm of a difference
  must_run("q = [1, 2.5, 0, 0, 0, 0]\n"
           "qd = [0.5, -1, 0, 0, 0, 2]\n"
           "textmsg(q + qd * 0.002)\n"
           "textmsg((-3 * q + q * 3 - qd * 2 * 1.5) / pow(1.5, 2))\n"
           "textmsg(norm([3, 4] - [0, 0]), -[1, -2.5])\n"
           "textmsg([1, 2] + [3, 4], [6, 4] / 2)\n");
  assert_string_equal(R.f.msg[0].text, "[1.001,2.498,0,0,0,0.004]");
  assert_string_equal(R.f.msg[1].text, "[-0.666667,1.33333,0,0,0,-2.66667]");
  assert_string_equal(R.f.msg[2].text, "5[-1,2.5]");
  assert_string_equal(R.f.msg[3].text, "[4,6][3,2]");
  for (int k = 0; k < 3; k++) {
    static const char *bad[] = {"x = [1, 2] + [1, 2, 3]\n", "x = [1, 2] + 1\n", "x = 2 / [1, 2]\n"};
    setup(state);
    assert_int_equal(run_text(bad[k], 0), -1);
    assert_int_equal(R.err.kind, US_ERR_RUNTIME);
    assert_non_null(strstr(R.err.text, "Type error"));
  }
}

static void test_interp__loop_that_never_yields_is_too_much_behind(void **state) {
  assert_int_equal(run_text("def f():\n  x = 0\n  while True:\n    x = 1\n  end\nend\n", 10000), -1);
  assert_int_equal(R.err.kind, US_ERR_RUNTIME);
  assert_string_equal(R.err.text, "Runtime is too much behind");
  assert_int_equal(R.err.line, 4);
}

static void test_interp__loop_with_sync_runs_until_stopped(void **state) {
  // the budget resets at every tick: this runs 300 ticks without complaint
  must_run("i = 0\nwhile i < 300:\n  j = 0\n  while j < 20:\n    j = j + 1\n  end\n  i = i + 1\n  sync()\nend\n");
  assert_int_equal(R.f.s.tick, 300);
}

static void test_interp__refused_motion_stops_the_program(void **state) {
  R.f.refuse_motion = true;
  assert_int_equal(run_text("movej([0, 0, 0, 0, 0, 0])\ntextmsg(\"after\")\n", 0), -1);
  assert_int_equal(R.err.kind, US_ERR_RUNTIME);
  assert_non_null(strstr(R.err.text, "movej: motion refused or aborted (protective stop"));
  assert_int_equal(R.err.line, 1);
  assert_int_equal(R.err.column, 1);
  assert_int_equal(R.f.n_msg, 0);
}

static void test_interp__protective_stop_pauses_and_play_runs_the_motion_again(void **state) {
  // a movel out of the workspace: the stop pauses the program (no runtime error); the unlock
  // at tick 50 leaves it paused; `play` at tick 80 resumes it, and the movel runs again
  R.f.s.program_state = URT_PROGRAM_PLAYING;
  R.f.pause_stops = 1;
  R.f.unlock_at = 50;
  R.f.resume_at = 80;
  must_run("movel(p[10, 0, 0, 0, 0, 0])\ntextmsg(\"after\")\n");
  assert_int_equal(R.f.n_cmd, 2);
  assert_int_equal(R.f.cmd[0].kind, URT_CTRL_MOVEL);
  assert_int_equal(R.f.cmd[1].kind, URT_CTRL_MOVEL);
  assert_int_equal(R.f.cmd_vm_tick[1], 80);  // not at the unlock: at the resume
  assert_true(R.f.cmd[1].id > R.f.cmd[0].id);
  assert_near(R.f.cmd[1].pose[0], 10, 0);
  assert_int_equal(R.f.n_msg, 1);
  assert_string_equal(R.f.msg[0].text, "after");
}

static void test_interp__a_stop_that_does_not_pause_is_a_runtime_error(void **state) {
  // the same stop with the program not playing (nothing paused it): the refusal ends it
  R.f.pause_stops = 1;
  R.f.unlock_at = 50;
  assert_int_equal(run_text("movel(p[10, 0, 0, 0, 0, 0])\n", 0), -1);
  assert_non_null(strstr(R.err.text, "movel: motion refused or aborted (no inverse kinematics"));
}

static void test_interp__motion_while_powered_off_is_refused(void **state) {
  R.f.s.robot_mode = URT_ROBOT_MODE_POWER_OFF;
  R.f.motion_ticks = 1000000;  // the fake would never finish it: the runner must not hang
  assert_int_equal(run_text("movej([0, 0, 0, 0, 0, 0])\n", 0), -1);
  assert_string_equal(R.err.text, "movej: motion refused (robot is not running; robot mode 3)");
}

static void test_interp__runtime_errors_carry_line_and_column(void **state) {
  assert_int_equal(run_text("l = [1, 2]\nx = l[5]\n", 0), -1);
  assert_string_equal(R.err.text, "Index out of bounds: 5 (length 2)");
  assert_int_equal(R.err.line, 2);
  assert_int_equal(R.err.column, 7);
  setup(NULL);
  assert_int_equal(run_text("x = 1 / 0\n", 0), -1);
  assert_string_equal(R.err.text, "Division by zero");
  setup(NULL);
  assert_int_equal(run_text("movej([1, 2])\n", 0), -1);
  assert_non_null(strstr(R.err.text, "Type error"));
  assert_int_equal(R.f.n_cmd, 0);
  setup(NULL);
  assert_int_equal(run_text("movej([0,0,0,0,0,0], speed=1)\n", 0), -1);
  assert_string_equal(R.err.text, "Type error: movej has no parameter speed");
}

static void test_interp__full_command_ring_is_retried_on_later_ticks(void **state) {
  R.f.full_for = 3;
  must_run("set_digital_out(1, True)\n");
  assert_int_equal(R.f.n_cmd, 1);
  assert_int_equal(R.f.s.tick, 3);
}

static void test_interp__secondary_program_must_not_block(void **state) {
  us_prog *p = NULL;
  const char *text = "sec s():\n  set_digital_out(1, True)\n  sleep(1)\nend\n";
  assert_int_equal(urt__us_parse(text, strlen(text), &p, &R.err), 0);
  us_hooks h = {.host = &R.host, .motion_id = &R.motion_id, .step_budget = 1000, .wait_timeout_ms = 1};
  assert_int_equal(urt__us_run(p, &h, &R.err), -1);
  urt__us_prog_free(p);
  assert_string_equal(R.err.text, "Blocking call in a secondary program");
  assert_int_equal(R.err.line, 3);
  assert_int_equal(R.f.n_cmd, 1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_interp__movej_python_urx_arguments, setup),
      cmocka_unit_test_setup(test_interp__movej_defaults_and_pose_through_ik, setup),
      cmocka_unit_test_setup(test_interp__movel_defaults, setup),
      cmocka_unit_test_setup(test_interp__movel_with_joints_needs_forward_kinematics, setup),
      cmocka_unit_test_setup(test_interp__blocking_motion_waits_for_the_controller, setup),
      cmocka_unit_test_setup(test_interp__servoj_blocks_t_and_maps_arguments, setup),
      cmocka_unit_test_setup(test_interp__speedj_with_t_blocks_t, setup),
      cmocka_unit_test_setup(test_interp__speedj_t_is_motion_time_under_the_slider, setup),
      cmocka_unit_test_setup(test_interp__a_speedj_stream_keeps_its_motion_time_under_the_slider, setup),
      cmocka_unit_test_setup(test_interp__stopj_and_stopl, setup),
      cmocka_unit_test_setup(test_interp__sleep_counts_controller_ticks, setup),
      cmocka_unit_test_setup(test_interp__io_and_settings, setup),
      cmocka_unit_test_setup(test_interp__textmsg_concatenates, setup),
      cmocka_unit_test_setup(test_interp__functions_scopes_and_control_flow, setup),
      cmocka_unit_test_setup(test_interp__free_variable_in_a_function_is_the_global, setup),
      cmocka_unit_test_setup(test_interp__inverse_kinematics_honours_qnear, setup),
      cmocka_unit_test_setup(test_interp__matrices_pose_sub_and_mode_commands, setup),
      cmocka_unit_test_setup(test_interp__halt_inside_a_function_ends_the_program_normally, setup),
      cmocka_unit_test_setup(test_interp__pose_functions, setup),
      cmocka_unit_test_setup(test_interp__lists_are_vectors, setup),
      cmocka_unit_test_setup(test_interp__loop_that_never_yields_is_too_much_behind, setup),
      cmocka_unit_test_setup(test_interp__loop_with_sync_runs_until_stopped, setup),
      cmocka_unit_test_setup(test_interp__refused_motion_stops_the_program, setup),
      cmocka_unit_test_setup(test_interp__protective_stop_pauses_and_play_runs_the_motion_again, setup),
      cmocka_unit_test_setup(test_interp__a_stop_that_does_not_pause_is_a_runtime_error, setup),
      cmocka_unit_test_setup(test_interp__motion_while_powered_off_is_refused, setup),
      cmocka_unit_test_setup(test_interp__runtime_errors_carry_line_and_column, setup),
      cmocka_unit_test_setup(test_interp__full_command_ring_is_retried_on_later_ticks, setup),
      cmocka_unit_test_setup(test_interp__secondary_program_must_not_block, setup),
  };
  return cmocka_run_group_tests_name("net/urscript/script_interp", tests, NULL, NULL);
}
