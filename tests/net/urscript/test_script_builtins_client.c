/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/test_script_builtins_client.c — the state and kinematics builtins with the
 * UR5's own kinematics behind the fake controller (as the emulator's host has them: the active
 * TCP offset applied): get_inverse_kin round trips, its qnear choosing the branch, its tcp and
 * get_forward_kin's against a transform composed by hand; the settings as the commands they
 * queue; the getters as the snapshot holds them. */
#include <math.h>

#include "script_run.h"
#include "test_model.h"
#include "urt/controller.h"

static script_run R;
static urt_model_t *M;

static int ik(void *ctx, const double pose[6], const double qnear[URT_NJ], double q[URT_NJ]) {
  return urt_ctrl_inverse_kinematics_tcp(M, R.f.s.tcp_offset, pose, qnear, q);
}

static int fk(void *ctx, const double q[URT_NJ], double pose[6]) {
  urt_ctrl_forward_kinematics_tcp(M, R.f.s.tcp_offset, q, pose);
  return 0;
}

static const urt_model_t *model(void *ctx) { return M; }

static int setup(void **state) {
  memset(&R, 0, sizeof R);
  fake_init(&R.f, &R.host);
  R.host.inverse_kinematics = ik;
  R.host.forward_kinematics = fk;
  R.host.model = model;
  return 0;
}

static int group_setup(void **state) {
  M = urt_test_model(NULL);
  return 0;
}

static int group_teardown(void **state) {
  urt_model_free(M);
  return 0;
}

/* the script's helper: the largest difference of two 6-vectors */
#define MAXDIFF "def maxdiff(a, b):\n  m = 0\n  i = 0\n  while i < 6:\n    d = fabs(a[i] - b[i])\n" \
                "    if d > m:\n      m = d\n    end\n    i = i + 1\n  end\n  return m\nend\n"

static double msg_num(int k) {
  double x[1] = {0};
  assert_int_equal(sr_nums(&R, k, x, 1), 1);
  return x[0];
}

static void test_client__inverse_kin_round_trip(void **state) {
  sr_must(&R, MAXDIFF "q0 = [0.3, -1.2, 1.4, -1.7, -1.6, 0.2]\n"
                      "x = get_forward_kin(q0)\n"
                      "textmsg(maxdiff(get_inverse_kin(x, q0), q0))\n"
                      "textmsg(maxdiff(get_forward_kin(get_inverse_kin(x, qnear=q0)), x))\n");
  assert_true(msg_num(0) < 1e-6);
  assert_true(msg_num(1) < 1e-6);
}

static void test_client__qnear_chooses_the_branch(void **state) {
  // elbow up and elbow down reach the same pose: each qnear gets its own branch back
  const double q0[6] = {0.3, -1.2, 1.4, -1.7, -1.6, 0.2};
  double x[6], q1[6], zero[6] = {0};
  urt_ctrl_forward_kinematics_tcp(M, zero, q0, x);
  double guess[6] = {0.3, -0.2, -1.4, -3.0, -1.6, 0.2};  // the elbow flipped
  assert_int_equal(urt_ctrl_inverse_kinematics_tcp(M, zero, x, guess, q1), 0);
  // another branch: far from q0 in joint space, the same pose by the model
  double far = 0, y[6];
  for (int j = 0; j < 6; j++) far = fmax(far, fabs(q1[j] - q0[j]));
  assert_true(far > 0.5);
  urt_ctrl_forward_kinematics_tcp(M, zero, q1, y);
  for (int j = 0; j < 3; j++) assert_true(fabs(y[j] - x[j]) < 1e-9);
  char text[1024];
  snprintf(text, sizeof text,
           MAXDIFF "x = p[%.17g,%.17g,%.17g,%.17g,%.17g,%.17g]\n"
                   "a = [%.17g,%.17g,%.17g,%.17g,%.17g,%.17g]\nb = [%.17g,%.17g,%.17g,%.17g,%.17g,%.17g]\n"
                   "textmsg(maxdiff(get_inverse_kin(x, qnear=a), a))\n"
                   "textmsg(maxdiff(get_inverse_kin(x, qnear=b), b))\n"
                   "textmsg(get_inverse_kin_has_solution(x))\n"
                   "textmsg(get_inverse_kin_has_solution(p[3, 0, 0, 0, 0, 0]))\n",
           x[0], x[1], x[2], x[3], x[4], x[5], q0[0], q0[1], q0[2], q0[3], q0[4], q0[5], q1[0],
           q1[1], q1[2], q1[3], q1[4], q1[5]);
  sr_must(&R, text);
  assert_true(msg_num(0) < 1e-6);
  assert_true(msg_num(1) < 1e-6);
  assert_string_equal(R.f.msg[2].text, "True");
  assert_string_equal(R.f.msg[3].text, "False");  // 3 m away: out of reach
  assert_int_not_equal(sr_run(&R, "get_inverse_kin(p[3, 0, 0, 0, 0, 0])\n"), 0);
  assert_non_null(strstr(R.err.text, "no solution"));
}

static void test_client__tcp_argument_against_a_hand_composed_transform(void **state) {
  // an active TCP and another one given as the argument: the flange pose F by the model with a
  // zero TCP, then F ∘ T composed here by hand (position F.p + R_F T.p)
  memcpy(R.f.s.tcp_offset, (double[6]){0, 0, 0.05, 0, 0, 0}, sizeof R.f.s.tcp_offset);
  const double q0[6] = {0.3, -1.2, 1.4, -1.7, -1.6, 0.2}, T[3] = {0.02, -0.01, 0.1};
  double F[6], zero[6] = {0}, Rf[9];
  urt_ctrl_forward_kinematics_tcp(M, zero, q0, F);
  double th = sqrt(F[3] * F[3] + F[4] * F[4] + F[5] * F[5]), k[3] = {F[3] / th, F[4] / th, F[5] / th};
  double c = cos(th), s = sin(th), v = 1 - c;
  double A[9] = {c + k[0] * k[0] * v, k[0] * k[1] * v - k[2] * s, k[0] * k[2] * v + k[1] * s,
                 k[1] * k[0] * v + k[2] * s, c + k[1] * k[1] * v, k[1] * k[2] * v - k[0] * s,
                 k[2] * k[0] * v - k[1] * s, k[2] * k[1] * v + k[0] * s, c + k[2] * k[2] * v};
  memcpy(Rf, A, sizeof A);
  double want[3];
  for (int i = 0; i < 3; i++) want[i] = F[i] + Rf[3 * i] * T[0] + Rf[3 * i + 1] * T[1] + Rf[3 * i + 2] * T[2];
  sr_must(&R, MAXDIFF "q0 = [0.3, -1.2, 1.4, -1.7, -1.6, 0.2]\n"
                      "t = p[0.02, -0.01, 0.1, 0, 0, 0]\n"
                      "x = get_forward_kin(q0, tcp=t)\n"
                      "textmsg(x)\n"
                      "textmsg(maxdiff(get_inverse_kin(x, q0, tcp=t), q0))\n"
                      "textmsg(maxdiff(get_forward_kin(q0, p[0, 0, 0.05, 0, 0, 0]), get_forward_kin(q0)))\n"
                      "textmsg(point_dist(get_forward_kin(q0, p[0,0,0,0,0,0]), get_forward_kin(q0)))\n");
  double x[6];
  assert_int_equal(sr_nums(&R, 0, x, 6), 6);
  for (int i = 0; i < 3; i++) assert_true(fabs(x[i] - want[i]) < 1e-5);
  assert_true(msg_num(1) < 1e-6);
  assert_true(msg_num(2) < 1e-12);          // the active TCP given explicitly: the same pose
  assert_true(fabs(msg_num(3) - 0.05) < 1e-6);  // the flange is the active TCP minus 5 cm
}

static void test_client__flange_pose_and_getters(void **state) {
  R.f.s.period = 0.008;
  memcpy(R.f.s.tcp_offset, (double[6]){0, 0, 0.1, 0, 0, 0}, sizeof R.f.s.tcp_offset);
  memcpy(R.f.s.tcp_pose, (double[6]){0.3, 0.2, 0.5, 0, 0, 0}, sizeof R.f.s.tcp_pose);
  R.f.s.payload_mass = 1.25;
  memcpy(R.f.s.payload_cog, (double[3]){0, 0.01, 0.04}, sizeof R.f.s.payload_cog);
  R.f.s.tcp_speed_target[2] = 0.07;
  R.f.s.qdd_target[1] = -0.5;
  R.f.s.tau[3] = 4.5;
  R.f.s.q[5] = 0.25;
  R.f.s.q_target[5] = 0.5;  // get_joint_positions() is the target, not the encoders
  R.f.s.temperature[2] = 41.5;
  // get_actual_tool_flange_pose is the forward kinematics of the actual joints
  // (script_builtins_state.c), which this fake's snapshot does not keep consistent
  sr_must(&R, "textmsg(get_steptime())\n"
              "textmsg(get_target_payload())\ntextmsg(get_target_payload_cog())\n"
              "textmsg(get_target_tcp_speed())\ntextmsg(get_target_joint_accelerations())\n"
              "textmsg(get_joint_torques())\ntextmsg(get_joint_positions())\ntextmsg(get_joint_temp(2))\n");
  const char *want[] = {"0.008", "1.25", "[0,0.01,0.04]",
                        "[0,0,0.07,0,0,0]", "[0,-0.5,0,0,0,0]", "[0,0,0,4.5,0,0]",
                        "[0,0,0,0,0,0.5]", "41.5"};
  for (int k = 0; k < 8; k++) assert_string_equal(R.f.msg[k].text, want[k]);
}

static void test_client__inputs_force_accelerometer(void **state) {
  R.f.s.digital_in = 1u << 9 | 1u << 17;  // configurable input 1, tool input 1
  memcpy(R.f.s.tcp_force, (double[6]){3, 4, 12, 100, 100, 100}, sizeof R.f.s.tcp_force);
  memcpy(R.f.s.tool_accel, (double[3]){0.1, -0.2, 9.81}, sizeof R.f.s.tool_accel);
  sr_must(&R, "textmsg(get_configurable_digital_in(1), get_configurable_digital_in(0))\n"
              "textmsg(get_tool_digital_in(1), get_tool_digital_in(0))\n"
              "textmsg(force())\ntextmsg(get_tool_accelerometer_reading())\n");
  assert_string_equal(R.f.msg[0].text, "TrueFalse");
  assert_string_equal(R.f.msg[1].text, "TrueFalse");
  assert_string_equal(R.f.msg[2].text, "13");  // |(3, 4, 12)|; the torques do not count
  assert_string_equal(R.f.msg[3].text, "[0.1,-0.2,9.81]");
  assert_int_not_equal(sr_run(&R, "get_tool_digital_in(2)\n"), 0);
}

/* the fake's joints move every tick: q[0] = tick / 1000 */
static uint64_t moving_wait_tick(void *ctx, uint64_t after, int timeout_ms) {
  pthread_mutex_lock(&R.f.mu);
  R.f.s.q[0] = (double)(R.f.s.tick + 1) / 1000.0;
  pthread_mutex_unlock(&R.f.mu);
  return fake_wait_tick(ctx, after, timeout_ms);
}

static void test_client__joint_positions_history(void **state) {
  R.host.wait_tick = moving_wait_tick;
  sr_must(&R, "sleep(0.04)\n"  // 20 ticks
              "textmsg(get_actual_joint_positions_history()[0])\n"
              "textmsg(get_actual_joint_positions_history(5)[0])\n"
              "textmsg(get_actual_joint_positions_history(steps=20)[0])\n");
  assert_string_equal(R.f.msg[0].text, "0.02");
  assert_string_equal(R.f.msg[1].text, "0.015");
  assert_string_equal(R.f.msg[2].text, "0");
  assert_int_not_equal(sr_run(&R, "get_actual_joint_positions_history(21)\n"), 0);  // before tick 0
  memset(&R.err, 0, sizeof R.err);
  assert_int_not_equal(sr_run(&R, "sleep(0.2)\nget_actual_joint_positions_history(90)\n"), 0);
  assert_non_null(strstr(R.err.text, "older than the controller keeps"));
}

static void test_client__safety_limits(void **state) {
  sr_must(&R, "textmsg(is_within_safety_limits([0, -1.5, 1, 0, 0, 0]))\n"
              "textmsg(is_within_safety_limits([0, 0, 0, 0, 0, 7]))\n"
              "textmsg(is_within_safety_limits(get_forward_kin([0.3, -1.2, 1.4, -1.7, -1.6, 0.2])))\n");
  assert_string_equal(R.f.msg[0].text, "True");
  assert_string_equal(R.f.msg[1].text, "False");  // 7 rad is past the UR5's ±2π
  assert_string_equal(R.f.msg[2].text, "True");
}

static void test_client__gravity_and_target_payload_commands(void **state) {
  sr_must(&R, "set_gravity([0, 0, 9.82])\n"
              "set_target_payload(1.5, [0, 0.01, 0.05], [0, 0, 0, 0, 0, 0], 0.5)\n");
  assert_int_equal(R.f.n_cmd, 2);
  assert_int_equal(R.f.cmd[0].kind, URT_CTRL_SET_GRAVITY);
  assert_true(R.f.cmd[0].pose[2] == -9.82 && R.f.cmd[0].pose[0] == 0);  // towards the earth
  assert_int_equal(R.f.cmd[1].kind, URT_CTRL_SET_PAYLOAD);
  assert_true(R.f.cmd[1].value == 1.5 && R.f.cmd[1].pose[1] == 0.01 && R.f.cmd[1].pose[2] == 0.05);
  assert_true(R.f.cmd[1].t == 0.5);  // the transition time rides along
  sr_must(&R, "set_tool_voltage(12)\n");
  assert_int_equal(R.f.cmd[2].kind, URT_CTRL_SET_TOOL_VOLTAGE);
  assert_true(R.f.cmd[2].value == 12);
  assert_int_not_equal(sr_run(&R, "set_tool_voltage(5)\n"), 0);
  memset(&R.err, 0, sizeof R.err);
  assert_int_not_equal(sr_run(&R, "set_target_payload(-1, [0, 0, 0])\n"), 0);
  memset(&R.err, 0, sizeof R.err);
  // the inertia rides in tau (Ixx Iyy Izz Ixy Ixz Iyz about the CoG), mounted by the controller
  sr_must(&R, "set_target_payload(1, [0, 0, 0.1], [0.01, 0.02, 0.03, 0.001, 0, 0])\n");
  assert_int_equal(R.f.cmd[3].kind, URT_CTRL_SET_PAYLOAD);
  assert_true(R.f.cmd[3].tau[0] == 0.01 && R.f.cmd[3].tau[1] == 0.02 && R.f.cmd[3].tau[2] == 0.03 &&
              R.f.cmd[3].tau[3] == 0.001 && R.f.cmd[3].tau[5] == 0);
  // UR's rule: a tensor no body has is taken (the physics carries its nearest PSD one), a
  // negative Ixx/Iyy/Izz or more than the UR5 carries are runtime errors saying why
  sr_must(&R, "set_target_payload(1, [0, 0, 0], [0.01, 0.01, 0.01, 0.5, 0, 0])\n");
  assert_int_not_equal(sr_run(&R, "set_target_payload(1, [0, 0, 0], [0.01, -0.01, 0.01, 0, 0, 0])\n"), 0);
  assert_non_null(strstr(R.err.text, "must not be negative"));
  memset(&R.err, 0, sizeof R.err);
  assert_int_not_equal(sr_run(&R, "set_payload(5.5)\n"), 0);
  assert_non_null(strstr(R.err.text, "set_payload: payload mass must be within [0, 5] kg"));
  memset(&R.err, 0, sizeof R.err);
  assert_int_not_equal(sr_run(&R, "set_gravity([0, 0])\n"), 0);
}

static void test_client__coriolis_is_quadratic_in_the_speeds(void **state) {
  // C(q, q̇) q̇: zero at rest, four times as large at twice the speeds
  const double q[6] = {0.3, -1.2, 1.4, -1.7, -1.6, 0.2}, qd[6] = {0.4, -0.3, 0.5, 0.2, -0.6, 0.1};
  memcpy(R.f.s.q, q, sizeof q);
  sr_must(&R, "textmsg(get_coriolis_and_centrifugal_torques())\n");
  memcpy(R.f.s.qd, qd, sizeof qd);
  sr_must(&R, "textmsg(get_coriolis_and_centrifugal_torques())\n");
  for (int j = 0; j < 6; j++) R.f.s.qd[j] = 2 * qd[j];
  sr_must(&R, "textmsg(get_coriolis_and_centrifugal_torques())\n");
  double c0[6], c1[6], c2[6];
  assert_int_equal(sr_nums(&R, 0, c0, 6), 6);
  assert_int_equal(sr_nums(&R, 1, c1, 6), 6);
  assert_int_equal(sr_nums(&R, 2, c2, 6), 6);
  double big = 0;
  for (int j = 0; j < 6; j++) {
    assert_true(fabs(c0[j]) < 1e-9);
    assert_true(fabs(c2[j] - 4 * c1[j]) < 1e-4 * (1 + fabs(c2[j])));
    big = fmax(big, fabs(c1[j]));
  }
  assert_true(big > 1e-3);  // not trivially zero
}

static int polls;
static int cancel_after_20(void *ctx) { return ++polls >= 20; }

static void test_client__popup_message_and_blocking(void **state) {
  sr_must(&R, "popup(\"hello\", title=\"T1\", warning=True)\npopup(3.5)\n");
  assert_int_equal(R.f.n_msg, 2);
  assert_int_equal(R.f.msg[0].kind, URT_SCRIPT_MSG_POPUP);
  assert_string_equal(R.f.msg[0].title, "T1");
  assert_string_equal(R.f.msg[0].text, "hello");
  assert_true(R.f.msg[0].warning && !R.f.msg[0].error && !R.f.msg[0].blocking);
  assert_string_equal(R.f.msg[1].title, "Popup");
  assert_string_equal(R.f.msg[1].text, "3.5");
  // blocking: nobody dismisses it, the program waits until it is stopped (here after 20 ticks)
  const char *text = "popup(\"wait\", blocking=True, error=True)\ntextmsg(\"after\")\n";
  us_prog *p = NULL;
  assert_int_equal(urt__us_parse(text, strlen(text), &p, &R.err), 0);
  polls = 0;
  us_hooks h = {.host = &R.host, .motion_id = &R.motion_id, .step_budget = 1000,
                .wait_timeout_ms = 1, .poll = cancel_after_20};
  assert_int_not_equal(urt__us_run(p, &h, &R.err), 0);
  urt__us_prog_free(p);
  assert_int_equal(R.err.kind, US_ERR_CANCEL);
  assert_int_equal(R.f.n_msg, 3);  // the popup, never "after"
  assert_true(R.f.msg[2].blocking && R.f.msg[2].error);
  assert_int_equal(R.f.s.tick, 20);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_client__inverse_kin_round_trip, setup),
      cmocka_unit_test_setup(test_client__qnear_chooses_the_branch, setup),
      cmocka_unit_test_setup(test_client__tcp_argument_against_a_hand_composed_transform, setup),
      cmocka_unit_test_setup(test_client__flange_pose_and_getters, setup),
      cmocka_unit_test_setup(test_client__safety_limits, setup),
      cmocka_unit_test_setup(test_client__joint_positions_history, setup),
      cmocka_unit_test_setup(test_client__inputs_force_accelerometer, setup),
      cmocka_unit_test_setup(test_client__gravity_and_target_payload_commands, setup),
      cmocka_unit_test_setup(test_client__popup_message_and_blocking, setup),
      cmocka_unit_test_setup(test_client__coriolis_is_quadratic_in_the_speeds, setup),
  };
  return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
