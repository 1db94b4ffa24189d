/* SPDX-License-Identifier: Apache-2.0
 * tests/net/lcm/test_lcm_sender.c — status/drive fill field by field, command checks, and one
 * round trip through LCM's in-process memq:// provider. */
#include <lcm/lcm.h>
#include <math.h>
#include <string.h>

#include "test_model.h"
#include "test_support.h"
#include "urt/errors.h"
#include "urt/net/lcm_sender.h"

//---- fixtures ---------------------------------------------------------------------------------

// every double of the snapshot gets its own value, so a swapped field shows
static void fill_distinct(double *x, int n, double base) {
  for (int i = 0; i < n; ++i) {
    x[i] = base + 0.125 * i;
  }
}

static urt_snapshot_t make_snapshot(void) {
  urt_snapshot_t s;
  memset(&s, 0, sizeof s);
  s.tick = 1234;
  s.period = 0.002;
  s.time = 1234 * 0.002;
  s.sim_time = s.time;
  fill_distinct(s.q_target, 6, 100);
  fill_distinct(s.qd_target, 6, 110);
  fill_distinct(s.qdd_target, 6, 120);
  fill_distinct(s.i_target, 6, 130);
  fill_distinct(s.m_target, 6, 140);
  fill_distinct(s.q, 6, 150);
  fill_distinct(s.qd, 6, 160);
  fill_distinct(s.qdd, 6, 170);
  fill_distinct(s.i_actual, 6, 180);
  fill_distinct(s.i_control, 6, 190);
  fill_distinct(s.tau, 6, 200);
  fill_distinct(s.v_actual, 6, 210);
  fill_distinct(s.temperature, 6, 220);
  fill_distinct(s.tcp_pose, 6, 230);
  fill_distinct(s.tcp_speed, 6, 240);
  fill_distinct(s.tcp_pose_target, 6, 250);
  fill_distinct(s.tcp_speed_target, 6, 260);
  fill_distinct(s.tcp_force, 6, 270);
  for (int j = 0; j < 6; ++j) {
    s.joint_mode[j] = URT_JOINT_MODE_RUNNING + (j % 2);
  }
  s.robot_mode = URT_ROBOT_MODE_RUNNING;
  s.safety_mode = URT_SAFETY_MODE_PROTECTIVE_STOP;
  s.program_state = URT_PROGRAM_PLAYING;
  s.motion = URT_MOTION_DIRECT;
  s.ctrl_fault = URT_CTRL_FAULT_BAD_TARGET;
  s.pstop = URT_PSTOP_POS_LIMIT;
  s.speed_scaling = 0.75;
  s.exec_time = 3.5e-4;
  s.overruns = 7;
  s.missed_periods = 3;
  return s;
}

static urt_drive_sample_t make_drive(void) {
  urt_drive_sample_t d;
  memset(&d, 0, sizeof d);
  d.seq = 42;
  d.time = 0.0021;
  fill_distinct(d.q, 6, 10);
  fill_distinct(d.qd, 6, 20);
  fill_distinct(d.motor_angle, 6, 30);
  fill_distinct(d.motor_speed, 6, 40);
  fill_distinct(d.i, 6, 50);
  fill_distinct(d.i_ref, 6, 60);
  fill_distinct(d.v, 6, 70);
  fill_distinct(d.gear_in_torque, 6, 80);
  fill_distinct(d.gear_out_torque, 6, 90);
  fill_distinct(d.friction_torque, 6, 100);
  fill_distinct(d.flex_x, 6, 110);
  fill_distinct(d.flex_y, 6, 120);
  fill_distinct(d.bristle_z, 6, 130);
  return d;
}

static void assert_six(const double *got, const double *want) {
  for (int j = 0; j < 6; ++j) {
    assert_true(got[j] == want[j]);
  }
}

//---- status and drive -------------------------------------------------------------------------

static void test_lcm_status_fill__maps_every_field(void **state) {
  urt_snapshot_t s = make_snapshot();
  urtwin_lcmt_urtwin_status m;
  memset(&m, 0xff, sizeof m);
  urt_lcm_status_fill(&s, 1700000000123456, 5, &m);

  assert_int_equal(m.utime, 2468000);  // 2.468 s of controller time
  assert_int_equal(m.tick, 1234);
  assert_true(m.time == s.time && m.period == 0.002);
  assert_int_equal(m.publish_utime, 1700000000123456);
  assert_int_equal(m.ticks_lost, 5);
  assert_six(m.q_target, s.q_target);
  assert_six(m.qd_target, s.qd_target);
  assert_six(m.qdd_target, s.qdd_target);
  assert_six(m.q_actual, s.q);
  assert_six(m.qd_actual, s.qd);
  assert_six(m.qdd_actual, s.qdd);
  assert_six(m.current_actual, s.i_actual);
  assert_six(m.current_target, s.i_target);
  assert_six(m.current_control, s.i_control);
  assert_six(m.torque_actual, s.tau);
  assert_six(m.torque_target, s.m_target);
  assert_six(m.voltage_actual, s.v_actual);
  assert_six(m.temperature, s.temperature);
  assert_six(m.tcp_pose_actual, s.tcp_pose);
  assert_six(m.tcp_pose_target, s.tcp_pose_target);
  assert_six(m.tcp_speed_actual, s.tcp_speed);
  assert_six(m.tcp_speed_target, s.tcp_speed_target);
  assert_six(m.tcp_force, s.tcp_force);
  assert_int_equal(m.robot_mode, URT_ROBOT_MODE_RUNNING);
  assert_int_equal(m.safety_mode, URT_SAFETY_MODE_PROTECTIVE_STOP);
  assert_int_equal(m.program_state, URT_PROGRAM_PLAYING);
  for (int j = 0; j < 6; ++j) {
    assert_int_equal(m.joint_mode[j], s.joint_mode[j]);
  }
  assert_int_equal(m.motion, URT_MOTION_DIRECT);
  assert_int_equal(m.ctrl_fault, URT_CTRL_FAULT_BAD_TARGET);
  assert_int_equal(m.pstop, URT_PSTOP_POS_LIMIT);
  assert_true(m.speed_scaling == 0.75 && m.exec_time == 3.5e-4);
  assert_int_equal(m.overruns, 7);
  assert_int_equal(m.missed_periods, 3);
}

static void test_lcm_drive_fill__maps_every_field(void **state) {
  urt_drive_sample_t d = make_drive();
  urtwin_lcmt_urtwin_drive m;
  memset(&m, 0xff, sizeof m);
  urt_lcm_drive_fill(&d, 9, &m);

  assert_int_equal(m.utime, 2100);
  assert_int_equal(m.seq, 42);
  assert_true(m.time == 0.0021);
  assert_int_equal(m.samples_lost, 9);
  assert_six(m.q, d.q);
  assert_six(m.qd, d.qd);
  assert_six(m.motor_angle, d.motor_angle);
  assert_six(m.motor_speed, d.motor_speed);
  assert_six(m.current, d.i);
  assert_six(m.current_reference, d.i_ref);
  assert_six(m.voltage, d.v);
  assert_six(m.gear_input_torque, d.gear_in_torque);
  assert_six(m.gear_output_torque, d.gear_out_torque);
  assert_six(m.friction_torque, d.friction_torque);
  assert_six(m.bristle_z, d.bristle_z);
  assert_six(m.flexspline_x, d.flex_x);
  assert_six(m.flexspline_y, d.flex_y);
}

//---- memq round trip --------------------------------------------------------------------------

static void on_status(const lcm_recv_buf_t *rbuf, const char *ch,
                      const urtwin_lcmt_urtwin_status *msg, void *user) {
  *(urtwin_lcmt_urtwin_status *)user = *msg;
}

static void test_lcm_status__survives_encode_publish_decode_over_memq(void **state) {
  lcm_t *lcm = lcm_create("memq://");
  assert_non_null(lcm);
  urtwin_lcmt_urtwin_status got;
  memset(&got, 0, sizeof got);
  urtwin_lcmt_urtwin_status_subscription_t *sub =
      urtwin_lcmt_urtwin_status_subscribe(lcm, "S", on_status, &got);

  urt_snapshot_t s = make_snapshot();
  urtwin_lcmt_urtwin_status sent;
  urt_lcm_status_fill(&s, 1, 0, &sent);
  assert_int_equal(urtwin_lcmt_urtwin_status_publish(lcm, "S", &sent), 0);
  assert_true(lcm_handle_timeout(lcm, 100) > 0);
  assert_memory_equal(&got, &sent, sizeof sent);  // fixed-size arrays only: no pointers
  urtwin_lcmt_urtwin_status_unsubscribe(lcm, sub);
  lcm_destroy(lcm);
}

//---- commands ---------------------------------------------------------------------------------

static double Q[6] = {0.1, -1.2, 1.3, -0.4, 0.5, 0.6};
static double QD[6] = {1, 2, 3, 4, 5, 6};
static double TAU[6] = {-1, -2, -3, -4, -5, -6};

static urtwin_lcmt_urtwin_command make_command(void) {
  urtwin_lcmt_urtwin_command c = {
      .utime = 77, .num_joints = 6, .joint_position = Q, .num_velocities = 6,
      .joint_velocity = QD, .num_torques = 6, .joint_torque = TAU};
  return c;
}

static void test_lcm_command_to_ctrl__gives_direct_setpoint(void **state) {
  urtwin_lcmt_urtwin_command c = make_command();
  urt_ctrl_cmd_t out;
  assert_int_equal(urt_lcm_command_to_ctrl(&c, 5, &out), 0);
  assert_int_equal(out.kind, URT_CTRL_DIRECT);
  assert_int_equal(out.id, 5);
  assert_six(out.q, Q);
  assert_six(out.qd, QD);
  assert_six(out.tau, TAU);
}

static void test_lcm_command_to_ctrl__absent_velocity_and_torque_are_zero(void **state) {
  urtwin_lcmt_urtwin_command c = make_command();
  c.num_velocities = 0;
  c.joint_velocity = NULL;
  c.num_torques = 0;
  c.joint_torque = NULL;
  urt_ctrl_cmd_t out;
  memset(&out, 0xff, sizeof out);
  assert_int_equal(urt_lcm_command_to_ctrl(&c, 1, &out), 0);
  double zero[6] = {0};
  assert_six(out.q, Q);
  assert_six(out.qd, zero);
  assert_six(out.tau, zero);
}

// each bad shape is refused with URT_EPROTO and leaves the output alone
static void test_lcm_command_to_ctrl__refuses_wrong_lengths(void **state) {
  urtwin_lcmt_urtwin_command bad[5];
  for (int k = 0; k < 5; ++k) {
    bad[k] = make_command();
  }
  bad[0].num_joints = 5;
  bad[1].num_joints = 7;
  bad[2].num_velocities = 3;
  bad[3].num_torques = 12;
  bad[4].joint_position = NULL;
  for (int k = 0; k < 5; ++k) {
    urt_ctrl_cmd_t out, before;
    memset(&out, 0xab, sizeof out);
    before = out;
    assert_int_equal(urt_lcm_command_to_ctrl(&bad[k], 1, &out), URT_EPROTO);
    assert_memory_equal(&out, &before, sizeof out);
  }
}

static void test_lcm_command_to_ctrl__refuses_nan_and_inf(void **state) {
  double q[6], qd[6], tau[6];
  for (int field = 0; field < 3; ++field) {
    for (int j = 0; j < 6; ++j) {
      memcpy(q, Q, sizeof q);
      memcpy(qd, QD, sizeof qd);
      memcpy(tau, TAU, sizeof tau);
      double *x = field == 0 ? q : field == 1 ? qd : tau;
      x[j] = (j % 2) ? NAN : -INFINITY;
      urtwin_lcmt_urtwin_command c = make_command();
      c.joint_position = q;
      c.joint_velocity = qd;
      c.joint_torque = tau;
      urt_ctrl_cmd_t out, before;
      memset(&out, 0xab, sizeof out);
      before = out;
      assert_int_equal(urt_lcm_command_to_ctrl(&c, 1, &out), URT_ERANGE);
      assert_memory_equal(&out, &before, sizeof out);
    }
  }
}

//---- command bytes ----------------------------------------------------------------------------

static int encode(const urtwin_lcmt_urtwin_command *c, uint8_t *buf, int cap) {
  int n = urtwin_lcmt_urtwin_command_encode(buf, 0, cap, c);
  assert_true(n > 0);
  return n;
}

static void test_lcm_command_decode__accepts_encoded_message(void **state) {
  uint8_t buf[512];
  urtwin_lcmt_urtwin_command c = make_command();
  int n = encode(&c, buf, sizeof buf);
  urt_ctrl_cmd_t out;
  assert_int_equal(urt_lcm_command_decode(buf, n, 9, &out), 0);
  assert_int_equal(out.kind, URT_CTRL_DIRECT);
  assert_int_equal(out.id, 9);
  assert_six(out.q, Q);
  assert_six(out.qd, QD);
  assert_six(out.tau, TAU);

  // positions only (Drake's iiwa command without torques)
  c.num_velocities = c.num_torques = 0;
  n = encode(&c, buf, sizeof buf);
  assert_int_equal(urt_lcm_command_decode(buf, n, 10, &out), 0);
  assert_six(out.q, Q);
}

static void test_lcm_command_decode__refuses_truncated_and_trailing_bytes(void **state) {
  uint8_t buf[512];
  urtwin_lcmt_urtwin_command c = make_command();
  int n = encode(&c, buf, sizeof buf);
  urt_ctrl_cmd_t out;
  for (int len = 0; len < n; ++len) {
    assert_int_equal(urt_lcm_command_decode(buf, len, 1, &out), URT_EPROTO);
  }
  buf[n] = 0;
  assert_int_equal(urt_lcm_command_decode(buf, n + 1, 1, &out), URT_EPROTO);
}

static void test_lcm_command_decode__refuses_wrong_fingerprint(void **state) {
  uint8_t buf[512];
  urtwin_lcmt_urtwin_command c = make_command();
  int n = encode(&c, buf, sizeof buf);
  buf[3] ^= 0x10;
  urt_ctrl_cmd_t out;
  assert_int_equal(urt_lcm_command_decode(buf, n, 1, &out), URT_EPROTO);

  // a status message on the command channel
  urt_snapshot_t s = make_snapshot();
  urtwin_lcmt_urtwin_status st;
  urt_lcm_status_fill(&s, 0, 0, &st);
  uint8_t sbuf[4096];
  int sn = urtwin_lcmt_urtwin_status_encode(sbuf, 0, sizeof sbuf, &st);
  assert_true(sn > 0);
  assert_int_equal(urt_lcm_command_decode(sbuf, sn, 1, &out), URT_EPROTO);
}

// a peer's huge count must be refused before the generated decoder allocates for it
static void test_lcm_command_decode__refuses_huge_counts_without_allocating(void **state) {
  uint8_t buf[512];
  urtwin_lcmt_urtwin_command c = make_command();
  int n = encode(&c, buf, sizeof buf);
  buf[16] = 0x7f;  // num_joints = 0x7f000006
  urt_ctrl_cmd_t out;
  urt_test_malloc_arm(1);
  int rc = urt_lcm_command_decode(buf, n, 1, &out);
  long calls = urt_test_malloc_count();
  urt_test_malloc_arm(0);
  assert_int_equal(rc, URT_EPROTO);
  assert_int_equal(calls, 0);

  // num_torques negative
  n = encode(&c, buf, sizeof buf);
  buf[n - 6 * 8 - 4] = 0xff;
  assert_int_equal(urt_lcm_command_decode(buf, n, 1, &out), URT_EPROTO);
}

static void test_lcm_command_decode__refuses_nan_in_bytes(void **state) {
  uint8_t buf[512];
  double q[6];
  memcpy(q, Q, sizeof q);
  q[2] = NAN;
  urtwin_lcmt_urtwin_command c = make_command();
  c.joint_position = q;
  int n = encode(&c, buf, sizeof buf);
  urt_ctrl_cmd_t out;
  assert_int_equal(urt_lcm_command_decode(buf, n, 1, &out), URT_ERANGE);
}

/* ---- faults ---- */

static int encode_fault(const urtwin_lcmt_urtwin_fault *f, uint8_t *buf, int cap) {
  int n = urtwin_lcmt_urtwin_fault_encode(buf, 0, cap, f);
  assert_true(n > 0);
  return n;
}

static urtwin_lcmt_urtwin_fault fault_msg(char *cls, char *profile, int joint, double sev) {
  static char empty[] = "";
  urtwin_lcmt_urtwin_fault f;
  memset(&f, 0, sizeof f);
  f.inject = 1;
  f.fault_class = cls;
  f.profile = profile;
  f.location = empty;
  f.joint = joint;
  f.severity = sev;
  return f;
}

static void test_lcm_fault_decode__gives_the_spec_as_a_fault_command(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  char cls[] = "wg_bearing", prof[] = "linear", loc[] = "ball";
  urtwin_lcmt_urtwin_fault f = fault_msg(cls, prof, 4, 0.01);
  f.location = loc;
  f.balls = 11;
  f.ball_ratio = 0.25;
  f.onset = 1.5;
  f.ramp = 2.0;
  f.seed = 77;
  uint8_t buf[512];
  int n = encode_fault(&f, buf, sizeof buf);
  urt_ctrl_cmd_t c;
  assert_int_equal(urt_lcm_fault_decode(buf, (size_t)n, m, &c), 0);
  assert_int_equal(c.kind, URT_CTRL_FAULT);
  urt_fault_spec_t s;
  assert_int_equal(urt_fault_cmd_unpack(&c, &s), 1);
  assert_int_equal(s.cls, URT_FAULT_WG_BEARING);
  assert_int_equal(s.joint, 4);
  assert_int_equal(s.profile, URT_FAULT_LINEAR);
  assert_int_equal(s.location, URT_FAULT_BEARING_BALL);
  assert_int_equal(s.balls, 11);
  assert_true(s.severity == 0.01 && s.onset == 1.5 && s.ramp == 2.0 && s.ball_ratio == 0.25);
  assert_true(s.seed == 77);
  urt_model_free(m);
}

static void test_lcm_fault_decode__refuses_unknown_names_ranges_and_garbage(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  char demag[] = "demagnetisation", nope[] = "flux_capacitor", step[] = "step", saw[] = "saw";
  uint8_t buf[512];
  urt_ctrl_cmd_t c, before;
  memset(&c, 0x5a, sizeof c);
  before = c;
  struct {
    urtwin_lcmt_urtwin_fault f;
    const char *why;
  } bad[] = {
      {fault_msg(nope, step, 1, 0.1), "unknown class"},
      {fault_msg(demag, saw, 1, 0.1), "unknown profile"},
      {fault_msg(demag, step, 1, 0.5), "severity beyond 0.3"},
      {fault_msg(demag, step, 6, 0.1), "joint 6"},
      {fault_msg(demag, step, 1, NAN), "NaN severity"},
  };
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
    int n = encode_fault(&bad[k].f, buf, sizeof buf);
    print_message("%s\n", bad[k].why);
    assert_int_equal(urt_lcm_fault_decode(buf, (size_t)n, m, &c), URT_ERANGE);
    assert_memory_equal(&c, &before, sizeof c);
  }
  // truncated, trailing bytes, garbage
  urtwin_lcmt_urtwin_fault ok = fault_msg(demag, step, 1, 0.1);
  int n = encode_fault(&ok, buf, sizeof buf);
  assert_int_equal(urt_lcm_fault_decode(buf, (size_t)n - 3, m, &c), URT_EPROTO);
  assert_int_equal(urt_lcm_fault_decode(buf, (size_t)n + 1, m, &c), URT_EPROTO);
  memset(buf, 0x01, 64);
  assert_int_equal(urt_lcm_fault_decode(buf, 64, m, &c), URT_EPROTO);
  assert_memory_equal(&c, &before, sizeof c);
  urt_model_free(m);
}

static void test_lcm_fault_truth_fill__maps_every_fault(void **state) {
  (void)state;
  urt_snapshot_t s;
  memset(&s, 0, sizeof s);
  s.tick = 250;
  s.time = 0.5;
  s.sim_time = 0.5;
  s.faults_applied = 3;
  s.faults_refused = 1;
  s.fault_truth.n = 2;
  s.fault_truth.cls[0] = URT_FAULT_BACKLASH;
  s.fault_truth.joint[0] = 2;
  s.fault_truth.active[0] = 1;
  s.fault_truth.severity[0] = 1e-3;
  s.fault_truth.onset[0] = 0.25;
  s.fault_truth.cls[1] = URT_FAULT_COLLISION;
  s.fault_truth.severity[1] = 0.0;
  s.fault_truth.onset[1] = -1.0;
  static urt_lcm_fault_truth_buf_t b;
  urt_lcm_fault_truth_fill(&s, &b);
  assert_int_equal(b.msg.utime, 500000);
  assert_int_equal(b.msg.tick, 250);
  assert_int_equal(b.msg.num_faults, 2);
  assert_string_equal(b.msg.fault_class[0], "backlash");
  assert_string_equal(b.msg.fault_class[1], "collision");
  assert_int_equal(b.msg.joint[0], 2);
  assert_int_equal(b.msg.joint[1], -1);  // at the TCP
  assert_true(b.msg.active[0] == 1 && b.msg.active[1] == 0);
  assert_true(b.msg.severity[0] == 1e-3 && b.msg.onset[0] == 0.25 && b.msg.onset[1] == -1.0);
  assert_int_equal(b.msg.faults_applied, 3);
  assert_int_equal(b.msg.faults_refused, 1);
  // it encodes and decodes to itself
  uint8_t buf[2048];
  int n = urtwin_lcmt_urtwin_fault_truth_encode(buf, 0, sizeof buf, &b.msg);
  assert_true(n > 0);
  urtwin_lcmt_urtwin_fault_truth back;
  assert_int_equal(urtwin_lcmt_urtwin_fault_truth_decode(buf, 0, n, &back), n);
  assert_string_equal(back.fault_class[0], "backlash");
  assert_true(back.severity[0] == 1e-3);
  urtwin_lcmt_urtwin_fault_truth_decode_cleanup(&back);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_lcm_status_fill__maps_every_field),
      cmocka_unit_test(test_lcm_drive_fill__maps_every_field),
      cmocka_unit_test(test_lcm_status__survives_encode_publish_decode_over_memq),
      cmocka_unit_test(test_lcm_command_to_ctrl__gives_direct_setpoint),
      cmocka_unit_test(test_lcm_command_to_ctrl__absent_velocity_and_torque_are_zero),
      cmocka_unit_test(test_lcm_command_to_ctrl__refuses_wrong_lengths),
      cmocka_unit_test(test_lcm_command_to_ctrl__refuses_nan_and_inf),
      cmocka_unit_test(test_lcm_command_decode__accepts_encoded_message),
      cmocka_unit_test(test_lcm_command_decode__refuses_truncated_and_trailing_bytes),
      cmocka_unit_test(test_lcm_command_decode__refuses_wrong_fingerprint),
      cmocka_unit_test(test_lcm_command_decode__refuses_huge_counts_without_allocating),
      cmocka_unit_test(test_lcm_command_decode__refuses_nan_in_bytes),
      cmocka_unit_test(test_lcm_fault_decode__gives_the_spec_as_a_fault_command),
      cmocka_unit_test(test_lcm_fault_decode__refuses_unknown_names_ranges_and_garbage),
      cmocka_unit_test(test_lcm_fault_truth_fill__maps_every_fault),
  };
  return cmocka_run_group_tests_name("net/lcm/sender", tests, NULL, NULL);
}
