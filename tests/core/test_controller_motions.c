/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_controller_motions.c — the motions added after the motions became objects
 * (core/motion_*.cpp): each against values computed here from its definition, not by the code
 * under test. */
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

/* periods until the id is done (at most t_max) [s] */
static double time_to_done(rig_t *r, const urt_ctrl_cmd_t *cmd, double t_max) {
  rig_period(r, cmd);
  double t = r->c->period;
  while (r->c->motion_done_id < cmd->id && t < t_max) {
    rig_period(r, NULL);
    t += r->c->period;
  }
  return t;
}

/* ---- optimovej ---- */

/* a trapezoid's duration over D at peak speed v and acceleration a (triangle if D < v²/a) */
static double trapezoid_time(double D, double v, double a) {
  return D * a <= v * v ? 2.0 * sqrt(D / a) : D / v + v / a;
}

/* optimovej's "maximum acceleration": along the direction d (largest component 1), what keeps
 * every joint's M(q)·d·A + |g(q)| within 0.6 of its torque_max, the least of the move's start,
 * middle and end (core/controller_internal.hpp), from the model's mass matrix and gravity */
static double torque_accel(const urt_model_t *m, const double *q0, const double *dq) {
  double D = 0.0, A = HUGE_VAL;
  for (int j = 0; j < URT_NJ; j++) D = fmax(D, fabs(dq[j]));
  for (int k = 0; k <= 2; k++) {
    double q[URT_NJ], M[36], g[URT_NJ];
    for (int j = 0; j < URT_NJ; j++) q[j] = q0[j] + 0.5 * k * dq[j];
    urt_arm_mass_matrix(m, q, M);
    urt_arm_gravity(m, q, g);
    for (int i = 0; i < URT_NJ; i++) {
      double md = 0.0;
      for (int j = 0; j < URT_NJ; j++) md += M[i * 6 + j] * dq[j] / D;
      if (fabs(md) > 1e-12) A = fmin(A, fmax(0.6 * m->joint[i].torque_max - fabs(g[i]), 0.0) / fabs(md));
    }
  }
  return fmax(A, 0.1);
}

static void test_optimovej__fractions_of_the_joint_limits_set_the_time(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  const double D = 0.5, fa = 0.3, fv = 0.3;
  urt_ctrl_cmd_t c = rig_cmd(&r, URT_CTRL_OPTIMOVEJ);
  memcpy(c.q, r.c->q1, sizeof c.q);
  c.q[0] += D;       // the leading joint
  c.q[2] -= 0.25;    // half its share
  c.a = fa;
  c.v = fv;
  double vmax = 0.0;
  rig_period(&r, &c);
  double t = r.c->period;
  while (r.c->motion_done_id < c.id && t < 5.0) {
    vmax = fmax(vmax, fabs(r.c->qd1[0]));
    rig_period(&r, NULL);
    t += r.c->period;
  }
  // the planner's margins on the model's limits (0.98 qd_max, 0.9 qdd_max), the acceleration
  // also within what the torques allow
  double q0[URT_NJ], dq[URT_NJ] = {D, 0, -0.25, 0, 0, 0};
  memcpy(q0, c.q, sizeof q0);
  q0[0] -= D;
  q0[2] += 0.25;
  const double A = torque_accel(r.m, q0, dq);
  const double v = fv * 0.98 * r.m->joint[0].qd_max,
               a = fa * fmin(0.9 * r.m->joint[0].qdd_max, A);
  const double T = trapezoid_time(D, v, a);
  print_message("optimovej %.1f/%.1f over %.2f rad: done after %.4f s, trapezoid %.4f s (a %.2f "
                "rad/s², the torques' %.2f); peak set-point speed %.6f rad/s (expected %.6f)\n",
                fa, fv, D, t, T, a, A, vmax, v);
  assert_true(t >= T - 1e-9 && t <= T + 2.0 * r.c->period);
  assert_near(vmax, v, 1e-9);
  assert_near(r.c->q1[0], c.q[0], 1e-12);
  assert_near(r.c->q1[2], c.q[2], 1e-12);
  rig_free(&r);
}

static void test_optimovej__fractions_outside_0_1_are_refused(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  const double bad[][2] = {{0.0, 0.5}, {1.5, 0.5}, {0.5, 0.0}, {0.5, 1.01}, {NAN, 0.5}};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    urt_ctrl_cmd_t c = rig_cmd(&r, URT_CTRL_OPTIMOVEJ);
    memcpy(c.q, r.c->q1, sizeof c.q);
    c.q[1] += 0.1;
    c.a = bad[i][0];
    c.v = bad[i][1];
    rig_period(&r, &c);
    assert_true(r.c->fault & URT_CTRL_FAULT_BAD_ARGUMENT);
    assert_true(r.c->motion_done_id >= c.id);
    assert_int_equal(r.c->motion, URT_MOTION_IDLE);
  }
  // 1.0 is allowed: the full limits
  urt_ctrl_cmd_t c = rig_cmd(&r, URT_CTRL_OPTIMOVEJ);
  memcpy(c.q, r.c->q1, sizeof c.q);
  c.q[5] += 0.2;
  c.a = c.v = 1.0;
  const double dq[URT_NJ] = {0, 0, 0, 0, 0, 0.2};
  const double A = torque_accel(r.m, r.c->q1, dq);
  double t = time_to_done(&r, &c, 3.0);
  const double T =
      trapezoid_time(0.2, 0.98 * r.m->joint[5].qd_max, fmin(0.9 * r.m->joint[5].qdd_max, A));
  print_message("optimovej 1/1 over 0.2 rad: %.4f s, trapezoid %.4f s\n", t, T);
  assert_true(t >= T - 1e-9 && t <= T + 2.0 * r.c->period);
  rig_free(&r);
}

/* optimovej(a=1, v=1) swinging the stretched arm's base and shoulder: UR's optimovej moves "as
 * fast as the robot's limits allow", so the drives' torques stay within torque_max and no
 * protective stop comes (with a = 0.9 qdd_max, before, the set-point asked for 2.4 times the
 * torque_max and the torque limit stopped the arm) */
static void test_optimovej__full_fractions_stay_within_the_torques(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  urt_ctrl_cmd_t c = rig_cmd(&r, URT_CTRL_OPTIMOVEJ);
  const double stretched[URT_NJ] = {0.0, -0.3, 0.3, -1.57, -1.57, 0.0};
  memcpy(c.q, stretched, sizeof c.q);
  c.a = c.v = 0.3;
  time_to_done(&r, &c, 20.0);
  run_for(&r, 0.5);
  c = rig_cmd(&r, URT_CTRL_OPTIMOVEJ);
  memcpy(c.q, stretched, sizeof c.q);
  c.q[0] += 2.0;
  c.q[1] -= 1.2;
  c.a = c.v = 1.0;
  rig_period(&r, &c);
  double peak = 0.0;
  for (int i = 0; i < 5000 && r.c->motion_done_id < c.id; i++) {
    urt_snapshot_t s;
    urt_snapshot_fill(r.m, r.c, r.d, &s);
    for (int j = 0; j < URT_NJ; j++) peak = fmax(peak, fabs(s.m_target[j]) / r.m->joint[j].torque_max);
    rig_period(&r, NULL);
  }
  print_message("optimovej 1/1 swinging the stretched arm: done %d, pstop %#x, peak set-point "
                "torque %.3f of torque_max\n", r.c->motion_done_id >= c.id, r.d->pstop, peak);
  assert_true(r.c->motion_done_id >= c.id);
  assert_int_equal(r.d->pstop, 0);
  assert_true(peak < 1.0);
  rig_free(&r);
}

/* URCL's motion sequence from 5.21 (its execute_motion_sequence test and instruction_executor
 * example): movej, movel t=2, movel t=2 r=0.1, optimovej r=0.1, optimovel to rest, each sent as
 * the program would, once the one before is done (early, inside its blend zone). The pieces
 * hand over without a step in the joints' speeds, and the optimovel brakes to rest: its last
 * period's step to zero joint speed is at most what braking in whole periods leaves (a T, a the
 * deceleration it brakes at), not a jump from speed. Before, the path, held at braking no
 * faster than the last tick's acceleration, reached its end at speed (wrist 2 from 0.41 rad/s
 * to rest in one period: 206 rad/s², 8 times its braking), and its end's limit √(2 a d), taken
 * before each period's travel, left up to 3 a T. */
static void test_optimovel__a_sequence_hands_over_smoothly_and_ends_braked_to_rest(void **state) {
  (void)state;
  const double fr[2][2] = {{0.4, 0.7}, {1.0, 1.0}};
  for (int k = 0; k < 2; k++) {
    rig_t r = rig_new(urt_test_quiet, 0.002, 1);
    const double j0[6] = {-1.57, -1.6, 1.6, -0.7, 0.7, 0.2};
    const double j1[6] = {-1.57, -1.57, 1.6, -0.5, 0.4, 0.3};
    const double l1[6] = {-0.203, 0.263, 0.559, 0.68, -1.083, -2.076};
    const double l2[6] = {-0.203, 0.463, 0.559, 0.68, -1.083, -2.076};
    urt_ctrl_cmd_t seq[5];
    seq[0] = rig_cmd(&r, URT_CTRL_MOVEJ);
    memcpy(seq[0].q, j0, sizeof j0);
    seq[0].a = seq[0].v = 1.0;
    seq[1] = rig_tool_move(&r, URT_CTRL_MOVEL, l1, 1.2, 0.25, 0.0);
    seq[1].t = 2.0;
    seq[2] = rig_tool_move(&r, URT_CTRL_MOVEL, l2, 1.2, 0.25, 0.1);
    seq[2].t = 2.0;
    seq[3] = rig_cmd(&r, URT_CTRL_OPTIMOVEJ);
    memcpy(seq[3].q, j1, sizeof j1);
    seq[3].a = fr[k][0];
    seq[3].v = fr[k][1];
    seq[3].r = 0.1;
    seq[4] = rig_tool_move(&r, URT_CTRL_OPTIMOVEL, l1, fr[k][0], fr[k][1], 0.0);
    enum { kMax = 10000, kLast = 25 };
    double(*qdd)[URT_NJ] = calloc(kMax, sizeof *qdd);
    double last_qd[URT_NJ] = {0};
    int next = 0, n = 0;
    for (int i = 0; i < kMax; i++) {
      const urt_ctrl_cmd_t *cmd = NULL;
      if (next < 5 && (next == 0 || r.c->motion_done_id >= seq[next - 1].id)) cmd = &seq[next++];
      memcpy(last_qd, r.c->qd1, sizeof last_qd);
      rig_period(&r, cmd);
      assert_int_equal(r.c->safety_mode, URT_SAFETY_MODE_NORMAL);
      if (next == 5 && r.c->motion_done_id >= seq[4].id) break;
      memcpy(qdd[n++], r.c->qdd1, sizeof qdd[0]);
    }
    assert_true(next == 5 && r.c->motion_done_id >= seq[4].id && n > kLast);
    // no period's acceleration stands alone: where one piece hands over to the next (a blend
    // to the move after it) the joints' speeds run on, not step. Before, a blend followed by a
    // piece shorter than one period's travel (optimovej between its two blends) was placed
    // beyond that piece's end, and the next blend pulled the arm back: wrist 2 at 128 rad/s²
    // between periods at 2 and 14.
    double spike = 0.0;
    for (int i = 1; i + 1 < n; i++) {
      for (int j = 0; j < URT_NJ; j++) {
        const double around = fmax(fabs(qdd[i - 1][j]), fabs(qdd[i + 1][j]));
        spike = fmax(spike, fabs(qdd[i][j]) - 2.0 * around);
      }
    }
    print_message("fractions %.1f/%.1f: largest acceleration beyond twice its neighbours' %.2f "
                  "rad/s²\n", fr[k][0], fr[k][1], spike);
    assert_true(spike < 5.0);
    // the accelerations of the last 50 ms before the arrival: the braking
    double brake[URT_NJ] = {0};
    for (int i = n - kLast; i < n; i++) {
      for (int j = 0; j < URT_NJ; j++) brake[j] = fmax(brake[j], fabs(qdd[i][j]));
    }
    free(qdd);
    for (int j = 0; j < URT_NJ; j++) {
      const double step = fabs(last_qd[j]) / r.c->period;
      print_message("fractions %.1f/%.1f: joint %d steps to rest at %.1f rad/s², its braking "
                    "in the last 50 ms %.1f\n", fr[k][0], fr[k][1], j, step, brake[j]);
      // braking in whole periods of a·T leaves at most a·T for the last one; an optimovel's
      // a changes along the line (a fifth more here)
      assert_true(step <= 1.2 * brake[j] + 1e-9);
    }
    rig_free(&r);
  }
}

/* ---- speedj from a program that ran late ---- */

/* URCL's spline stream: one speedj(v_n, a = |v_n - v_(n-1)| / T, t = T) per period, v_n the
 * speed of a quintic over N periods on joint 1. skip: periods whose command comes late (each
 * then arrives with the next period's, stamped with the tick it was meant for unless unstamped).
 * Returns joint 1's set-point at the end, after the arm has stopped. */
static double speedj_stream(const int *late, int n_late, int stamped) {
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  const double T = r.c->period, D = 0.4;
  const int N = 500;  // 1 s: URCL's 2 s spline to held_pose peaks at 2.3 rad/s², this at 2.3 too
  const double q_start = r.c->q1[1];
  urt_ctrl_cmd_t held[16];
  int n_held = 0;
  double v_prev = 0.0;
  for (int n = 1; n <= N + 1; n++) {
    const double u = fmin(1.0, n * T / (N * T));
    const double v = D / (N * T) * (30 * u * u - 60 * u * u * u + 30 * u * u * u * u);
    urt_ctrl_cmd_t c = rig_cmd(&r, URT_CTRL_SPEEDJ);
    c.q[1] = v;
    c.a = fmax(fabs(v - v_prev) / T, 1e-9);
    c.t = T;
    c.tick = stamped ? r.c->tick : 0;
    v_prev = v;
    int is_late = 0;
    for (int k = 0; k < n_late; k++) {
      is_late = is_late || late[k] == n;
    }
    if (is_late) {
      held[n_held++] = c;  // the program's thread is descheduled: the controller goes on
      rig_period(&r, NULL);
      continue;
    }
    for (int k = 0; k < n_held; k++) {
      urt_ctrl_apply(r.m, r.c, r.d, &held[k]);  // the missed ticks' commands, all at once
    }
    n_held = 0;
    rig_period(&r, &c);
  }
  run_for(&r, 0.2);
  const double dq = r.c->q1[1] - q_start;
  rig_free(&r);
  return dq;
}

static void test_speedj__a_late_program_stream_ends_where_the_on_time_one_does(void **state) {
  (void)state;
  const double on_time = speedj_stream(NULL, 0, 1);
  // one period late early in the acceleration, then four periods late (five at once)
  const int late[] = {60, 120, 121, 122, 123};
  const double stamped = speedj_stream(late, 5, 1), unstamped = speedj_stream(late, 5, 0);
  print_message("speedj stream of 0.4 rad: on time %.9f rad, late and stamped %.9f (%+.2e), "
                "late without stamps %.9f (%+.2e)\n",
                on_time, stamped, stamped - on_time, unstamped, unstamped - on_time);
  assert_near(on_time, 0.4, 1e-6);
  // what the late periods cost while the arm went on without the program (about L²·a·T² per
  // event; the speed comes back at up to twice the commanded acceleration): 0.46 mrad
  assert_near(stamped, on_time, 1e-3);
  // without the stamps the controller cannot tell, and the lag stays through the acceleration
  assert_true(on_time - unstamped > 10.0 * fabs(on_time - stamped));
}

/* ---- servoj from a program that ran late ---- */

/* ur_rtde's and URCL's servo stream: one servoj(q, t = T, lookahead 0.03, gain 2000) per
 * period, a 0.2 rad, 0.5 Hz sine on joint 0, for N periods; late: as in speedj_stream. Writes
 * joint 0's set-point at the end of each period into q1 and its speed into qd1 (N + 1 values). */
static void servoj_stream(const int *late, int n_late, int stamped, int N, double *q1,
                          double *qd1) {
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  const double T = r.c->period, q_start = r.c->q1[0];
  urt_ctrl_cmd_t held[64];
  int n_held = 0;
  const uint64_t id = r.next_id++;
  for (int n = 0; n <= N; n++) {
    urt_ctrl_cmd_t c;
    memset(&c, 0, sizeof c);
    c.kind = URT_CTRL_SERVOJ;
    c.id = id;
    memcpy(c.q, r.c->q1, sizeof c.q);
    c.q[0] = q_start + 0.2 * sin(2 * M_PI * 0.5 * n * T);
    c.t = T;
    c.lookahead_time = 0.03;
    c.gain = 2000;
    c.tick = stamped ? r.c->tick : 0;
    int is_late = 0;
    for (int k = 0; k < n_late; k++) {
      is_late = is_late || late[k] == n;
    }
    if (is_late) {
      held[n_held++] = c;
      rig_period(&r, NULL);
    } else {
      for (int k = 0; k < n_held; k++) {
        urt_ctrl_apply(r.m, r.c, r.d, &held[k]);
      }
      n_held = 0;
      rig_period(&r, &c);
    }
    q1[n] = r.c->q1[0];
    qd1[n] = r.c->qd1[0];
  }
  rig_free(&r);
}

static void test_servoj__a_late_program_stream_is_re_run_from_its_ticks(void **state) {
  (void)state;
  enum { N = 600 };
  static double on_time[N + 1], stamped[N + 1], unstamped[N + 1], qd_on[N + 1], qd_late[N + 1],
      qd_plain[N + 1];
  servoj_stream(NULL, 0, 1, N, on_time, qd_on);
  // one period late; three (servoj's timeout starts a stop after the third); twelve at once
  int late[32], n_late = 0;
  late[n_late++] = 100;
  for (int n = 200; n < 203; n++) late[n_late++] = n;
  for (int n = 300; n < 312; n++) late[n_late++] = n;
  servoj_stream(late, n_late, 1, N, stamped, qd_late);
  servoj_stream(late, n_late, 0, N, unstamped, qd_plain);
  double after = 0.0, during = 0.0, plain = 0.0, step = 0.0;
  for (int n = 0; n <= N; n++) {
    int is_late = 0;
    for (int k = 0; k < n_late; k++) {
      is_late = is_late || late[k] == n;
    }
    const double e = fabs(stamped[n] - on_time[n]);
    if (is_late) {
      during = fmax(during, e);
    } else {
      after = fmax(after, e);
      if (n > 0) {
        // the speed step a burst's replay makes, beyond the on-time stream's own change
        step = fmax(step, fabs((qd_late[n] - qd_late[n - 1]) - (qd_on[n] - qd_on[n - 1])));
      }
    }
    plain = fmax(plain, fabs(unstamped[n] - on_time[n]));
  }
  print_message("servoj stream, late 1, 3 and 12 periods: set-point off the on-time stream by "
                "%.2e rad while late, %.2e once the commands arrived (without stamps %.2e); "
                "speed step of a replay %.2e rad/s\n",
                during, after, plain, step);
  // once a burst has arrived the set-point is the on-time stream's, to rounding
  assert_true(after < 1e-12);
  // within one period of the law's largest acceleration (else it is not replayed)
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  assert_true(step <= 0.9 * r.m->joint[0].qdd_max * r.c->period + 1e-12);
  rig_free(&r);
  assert_true(during > 1e-6 && plain > 1e-5);
}

static void test_servoj__a_late_jump_is_not_re_run(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  const uint64_t id = r.next_id++;
  urt_ctrl_cmd_t c;
  memset(&c, 0, sizeof c);
  c.kind = URT_CTRL_SERVOJ;
  c.id = id;
  memcpy(c.q, r.c->q1, sizeof c.q);
  c.t = r.c->period;
  c.lookahead_time = 0.03;
  c.gain = 2000;
  for (int n = 0; n < 10; n++) {  // a stream holding still
    c.tick = r.c->tick;
    rig_period(&r, &c);
  }
  // URCL's target_outside_limits_servoj: 2.5 rad on the wrist, here issued 2 periods ago (the
  // stream still runs: its timeout would stop it after 3)
  c.tick = r.c->tick;
  c.q[5] -= 2.5;
  for (int n = 0; n < 2; n++) {
    rig_period(&r, NULL);
  }
  rig_period(&r, &c);
  const double bound = 0.9 * r.m->joint[5].qdd_max * r.c->period;
  print_message("servoj 2.5 rad jump, 2 periods late: set-point speed %.4f rad/s after its first "
                "period (one period of the largest acceleration: %.4f)\n", r.c->qd1[5], bound);
  assert_true(fabs(r.c->qd1[5]) <= bound + 1e-12);
  rig_free(&r);
}

/* ---- a program's speedj whose t runs out while the program's thread is behind ---- */

/* joint 1's set-point speed per period: a speedj(0.3 rad/s, a = 6, t = 0.1) issued by a
 * program (stamped) or not; then no command. behind: the controller sees the program's thread
 * stuck at the speedj's slice (urt_ctrl_t.program_slice, as the loop sets it); else it sees
 * each slice delivered on time. */
static void speedj_then_silence(int stamped, int behind, double *qd, int n) {
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  run_for(&r, 0.01);  // (tick 0 is no tick: a stamp of 0 means not a program's)
  urt_ctrl_cmd_t c = rig_cmd(&r, URT_CTRL_SPEEDJ);
  c.q[1] = 0.3;
  c.a = 6.0;
  c.t = 0.1;
  c.tick = stamped ? r.c->tick : 0;
  const uint64_t issued = r.c->tick;
  for (int k = 0; k < n; k++) {
    r.c->program_slice = !stamped ? 0 : behind ? issued : r.c->tick;
    rig_period(&r, k == 0 ? &c : NULL);
    qd[k] = r.c->qd1[1];
  }
  rig_free(&r);
}

static void test_speedj__runs_on_while_the_program_is_behind(void **state) {
  (void)state;
  enum { N = 120, RUN_ON = 12 };  // 25 ms at 2 ms: 12 periods
  double plain[N], on_time[N], behind[N];
  speedj_then_silence(0, 0, plain, N);
  speedj_then_silence(1, 0, on_time, N);
  speedj_then_silence(1, 1, behind, N);
  // t runs out after 50 periods: then the stop at a (0.3 / 6 = 50 ms) begins
  assert_near(plain[49], 0.3, 1e-12);
  assert_near(plain[50], 0.3 - 6.0 * 0.002, 1e-12);
  assert_true(plain[N - 1] == 0.0);
  // a program on time: the same set-points, period by period
  for (int k = 0; k < N; k++) {
    if (on_time[k] != plain[k]) fail_msg("period %d: on time %.17g, plain %.17g", k, on_time[k], plain[k]);
  }
  // a program behind: its speed held for 25 ms more, then the same stop
  for (int k = 0; k < N; k++) {
    const double want = k < 50 ? plain[k] : k < 50 + RUN_ON ? 0.3 : plain[k - RUN_ON];
    if (behind[k] != want) fail_msg("period %d: behind %.17g, want %.17g", k, behind[k], want);
  }
}

/* ---- speedj's trajectory limiter ---- */

/* a goal beyond the joints' speed limits runs at the limit, in the commanded direction, with
 * the fraction reported as speed_scaling: no protective stop (URCL's zero_time spline tests
 * send such a segment and expect SUCCESS) */
static void test_speedj__a_goal_beyond_the_limits_is_scaled_down_to_them(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  const double qd[URT_NJ] = {2.4, -0.2, -5.6, 1.2, 4.8, -0.75};
  // the elbow is the furthest over its limit: every joint gets its fraction
  double f = 1.0;
  for (int j = 0; j < URT_NJ; j++) {
    f = fmin(f, r.m->joint[j].qd_max / fabs(qd[j]));
  }
  urt_ctrl_cmd_t c = rig_cmd(&r, URT_CTRL_SPEEDJ);
  memcpy(c.q, qd, sizeof c.q);
  c.a = 40.0;
  c.t = 0.3;
  rig_period(&r, &c);
  double vmax_ratio = 0.0, off = 0.0;
  for (int k = 0; k < 100; k++) {  // 0.2 s: past the ramp (5.6 · f / 40 ≈ 79 ms), inside t
    rig_period(&r, NULL);
    for (int j = 0; j < URT_NJ; j++) {
      vmax_ratio = fmax(vmax_ratio, fabs(r.c->qd1[j]) / r.m->joint[j].qd_max);
    }
  }
  for (int j = 0; j < URT_NJ; j++) {
    off = fmax(off, fabs(r.c->qd1[j] - f * qd[j]));
  }
  urt_snapshot_t s;
  urt_snapshot_fill(r.m, r.c, r.d, &s);
  print_message("speedj 5.6 rad/s on the elbow: limiter fraction %.6f, speeds off the scaled goal "
                "%.2e rad/s, fastest joint at %.6f of its limit, speed_scaling %.6f, pstop 0x%x\n",
                f, off, vmax_ratio, s.speed_scaling, (unsigned)r.d->pstop);
  assert_int_equal(r.d->pstop, 0);
  assert_int_equal(r.c->motion, URT_MOTION_SPEEDJ);
  assert_true(off < 1e-12);
  assert_true(vmax_ratio <= 1.0);
  assert_near(s.speed_scaling, f, 1e-12);
  // motion time (speedj's t, the VM's waits) still runs at the slider's rate: the limiter
  // slows the arm, not the program (a VM counting in speed_scaling fell behind URCL's spline)
  assert_near(s.motion_rate, 1.0, 0.0);
  // URCL's spline as it runs: one speedj(qd, |Δqd|/T, T) per period, the elbow's speed rising
  // past its limit (a 3.746 rad cubic segment of 1 s); a scaled goal must never round above the
  // limit (one did, at 3.40 rad/s: a protective stop, speed limit); from rest, on a new rig
  rig_free(&r);
  r = rig_new(urt_test_quiet, 0.002, 1);
  double prev = 0.0;
  int stopped_at = -1;
  for (int k = 1; k < 250 && stopped_at < 0; k++) {
    const double tau = k * r.c->period, v = -6.0 * 3.746 * (tau - tau * tau);
    urt_ctrl_cmd_t st = rig_cmd(&r, URT_CTRL_SPEEDJ);
    st.q[2] = v;
    st.a = fmax(fabs(v - prev) / r.c->period, 1e-9);
    st.t = r.c->period;
    prev = v;
    rig_period(&r, &st);
    if (r.d->pstop) {
      stopped_at = k;
    }
  }
  print_message("spline-like stream up to 5.6 rad/s on the elbow: pstop after %d periods (-1: none), "
                "elbow at %.9f rad/s\n", stopped_at, r.c->qd1[2]);
  assert_int_equal(stopped_at, -1);
  assert_true(fabs(r.c->qd1[2]) <= r.m->joint[2].qd_max);
  // within the limits nothing is scaled and speed_scaling is the slider's again
  urt_ctrl_cmd_t slow = rig_cmd(&r, URT_CTRL_SPEEDJ);
  slow.q[0] = 0.3;
  slow.a = 40.0;
  slow.t = 0.1;
  rig_period(&r, &slow);
  urt_snapshot_fill(r.m, r.c, r.d, &s);
  assert_near(s.speed_scaling, 1.0, 0.0);
  rig_free(&r);
}

/* ---- movel's trajectory limiter ---- */

/* a movel whose t asks more of the joints than they can give is slowed down to them and ends
 * at its target (URCL's unfeasible_times_succeeds: moveL with t = 0.1 s must succeed), where
 * before the set-point ran past qd_max and stopped the arm */
static void test_movel__a_t_too_short_for_the_joints_is_slowed_down_to_them(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  const double zero_tcp[6] = {0};
  double p0[6], p1[6];
  urt_ctrl_forward_kinematics_tcp(r.m, zero_tcp, r.c->q1, p0);
  memcpy(p1, p0, sizeof p1);
  p1[0] += 0.3;  // 30 cm in 0.1 s: 4.5 m/s peak on a triangle
  p1[2] -= 0.1;
  urt_ctrl_cmd_t c = rig_cmd(&r, URT_CTRL_MOVEL);
  memcpy(c.pose, p1, sizeof c.pose);
  c.a = 1.4;
  c.v = 1.04;
  c.t = 0.1;
  double peak = 0.0;
  const double t = time_to_done(&r, &c, 5.0);
  // time_to_done ran the motion; the peak is read from a second, identical move back and forth
  double pe[6];
  urt_ctrl_forward_kinematics_tcp(r.m, zero_tcp, r.c->q1, pe);
  double off = 0.0;
  for (int i = 0; i < 3; i++) {
    off = fmax(off, fabs(pe[i] - p1[i]));
  }
  urt_ctrl_cmd_t back = rig_cmd(&r, URT_CTRL_MOVEL);
  memcpy(back.pose, p0, sizeof back.pose);
  back.a = 1.4;
  back.v = 1.04;
  back.t = 0.1;
  rig_period(&r, &back);
  double t_back = r.c->period;
  while (r.c->motion_done_id < back.id && t_back < 5.0) {
    for (int j = 0; j < URT_NJ; j++) {
      peak = fmax(peak, fabs(r.c->qd1[j]) / r.m->joint[j].qd_max);
    }
    rig_period(&r, NULL);
    t_back += r.c->period;
  }
  print_message("movel 0.32 m with t = 0.1 s: done after %.3f s (back %.3f s), end off %.2e m, "
                "fastest joint at %.3f of qd_max, pstop 0x%x\n",
                t, t_back, off, peak, (unsigned)r.d->pstop);
  assert_int_equal(r.d->pstop, 0);
  assert_true(t > 0.1 && t < 5.0);
  assert_true(off < 1e-6);
  assert_true(peak <= 1.0);
  rig_free(&r);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_optimovej__fractions_of_the_joint_limits_set_the_time),
      cmocka_unit_test(test_optimovej__fractions_outside_0_1_are_refused),
      cmocka_unit_test(test_optimovej__full_fractions_stay_within_the_torques),
      cmocka_unit_test(test_optimovel__a_sequence_hands_over_smoothly_and_ends_braked_to_rest),
      cmocka_unit_test(test_speedj__a_late_program_stream_ends_where_the_on_time_one_does),
      cmocka_unit_test(test_speedj__runs_on_while_the_program_is_behind),
      cmocka_unit_test(test_speedj__a_goal_beyond_the_limits_is_scaled_down_to_them),
      cmocka_unit_test(test_servoj__a_late_program_stream_is_re_run_from_its_ticks),
      cmocka_unit_test(test_servoj__a_late_jump_is_not_re_run),
      cmocka_unit_test(test_movel__a_t_too_short_for_the_joints_is_slowed_down_to_them),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
