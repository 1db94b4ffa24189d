/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_controller_modes.c — core/controller.cpp and controller_commands.cpp, the
 * kinds added for ur_rtde's control script: pause/resume, external wrench and gravity, direct
 * torque, freedrive, servol, servoc and force mode. Each test runs the loop the way the hard
 * loop does (apply, tick, then n_sub × setpoint, command_set, step), sensor noise on as
 * configured. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "controller_harness.h"
#include "test_model.h"
#include "test_support.h"
#include "urt/controller.h"
#include "urt/core.h"
#include "urt/snapshot.h"

/* the 2 s directTorque hold; 0.5 s under AddressSanitizer (about 12× slower) */
#if defined(__SANITIZE_ADDRESS__)
#define URT_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define URT_TEST_ASAN 1
#endif
#endif
#ifdef URT_TEST_ASAN
static const double kHoldTime = 0.5;
#else
static const double kHoldTime = 2.0;
#endif

static void q_actual(const rig_t *r, double *q) {
  for (int j = 0; j < URT_NJ; j++) {
    q[j] = r->d->x[j][URT_X_Q];
  }
}

static double q_dist(const double *a, const double *b) {
  double e = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    e = fmax(e, fabs(a[j] - b[j]));
  }
  return e;
}

static void rotvec_matrix(const double *r, double R[9]) {
  double th = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  double k[3] = {0.0, 0.0, 1.0};
  if (th > 0.0) {
    for (int i = 0; i < 3; i++) {
      k[i] = r[i] / th;
    }
  }
  double c = cos(th), s = sin(th), v = 1.0 - c;
  R[0] = c + k[0] * k[0] * v;
  R[1] = k[0] * k[1] * v - k[2] * s;
  R[2] = k[0] * k[2] * v + k[1] * s;
  R[3] = k[1] * k[0] * v + k[2] * s;
  R[4] = c + k[1] * k[1] * v;
  R[5] = k[1] * k[2] * v - k[0] * s;
  R[6] = k[2] * k[0] * v - k[1] * s;
  R[7] = k[2] * k[1] * v + k[0] * s;
  R[8] = c + k[2] * k[2] * v;
}

/* the angle between the orientations of two poses [rad] */
static double rot_angle(const double *a, const double *b) {
  double A[9], B[9], tr = 0.0;
  rotvec_matrix(a + 3, A);
  rotvec_matrix(b + 3, B);
  for (int i = 0; i < 3; i++) {
    for (int k = 0; k < 3; k++) {
      tr += A[3 * k + i] * B[3 * k + i];  // trace(Aᵀ B)
    }
  }
  return acos(fmax(-1.0, fmin(1.0, 0.5 * (tr - 1.0))));
}

static urt_snapshot_t snap(rig_t *r) {
  urt_snapshot_t s;
  urt_snapshot_fill(r->m, r->c, r->d, &s);
  return s;
}

/* an arm pose away from the home pose's singular wrist, TCP in front of the base */
static void go_to_work_pose(rig_t *r) {
  const double q[URT_NJ] = {0.0, -1.9, 1.9, -1.57, -1.57, 0.0};
  urt_ctrl_cmd_t c = rig_cmd(r, URT_CTRL_MOVEJ);
  memcpy(c.q, q, sizeof c.q);
  c.a = 3.0;
  c.v = 2.0;
  rig_period(r, &c);
  for (int i = 0; i < 2000 && r->c->motion_done_id < c.id; i++) {
    rig_period(r, NULL);
  }
  run_for(r, 0.3);
  assert_int_equal(r->d->pstop, 0);
}

//---- pause / resume ----

static void test_pause__movej_slows_holds_and_resumes_to_the_same_target(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  urt_ctrl_cmd_t play = rig_cmd(&r, URT_CTRL_PROGRAM_STATE);
  play.index = URT_PROGRAM_PLAYING;
  rig_period(&r, &play);

  double q[URT_NJ];
  q_actual(&r, q);
  const double D = 30.0 * M_PI / 180.0;
  q[1] += D;
  urt_ctrl_cmd_t mj = rig_cmd(&r, URT_CTRL_MOVEJ);
  memcpy(mj.q, q, sizeof mj.q);
  mj.a = 1.4;
  mj.v = 1.05;
  const double ideal = D / 1.05 + 1.05 / 1.4, pause_len = 1.0;

  double t = 0.0;
  rig_period(&r, &mj);
  t += r.c->period;
  while (t < 0.5) {
    rig_period(&r, NULL);
    t += r.c->period;
  }
  urt_ctrl_cmd_t pause = rig_cmd(&r, URT_CTRL_PAUSE);
  rig_period(&r, &pause);
  t += r.c->period;
  assert_int_equal(snap(&r).program_state, URT_PROGRAM_PAUSED);
  double held[URT_NJ];
  double t_pause = t;
  while (t < t_pause + 0.5) {
    rig_period(&r, NULL);
    t += r.c->period;
  }
  q_actual(&r, held);
  urt_snapshot_t s = snap(&r);
  while (t < t_pause + pause_len) {
    rig_period(&r, NULL);
    t += r.c->period;
  }
  double q_now[URT_NJ];
  q_actual(&r, q_now);
  const double creep = q_dist(held, q_now);
  assert_true(r.c->motion_done_id < mj.id);
  assert_near(s.speed_scaling, 0.0, 1e-12);
  assert_near(r.c->qd1[1], 0.0, 0.0);

  urt_ctrl_cmd_t resume = rig_cmd(&r, URT_CTRL_RESUME);
  rig_period(&r, &resume);
  t += r.c->period;
  assert_int_equal(snap(&r).program_state, URT_PROGRAM_PLAYING);
  while (r.c->motion_done_id < mj.id && t < 10.0) {
    rig_period(&r, NULL);
    t += r.c->period;
  }
  run_for(&r, 0.5);
  q_actual(&r, q_now);
  const double err = q_dist(q_now, q);
  print_message("pause 1 s mid-movej: total %.4f s = ideal %.4f + pause %.1f %+.4f s; creep while "
                "paused %.2e rad; final error %.2e rad; pstop %u\n",
                t, ideal, pause_len, t - ideal - pause_len, creep, err, r.d->pstop);
  assert_int_equal(r.d->pstop, 0);
  // the slow-down and the speed-up each take 0.25 s at half the path speed on average
  assert_true(fabs(t - ideal - pause_len) < 0.3);
  assert_true(creep < 1e-4);
  assert_true(err < 1e-4);
  rig_free(&r);
}

static void test_pause__streaming_stops_and_program_stop_clears_the_pause(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  urt_ctrl_cmd_t play = rig_cmd(&r, URT_CTRL_PROGRAM_STATE);
  play.index = URT_PROGRAM_PLAYING;
  rig_period(&r, &play);
  urt_ctrl_cmd_t sj = rig_cmd(&r, URT_CTRL_SPEEDJ);
  sj.q[0] = 0.3;
  sj.a = 2.0;
  rig_period(&r, &sj);
  run_for(&r, 0.3);
  urt_ctrl_cmd_t pause = rig_cmd(&r, URT_CTRL_PAUSE);
  rig_period(&r, &pause);
  assert_int_equal(r.c->motion, URT_MOTION_STOP);
  run_for(&r, 0.3);
  assert_int_equal(r.c->motion, URT_MOTION_IDLE);
  assert_true(r.c->motion_done_id >= sj.id);
  assert_int_equal(snap(&r).program_state, URT_PROGRAM_PAUSED);
  urt_ctrl_cmd_t stop = rig_cmd(&r, URT_CTRL_PROGRAM_STATE);
  stop.index = URT_PROGRAM_STOPPED;
  rig_period(&r, &stop);
  assert_int_equal(r.c->paused, 0);
  assert_int_equal(snap(&r).program_state, URT_PROGRAM_STOPPED);
  assert_int_equal(r.d->pstop, 0);
  rig_free(&r);
}

//---- wrench and gravity ----

static void test_set_wrench__shows_in_tcp_force_and_bad_values_are_refused(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  urt_ctrl_cmd_t w = rig_cmd(&r, URT_CTRL_SET_WRENCH);
  const double wr[6] = {15.0, -8.0, 25.0, 1.5, -0.7, 0.4};
  memcpy(w.pose, wr, sizeof wr);
  rig_period(&r, &w);
  run_for(&r, 0.5);
  urt_snapshot_t s = snap(&r);
  double err = 0.0;
  for (int i = 0; i < 6; i++) {
    err = fmax(err, fabs(s.tcp_force[i] - wr[i]));
  }
  print_message("SET_WRENCH [15 -8 25 N, 1.5 -0.7 0.4 N m]: tcp_force worst error %.2e\n", err);
  assert_true(err < 1e-2);
  assert_int_equal(r.c->fault, 0);

  urt_ctrl_cmd_t bad = rig_cmd(&r, URT_CTRL_SET_WRENCH);
  bad.pose[2] = NAN;
  rig_period(&r, &bad);
  assert_true(r.c->fault & URT_CTRL_FAULT_BAD_ARGUMENT);
  assert_near(r.d->wrench_ext[2], 25.0, 0.0);
  bad.pose[2] = 1e5;
  rig_period(&r, &bad);
  assert_near(r.d->wrench_ext[2], 25.0, 0.0);

  // gravity: the controller's model only; bounded like the loader's
  urt_ctrl_cmd_t g = rig_cmd(&r, URT_CTRL_SET_GRAVITY);
  g.pose[2] = -9.7;
  rig_period(&r, &g);
  assert_near(r.c->gravity[2], -9.7, 0.0);
  g.pose[0] = INFINITY;
  rig_period(&r, &g);
  assert_near(r.c->gravity[0], 0.0, 0.0);
  assert_int_equal(r.d->pstop, 0);
  rig_free(&r);
}

static void test_set_tool_voltage__kept_shown_and_bad_values_refused(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  assert_int_equal(snap(&r).tool_voltage, 0);
  urt_ctrl_cmd_t v = rig_cmd(&r, URT_CTRL_SET_TOOL_VOLTAGE);
  v.value = 24;
  rig_period(&r, &v);
  assert_int_equal(snap(&r).tool_voltage, 24);
  v.value = 5;  // a tool connector has 0, 12 or 24 V
  rig_period(&r, &v);
  assert_true(r.c->fault & URT_CTRL_FAULT_BAD_ARGUMENT);
  assert_int_equal(snap(&r).tool_voltage, 24);
  v.value = 12;
  rig_period(&r, &v);
  assert_int_equal(snap(&r).tool_voltage, 12);
  rig_free(&r);
}

// SET_INPUTS changes only the inputs its masks name; a command a control box could not see
// (levels outside the mask, a pin past 17, a voltage outside 0–10 V, a NaN) changes nothing
static void test_set_inputs__masked_levels_shown_and_bad_commands_refused_whole(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  urt_ctrl_cmd_t in = rig_cmd(&r, URT_CTRL_SET_INPUTS);
  in.id = 0;
  in.index = (1 << 0) | (1 << 9) | (1 << 17);
  in.value = (1 << 0) | (1 << 17);
  in.a = 0x1 | 0x8;
  in.q[0] = 4.5;
  in.q[3] = 10.0;
  rig_period(&r, &in);
  urt_snapshot_t s = snap(&r);
  assert_int_equal(s.digital_in, (1u << 0) | (1u << 17));
  assert_true(s.analog_in[0] == 4.5 && s.analog_in[1] == 0.0);
  assert_true(s.tool_analog_in[0] == 0.0 && s.tool_analog_in[1] == 10.0);
  assert_false(r.c->fault & URT_CTRL_FAULT_BAD_ARGUMENT);

  // a second change leaves what it does not name
  urt_ctrl_cmd_t more = in;
  more.index = 1 << 17;
  more.value = 0;
  more.a = 0x2;
  more.q[1] = 0.25;
  rig_period(&r, &more);
  s = snap(&r);
  assert_int_equal(s.digital_in, 1u << 0);
  assert_true(s.analog_in[0] == 4.5 && s.analog_in[1] == 0.25 && s.tool_analog_in[1] == 10.0);

  const struct {
    int32_t mask;
    double levels, amask, v;
  } bad[] = {{1, 3, 0, 0}, {1 << 18, 0, 0, 0}, {-1, 0, 0, 0}, {0, 0, 16, 0},
             {0, 0, 0.5, 0}, {0, 0, 1, 10.5}, {0, 0, 1, -0.1}, {0, 0, 1, NAN}, {1, 0.5, 0, 0}};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
    urt_ctrl_cmd_t b = in;
    b.index = bad[k].mask;
    b.value = bad[k].levels;
    b.a = bad[k].amask;
    b.q[0] = bad[k].v;
    r.c->fault = 0;
    rig_period(&r, &b);
    assert_true(r.c->fault & URT_CTRL_FAULT_BAD_ARGUMENT);
    s = snap(&r);
    assert_int_equal(s.digital_in, 1u << 0);
    assert_true(s.analog_in[0] == 4.5);
  }
  rig_free(&r);
}

//---- direct torque ----

/* stream directTorque for t seconds: extra (nullable) besides gravity, which the controller adds
 * itself (UR: the target torque "should not include gravity compensation"); index 2 scales the
 * friction model's viscous and Coulomb parts by visc and coul. Returns the largest joint drift
 * from the start. */
static double stream_torque(rig_t *r, double t, const double *extra, int index, double visc,
                            double coul) {
  double q0[URT_NJ], q[URT_NJ], drift = 0.0;
  q_actual(r, q0);
  int n = (int)lround(t / r->c->period);
  uint64_t id = r->next_id++;
  for (int i = 0; i < n; i++) {
    urt_ctrl_cmd_t c;
    memset(&c, 0, sizeof c);
    c.kind = URT_CTRL_TORQUE;
    c.id = id;
    c.index = index;
    for (int j = 0; j < URT_NJ; j++) {
      c.tau[j] = extra ? extra[j] : 0.0;
      c.q[j] = visc;
      c.qd[j] = coul;
    }
    rig_period(r, &c);
    q_actual(r, q);
    drift = fmax(drift, q_dist(q, q0));
  }
  return drift;
}

static void test_torque__zero_torque_holds_the_arm_against_gravity_then_a_torque_moves_it(
    void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  go_to_work_pose(&r);
  const double t_hold = kHoldTime;
  // without the controller's gravity the shoulder (about 50 N m here) would fall at once
  double drift = stream_torque(&r, t_hold, NULL, 0, 0.0, 0.0);
  urt_snapshot_t s = snap(&r);
  print_message("directTorque = 0 for %.1f s: max joint drift %.2e rad; control_mode %d, "
                "torque mask %#x\n", t_hold, drift, s.control_mode, r.c->torque_mask);
  assert_int_equal(r.d->pstop, 0);
  assert_int_equal(r.c->motion, URT_MOTION_TORQUE);
  assert_int_equal(r.c->torque_mask, (1u << URT_NJ) - 1u);
  assert_int_equal(s.control_mode, 3);
  assert_true(drift < 1e-3);

  // a torque besides gravity acts through the drives: 5 N m on wrist 3 beats its friction
  double q0[URT_NJ], q1[URT_NJ];
  q_actual(&r, q0);
  const double extra[URT_NJ] = {0, 0, 0, 0, 0, 5.0};
  stream_torque(&r, 0.05, extra, 1, 0.0, 0.0);
  q_actual(&r, q1);
  double others = 0.0;
  for (int j = 0; j < 5; j++) {
    others = fmax(others, fabs(q1[j] - q0[j]));
  }
  print_message("+5 N m on wrist 3 for 0.05 s: wrist 3 moved %+.4f rad, others at most %.2e rad\n",
                q1[5] - q0[5], others);
  assert_true(q1[5] - q0[5] > 1e-2);
  assert_true(others < 1e-3);

  // friction scales (index 2): the drive's torque is the command, the controller's gravity
  // and the friction model's Coulomb part (with Stribeck's) at coul plus its viscous part
  // f_v |q̇|^(2/3) at visc, at the speed the period starts from (faded in over 2e-3 rad/s,
  // core/controller_feedforward.cpp)
  const double visc = 0.5, coul = 0.25;
  stream_torque(&r, 0.01, extra, 2, visc, coul);
  const double qd = r.d->x[5][URT_X_QD];
  stream_torque(&r, 0.002, extra, 2, visc, coul);
  const urt_friction_params_t *fp = &r.m->friction[5];
  const double g_f = urt_friction_g(fp, qd), v_part = fp->f_v * cbrt(qd * qd);
  double grav[URT_NJ];
  urt_arm_gravity(r.m, r.c->q1, grav);
  const double want = 5.0 + grav[5] + (coul * (g_f - v_part) + visc * v_part) * tanh(qd / 2e-3);
  print_message("wrist 3 at %.3f rad/s: torque feed-forward %.6f N m, expected %.6f (gravity "
                "%.4f, friction %.4f of the whole model's %.4f)\n", qd, r.c->tau_ff[5], want,
                grav[5], want - 5.0 - grav[5], g_f);
  assert_true(fabs(r.c->tau_ff[5] - want) < 1e-9);
  // out of UR's range [0, 1]: refused
  urt_ctrl_cmd_t wrong = rig_cmd(&r, URT_CTRL_TORQUE);
  wrong.index = 2;
  wrong.q[3] = 1.5;
  r.c->fault = 0;
  rig_period(&r, &wrong);
  assert_true(r.c->fault & URT_CTRL_FAULT_BAD_ARGUMENT);

  // the stream stops: after the time-out the arm is brought to rest under position control
  run_for(&r, 0.02);
  assert_int_equal(r.c->torque_mask, 0);
  run_for(&r, 0.5);
  q_actual(&r, q0);
  run_for(&r, 0.3);
  q_actual(&r, q1);
  print_message("after the time-out: motion %d, creep over 0.3 s %.2e rad\n", r.c->motion,
                q_dist(q0, q1));
  assert_int_equal(r.c->motion, URT_MOTION_IDLE);
  assert_true(q_dist(q0, q1) < 1e-4);
  assert_int_equal(r.d->pstop, 0);

  // above the joint's torque limit: protective stop
  urt_ctrl_cmd_t bad = rig_cmd(&r, URT_CTRL_TORQUE);
  bad.tau[1] = 1e3;
  rig_period(&r, &bad);
  assert_int_equal(r.c->safety_mode, URT_SAFETY_MODE_PROTECTIVE_STOP);
  assert_true(r.d->pstop & URT_PSTOP_TORQUE_LIMIT);
  rig_free(&r);
}

//---- freedrive ----

static void test_freedrive__holds_without_a_wrench_and_gives_way_to_one(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  go_to_work_pose(&r);
  urt_ctrl_cmd_t fd = rig_cmd(&r, URT_CTRL_FREEDRIVE);
  fd.index = 1;
  for (int j = 0; j < URT_NJ; j++) {
    fd.q[j] = 1.0;
  }
  double q0[URT_NJ], q1[URT_NJ], p0[6], p1[6];
  q_actual(&r, q0);
  rig_period(&r, &fd);
  assert_int_equal(r.c->motion, URT_MOTION_FREEDRIVE);
  assert_int_equal(snap(&r).control_mode, 1);
  run_for(&r, 0.5);
  q_actual(&r, q1);
  const double still = q_dist(q0, q1);

  // push the tool sideways and down
  tcp_actual(&r, p0);
  const double w[6] = {0.0, 40.0, -30.0, 0.0, 0.0, 0.0};
  memcpy(r.d->wrench_ext, w, sizeof w);
  run_for(&r, 0.3);
  tcp_actual(&r, p1);
  double along = ((p1[1] - p0[1]) * w[1] + (p1[2] - p0[2]) * w[2]) / 50.0;
  memset(r.d->wrench_ext, 0, sizeof r.d->wrench_ext);
  print_message("freedrive: drift without a wrench over 0.5 s %.2e rad; under [0 40 -30] N for "
                "0.3 s the TCP moved %.1f mm along the force\n", still, 1e3 * along);
  assert_true(still < 1e-3);
  assert_true(along > 5e-3);

  // end: decelerate and hold where it is
  urt_ctrl_cmd_t end = rig_cmd(&r, URT_CTRL_FREEDRIVE);
  end.index = 0;
  rig_period(&r, &end);
  assert_int_equal(r.c->torque_mask, 0);
  run_for(&r, 0.5);
  q_actual(&r, q0);
  run_for(&r, 0.3);
  q_actual(&r, q1);
  print_message("freedrive ended: creep over 0.3 s %.2e rad\n", q_dist(q0, q1));
  assert_int_equal(r.c->motion, URT_MOTION_IDLE);
  assert_true(q_dist(q0, q1) < 1e-4);
  assert_int_equal(r.d->pstop, 0);
  rig_free(&r);
}

static void test_freedrive__held_axes_resist_free_axis_gives_way(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  go_to_work_pose(&r);
  urt_ctrl_cmd_t fd = rig_cmd(&r, URT_CTRL_FREEDRIVE);
  fd.index = 1;
  fd.q[2] = 1.0;  // only z free, in the base frame (pose zeros)
  double p0[6], p1[6];
  tcp_actual(&r, p0);
  rig_period(&r, &fd);
  run_for(&r, 0.3);
  tcp_actual(&r, p1);
  double still = 0.0;
  for (int i = 0; i < 6; i++) {
    still = fmax(still, fabs(p1[i] - p0[i]));
  }
  // held x against a free z: friction makes the shoulder stick below ~50 N
  const double w[6] = {20.0, 0.0, -60.0, 0.0, 0.0, 0.0};
  memcpy(r.d->wrench_ext, w, sizeof w);
  run_for(&r, 0.3);
  tcp_actual(&r, p1);
  const double rot = rot_angle(p0, p1);
  print_message("freedrive z only: still %.2e; under [20 0 -60] N for 0.3 s: z %+.1f mm, x %+.2f "
                "mm, y %+.2f mm, rotation %.2e rad\n",
                still, 1e3 * (p1[2] - p0[2]), 1e3 * (p1[0] - p0[0]), 1e3 * (p1[1] - p0[1]), rot);
  assert_true(still < 1e-4);
  assert_true(p1[2] - p0[2] < -0.02);
  assert_true(fabs(p1[0] - p0[0]) < 5e-3 && fabs(p1[1] - p0[1]) < 5e-3);
  assert_true(rot < 2e-2);  // the held rotation lags while the wrist joints accelerate
  memset(r.d->wrench_ext, 0, sizeof r.d->wrench_ext);
  fd.index = 0;
  rig_period(&r, &fd);
  run_for(&r, 0.3);
  assert_int_equal(r.c->motion, URT_MOTION_IDLE);
  assert_int_equal(r.d->pstop, 0);
  rig_free(&r);
}

static void test_set_gravity__changes_the_controllers_model_not_the_world(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  go_to_work_pose(&r);
  // the controller believes there is no gravity: in freedrive the arm falls (a model off by a
  // little would stick: friction holds up to ~10 N m on the big joints)
  urt_ctrl_cmd_t g = rig_cmd(&r, URT_CTRL_SET_GRAVITY);
  rig_period(&r, &g);
  double z0[6], z1[6];
  tcp_actual(&r, z0);
  urt_ctrl_cmd_t fd = rig_cmd(&r, URT_CTRL_FREEDRIVE);
  fd.index = 1;
  for (int j = 0; j < URT_NJ; j++) {
    fd.q[j] = 1.0;
  }
  rig_period(&r, &fd);
  run_for(&r, 0.3);
  tcp_actual(&r, z1);
  print_message("freedrive with the controller's gravity zero: the TCP sank %.1f mm in 0.3 s\n",
                1e3 * (z0[2] - z1[2]));
  assert_true(z1[2] < z0[2] - 5e-3);
  fd.index = 0;
  rig_period(&r, &fd);
  run_for(&r, 0.3);
  assert_int_equal(r.d->pstop, 0);
  rig_free(&r);
}

//---- servol / servoc ----

static void test_servol__reaches_a_streamed_pose(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  go_to_work_pose(&r);
  double p0[6], goal[6], p[6];
  tcp_actual(&r, p0);
  memcpy(goal, p0, sizeof goal);
  goal[0] += 0.03;
  goal[2] -= 0.02;
  uint64_t id = r.next_id++;
  for (int i = 0; i < 600; i++) {  // 1.2 s of servoL at 500 Hz
    urt_ctrl_cmd_t c;
    memset(&c, 0, sizeof c);
    c.kind = URT_CTRL_SERVOL;
    c.id = id;
    memcpy(c.pose, goal, sizeof c.pose);
    c.t = 0.002;
    c.lookahead_time = 0.1;
    c.gain = 300.0;
    rig_period(&r, &c);
    assert_int_equal(r.c->motion, URT_MOTION_SERVOL);
  }
  tcp_actual(&r, p);
  double err = 0.0;
  for (int i = 0; i < 3; i++) {
    err = fmax(err, fabs(p[i] - goal[i]));
  }
  print_message("servoL 36 mm: position error after 1.2 s %.2e m\n", err);
  assert_true(err < 1e-4);
  run_for(&r, 0.3);  // the stream ended: stopped
  assert_true(r.c->motion_done_id >= id);
  assert_int_equal(r.d->pstop, 0);
  rig_free(&r);
}

static void test_servoc__moves_at_tool_speed_v_to_the_pose(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  go_to_work_pose(&r);
  double p0[6], goal[6], p[6], pa[6];
  tcp_actual(&r, p0);
  memcpy(goal, p0, sizeof goal);
  goal[1] += 0.15;
  urt_ctrl_cmd_t c = rig_cmd(&r, URT_CTRL_SERVOC);
  memcpy(c.pose, goal, sizeof c.pose);
  c.v = 0.1;
  c.a = 1.0;
  rig_period(&r, &c);
  run_for(&r, 0.6);
  tcp_actual(&r, pa);
  run_for(&r, 0.5);
  tcp_actual(&r, p);
  const double v_meas = hypot(hypot(p[0] - pa[0], p[1] - pa[1]), p[2] - pa[2]) / 0.5;
  double t = 1.1;
  while (r.c->motion_done_id < c.id && t < 5.0) {
    rig_period(&r, NULL);
    t += r.c->period;
  }
  run_for(&r, 0.3);
  tcp_actual(&r, p);
  double err = 0.0;
  for (int i = 0; i < 3; i++) {
    err = fmax(err, fabs(p[i] - goal[i]));
  }
  const double ideal = 0.15 / 0.1 + 0.1 / 1.0;
  print_message("servoC 150 mm at v = 0.1 m/s: cruise speed %.4f m/s, done after %.3f s (ideal "
                "%.3f s), position error %.2e m\n", v_meas, t, ideal, err);
  assert_true(fabs(v_meas - 0.1) < 0.005);
  assert_true(fabs(t - ideal) < 0.1);
  assert_true(err < 1e-4);
  assert_int_equal(r.d->pstop, 0);
  rig_free(&r);
}

//---- force mode ----

static void test_force_mode__complies_along_z_and_holds_the_other_axes(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  go_to_work_pose(&r);
  urt_ctrl_cmd_t f = rig_cmd(&r, URT_CTRL_FORCE_MODE);
  f.id = 0;
  f.index = 2;   // task frame = base frame as given
  f.q[2] = 1.0;  // compliant along z
  f.tau[2] = 10.0;  // apply +10 N along z
  const double limits[6] = {0.1, 0.1, 0.2, 0.5, 0.5, 0.5};  // z: speed; others: deviations
  memcpy(f.qd, limits, sizeof f.qd);
  double p0[6], p1[6], p2[6], p3[6];
  tcp_actual(&r, p0);
  rig_period(&r, &f);
  assert_int_equal(r.c->motion, URT_MOTION_FORCE);
  assert_int_equal(snap(&r).control_mode, 2);
  // free air: moves along +z at k·10 N = 0.05 m/s
  run_for(&r, 0.3);
  tcp_actual(&r, p1);
  run_for(&r, 0.2);
  tcp_actual(&r, p2);
  const double vz = (p2[2] - p1[2]) / 0.2;
  // the environment pushes back with the commanded force: rest
  urt_ctrl_cmd_t w = rig_cmd(&r, URT_CTRL_SET_WRENCH);
  w.pose[2] = -10.0;
  rig_period(&r, &w);
  run_for(&r, 0.2);
  tcp_actual(&r, p1);
  run_for(&r, 0.3);
  tcp_actual(&r, p3);
  const double vz_contact = (p3[2] - p1[2]) / 0.3;
  const double dxy = fmax(fabs(p3[0] - p0[0]), fabs(p3[1] - p0[1]));
  const double drot = rot_angle(p0, p3);
  print_message("force mode +10 N z: free-air speed %.4f m/s; against -10 N %.2e m/s; x/y moved "
                "%.2e m, rotation %.2e rad\n", vz, vz_contact, dxy, drot);
  assert_near(vz, 0.05, 0.003);
  assert_true(fabs(vz_contact) < 1e-3);
  assert_true(dxy < 1e-3);
  assert_true(drot < 5e-3);

  // a stronger push wins: moves down
  w.pose[2] = -30.0;
  rig_period(&r, &w);
  run_for(&r, 0.3);
  tcp_actual(&r, p1);
  assert_true(p1[2] < p3[2] - 5e-3);

  // a speedl inside force mode moves the non-compliant axes
  urt_ctrl_cmd_t sl = rig_cmd(&r, URT_CTRL_SPEEDL);
  sl.pose[0] = 0.05;
  sl.a = 0.5;
  rig_period(&r, &sl);
  assert_int_equal(r.c->motion, URT_MOTION_FORCE);
  run_for(&r, 0.4);
  tcp_actual(&r, p2);
  assert_true(p2[0] > p1[0] + 0.01);

  // end: at rest under position control
  urt_ctrl_cmd_t end = rig_cmd(&r, URT_CTRL_FORCE_MODE_END);
  end.id = 0;
  rig_period(&r, &end);
  memset(r.d->wrench_ext, 0, sizeof r.d->wrench_ext);
  run_for(&r, 0.3);
  assert_int_equal(r.c->force_mode, 0);
  assert_int_equal(r.c->motion, URT_MOTION_IDLE);
  assert_int_equal(snap(&r).control_mode, 0);
  assert_int_equal(r.d->pstop, 0);
  rig_free(&r);
}

static void test_force_mode__type_1_pulls_toward_the_frame_origin(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  go_to_work_pose(&r);
  double p0[6], p1[6];
  tcp_actual(&r, p0);
  urt_ctrl_cmd_t f = rig_cmd(&r, URT_CTRL_FORCE_MODE);
  f.id = 0;
  f.index = 1;  // y from the TCP toward the frame's origin
  f.pose[0] = p0[0] + 0.3;
  f.pose[1] = p0[1];
  f.pose[2] = p0[2];
  f.q[1] = 1.0;
  f.tau[1] = 10.0;
  const double limits[6] = {0.1, 0.1, 0.1, 0.5, 0.5, 0.5};
  memcpy(f.qd, limits, sizeof f.qd);
  rig_period(&r, &f);
  run_for(&r, 0.5);
  tcp_actual(&r, p1);
  print_message("force mode type 1, origin 0.3 m along +x, +10 N along y: moved %+.1f %+.1f %+.1f "
                "mm\n", 1e3 * (p1[0] - p0[0]), 1e3 * (p1[1] - p0[1]), 1e3 * (p1[2] - p0[2]));
  assert_true(p1[0] - p0[0] > 0.015);
  assert_true(fabs(p1[1] - p0[1]) < 1e-3 && fabs(p1[2] - p0[2]) < 1e-3);
  urt_ctrl_cmd_t end = rig_cmd(&r, URT_CTRL_FORCE_MODE_END);
  rig_period(&r, &end);
  run_for(&r, 0.2);
  assert_int_equal(r.c->motion, URT_MOTION_IDLE);
  assert_int_equal(r.d->pstop, 0);
  rig_free(&r);
}

//---- real-time rules ----

static void test_modes__no_heap_allocation(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  go_to_work_pose(&r);
  double p[6];
  tcp_actual(&r, p);
  long before = urt_test_malloc_count();
  urt_test_malloc_arm(1);
  urt_ctrl_cmd_t t = rig_cmd(&r, URT_CTRL_TORQUE);
  t.index = 2;
  t.q[5] = t.qd[5] = 0.5;
  rig_period(&r, &t);
  run_for(&r, 0.02);
  urt_ctrl_cmd_t fd = rig_cmd(&r, URT_CTRL_FREEDRIVE);
  fd.index = 1;
  fd.q[0] = 1.0;
  rig_period(&r, &fd);
  fd.index = 0;
  rig_period(&r, &fd);
  urt_ctrl_cmd_t g = rig_cmd(&r, URT_CTRL_SET_GRAVITY);
  g.pose[2] = -9.80;
  rig_period(&r, &g);
  urt_ctrl_cmd_t sl = rig_cmd(&r, URT_CTRL_SERVOL);
  memcpy(sl.pose, p, sizeof p);
  sl.lookahead_time = 0.1;
  sl.gain = 300.0;
  rig_period(&r, &sl);
  urt_ctrl_cmd_t sc = rig_cmd(&r, URT_CTRL_SERVOC);
  memcpy(sc.pose, p, sizeof p);
  sc.pose[0] += 0.01;
  sc.a = 1.0;
  sc.v = 0.1;
  rig_period(&r, &sc);
  run_for(&r, 0.02);
  urt_ctrl_cmd_t f = rig_cmd(&r, URT_CTRL_FORCE_MODE);
  f.index = 2;
  f.q[2] = 1.0;
  f.qd[2] = 0.1;
  rig_period(&r, &f);
  urt_ctrl_cmd_t pa = rig_cmd(&r, URT_CTRL_PAUSE);
  rig_period(&r, &pa);
  urt_ctrl_cmd_t re = rig_cmd(&r, URT_CTRL_RESUME);
  rig_period(&r, &re);
  urt_snapshot_t s;
  urt_snapshot_fill(r.m, r.c, r.d, &s);
  urt_test_malloc_arm(0);
  long calls = urt_test_malloc_count() - before;
  print_message("heap calls in the new modes: %ld\n", calls);
  assert_int_equal(calls, 0);
  assert_int_equal(r.d->pstop, 0);
  rig_free(&r);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_pause__movej_slows_holds_and_resumes_to_the_same_target),
      cmocka_unit_test(test_pause__streaming_stops_and_program_stop_clears_the_pause),
      cmocka_unit_test(test_set_wrench__shows_in_tcp_force_and_bad_values_are_refused),
      cmocka_unit_test(test_set_tool_voltage__kept_shown_and_bad_values_refused),
      cmocka_unit_test(test_set_inputs__masked_levels_shown_and_bad_commands_refused_whole),
      cmocka_unit_test(test_torque__zero_torque_holds_the_arm_against_gravity_then_a_torque_moves_it),
      cmocka_unit_test(test_freedrive__holds_without_a_wrench_and_gives_way_to_one),
      cmocka_unit_test(test_freedrive__held_axes_resist_free_axis_gives_way),
      cmocka_unit_test(test_set_gravity__changes_the_controllers_model_not_the_world),
      cmocka_unit_test(test_servol__reaches_a_streamed_pose),
      cmocka_unit_test(test_servoc__moves_at_tool_speed_v_to_the_pose),
      cmocka_unit_test(test_force_mode__complies_along_z_and_holds_the_other_axes),
      cmocka_unit_test(test_force_mode__type_1_pulls_toward_the_frame_origin),
      cmocka_unit_test(test_modes__no_heap_allocation),
  };
  return cmocka_run_group_tests_name("core/controller_modes", tests, NULL, NULL);
}
