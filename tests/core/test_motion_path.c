/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_motion_path.c — core/motion_path.cpp: blend radius on movej/movel, movep,
 * movec, optimovel. Each check is against a value computed here from the definition (the
 * circle through three points, the arc tangent to two lines, the joints' limits), not by the
 * code under test. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "controller_harness.h"
#include "test_model.h"
#include "test_support.h"
#include "urt/controller.h"
#include "urt/core.h"

static const double kWork[URT_NJ] = {0.0, -1.9, 1.9, -1.57, -1.57, 0.0};

static void go_work(rig_t *r) {
  urt_ctrl_cmd_t c = rig_cmd(r, URT_CTRL_MOVEJ);
  memcpy(c.q, kWork, sizeof c.q);
  c.a = 3.0;
  c.v = 2.0;
  rig_period(r, &c);
  for (int i = 0; i < 5000 && r->c->motion_done_id < c.id; i++) {
    rig_period(r, NULL);
  }
  run_for(r, 0.1);
}

static void tcp_set(const rig_t *r, double pose[6]) {
  urt_ctrl_forward_kinematics_tcp(r->m, r->c->tcp_offset, r->c->q1, pose);
}

static double dist3(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}

static double max_abs_qd(const rig_t *r) {
  double v = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    v = fmax(v, fabs(r->c->qd1[j]));
  }
  return v;
}

/* what a run of periods went through: TCP set-points and speeds */
#define NREC 20000
typedef struct rec {
  int n;
  double qdd_max;  /* the largest set-point acceleration of any joint [rad/s²] */
  double p[NREC][3];
  double qd[NREC];
  double R[NREC][9];
} rec_t;

/* the rotation matrix of a pose's rotation vector (Rodrigues), row-major */
static void rotm(const double pose[6], double *R) {
  double th = sqrt(pose[3] * pose[3] + pose[4] * pose[4] + pose[5] * pose[5]);
  double ax[3] = {0, 0, 1};
  if (th > 0) {
    ax[0] = pose[3] / th;
    ax[1] = pose[4] / th;
    ax[2] = pose[5] / th;
  }
  double c = cos(th), s = sin(th), C = 1 - c;
  R[0] = c + ax[0] * ax[0] * C;
  R[1] = ax[0] * ax[1] * C - ax[2] * s;
  R[2] = ax[0] * ax[2] * C + ax[1] * s;
  R[3] = ax[1] * ax[0] * C + ax[2] * s;
  R[4] = c + ax[1] * ax[1] * C;
  R[5] = ax[1] * ax[2] * C - ax[0] * s;
  R[6] = ax[2] * ax[0] * C - ax[1] * s;
  R[7] = ax[2] * ax[1] * C + ax[0] * s;
  R[8] = c + ax[2] * ax[2] * C;
}

static void record(rec_t *k, const rig_t *r) {
  if (k->n >= NREC) return;
  double pose[6];
  tcp_set(r, pose);
  memcpy(k->p[k->n], pose, 3 * sizeof(double));
  k->qd[k->n] = max_abs_qd(r);
  for (int j = 0; j < URT_NJ; j++) {
    k->qdd_max = fmax(k->qdd_max, fabs(r->c->qdd1[j]));
  }
  rotm(pose, k->R[k->n]);
  k->n++;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* send cmd, record until its id is done (and, if wait_idle, until the motion is over); the
 * wall time of the period that took the command (planning, and queueing a blend) is printed,
 * not asserted */
static void run_cmd(rig_t *r, const urt_ctrl_cmd_t *cmd, rec_t *k, int wait_idle) {
  const double t0 = now_s();
  rig_period(r, cmd);
  print_message("  the period taking command kind %d (r %.3f): %.1f us, physics included\n",
                cmd->kind, cmd->r, 1e6 * (now_s() - t0));
  record(k, r);
  for (int i = 0; i < 10000 && (r->c->motion_done_id < cmd->id ||
                                (wait_idle && r->c->motion != URT_MOTION_IDLE));
       i++) {
    rig_period(r, NULL);
    record(k, r);
  }
}

/* two tool lines at a right angle (x then y) with blend radius rad: the blend is the arc of
 * radius d / tan(45°) = d tangent to both, entering and leaving d from the via point; d is rad
 * shrunk to half a line's length (UR's motion version 2) */
static void corner(int kind, double len, double rad, double v, double d_expect) {
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  go_work(&r);
  static rec_t k;
  k.n = 0;
  k.qdd_max = 0.0;
  double p0[6], via[6], to[6];
  tcp_set(&r, p0);
  memcpy(via, p0, sizeof via);
  via[0] += len;
  memcpy(to, via, sizeof to);
  to[1] += len;
  urt_ctrl_cmd_t a = rig_tool_move(&r, kind, via, 1.2, v, rad);
  urt_ctrl_cmd_t b = rig_tool_move(&r, kind, to, 1.2, v, 0.0);
  run_cmd(&r, &a, &k, 0);
  const int n_a = k.n;
  assert_int_equal(r.c->motion, URT_MOTION_PATH);  // done early, still moving
  assert_true(max_abs_qd(&r) > 0.05);
  run_cmd(&r, &b, &k, 1);
  // the arc's centre: d back along x from the via point, then d along y
  const double d = d_expect, centre[3] = {via[0] - d, via[1] + d, via[2]};
  double dmin = 1e9, worst = 0.0, qd_min = 1e9, v_dev = 0.0;
  int on_arc = 0;
  for (int i = 1; i < k.n; i++) {
    const double dv = dist3(k.p[i], via);
    dmin = fmin(dmin, dv);
    if (dv < 0.98 * d) {  // inside the blend zone: on the arc
      worst = fmax(worst, fabs(dist3(k.p[i], centre) - d));
      worst = fmax(worst, fabs(k.p[i][2] - via[2]));
      on_arc++;
    }
    if (dv < d) {  // near the via point the joints never come to rest
      qd_min = fmin(qd_min, k.qd[i]);
    }
  }
  // tool speed on the straight parts and the arc once at cruise (movep: constant)
  const double t_acc = v / 1.2;
  const int i0 = (int)(t_acc / 0.002) + 3, i1 = k.n - i0 - 3;
  for (int i = i0; i < i1; i++) {
    v_dev = fmax(v_dev, fabs(dist3(k.p[i], k.p[i - 1]) / 0.002 - v));
  }
  double end[6];
  tcp_set(&r, end);
  print_message("%s corner %.2f m, r %.3f: %d periods to A's done, %d in all, %d on the arc; "
                "closest to the via point %.5f m (d %.4f), off the arc %.2e m, min |qd| within "
                "d %.4f rad/s, tool speed off %.2e m/s, end off %.2e m\n",
                kind == URT_CTRL_MOVEP ? "movep" : "movel", len, rad, n_a, k.n, on_arc, dmin, d,
                worst, qd_min, v_dev, dist3(end, to));
  print_message("  largest joint set-point acceleration %.2f rad/s²\n", k.qdd_max);
  assert_true(k.qdd_max < 20.0);  // no jump in speed anywhere (a late slow-down gave 140)
  assert_true(on_arc > 10);
  assert_true(dmin < d && dmin > 0.2 * d);  // passes inside the radius, not through the point
  assert_true(worst < 1e-6);
  assert_true(qd_min > 0.1);  // never at rest at the via point
  if (kind == URT_CTRL_MOVEP) {
    assert_true(v_dev < 2e-3 * v);
  }
  assert_true(dist3(end, to) < 1e-8);
  assert_true(max_abs_qd(&r) == 0.0);
  assert_int_equal(r.c->motion, URT_MOTION_IDLE);
  rig_free(&r);
}

static void test_blend__movel_corner_is_the_arc_tangent_to_both_lines(void **state) {
  (void)state;
  corner(URT_CTRL_MOVEL, 0.2, 0.05, 0.25, 0.05);
}

static void test_blend__radius_over_half_the_segment_shrinks_to_half(void **state) {
  (void)state;
  corner(URT_CTRL_MOVEL, 0.12, 0.3, 0.2, 0.06);
}

static void test_movep__constant_tool_speed_through_a_circular_blend(void **state) {
  (void)state;
  corner(URT_CTRL_MOVEP, 0.2, 0.03, 0.1, 0.03);
}

/* the tool's angular velocity between two recorded set-points i-1, i (base frame) [rad/s] */
static void angular_velocity(const rec_t *k, int i, double dt, double w[3]) {
  const double *A = k->R[i], *B = k->R[i - 1];
  double D[9];  // A B^T
  for (int r = 0; r < 3; r++) {
    for (int c = 0; c < 3; c++) {
      D[3 * r + c] = A[3 * r] * B[3 * c] + A[3 * r + 1] * B[3 * c + 1] + A[3 * r + 2] * B[3 * c + 2];
    }
  }
  const double cth = fmax(-1.0, fmin(1.0, 0.5 * (D[0] + D[4] + D[8] - 1.0)));
  const double th = acos(cth), f = th > 1e-12 ? th / (2.0 * sin(th)) : 0.5;
  w[0] = f * (D[7] - D[5]) / dt;
  w[1] = f * (D[2] - D[6]) / dt;
  w[2] = f * (D[3] - D[1]) / dt;
}

/* A movel that turns the tool (0.6 rad about the base z while it runs 0.2 m along x) blends
 * (r = 0.05) into one that only translates (0.2 m along y): the blend turns the tool from A's
 * angular velocity to B's (none) without a step. Before, the blend turned it at one constant
 * rate of its own, so the angular velocity stepped where the blend began and where it ended. */
static void test_blend__a_turning_line_into_a_straight_one_turns_the_tool_without_a_step(
    void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  go_work(&r);
  static rec_t k;
  k.n = 0;
  k.qdd_max = 0.0;
  double p0[6], via[6], to[6], R0[9];
  tcp_set(&r, p0);
  rotm(p0, R0);
  // the tool turned 0.6 rad about the base z: rotation vector of Rz(0.6)·R0
  const double c = cos(0.6), sn = sin(0.6);
  double R1[9];
  for (int j = 0; j < 3; j++) {
    R1[j] = c * R0[j] - sn * R0[3 + j];
    R1[3 + j] = sn * R0[j] + c * R0[3 + j];
    R1[6 + j] = R0[6 + j];
  }
  const double th = acos(fmax(-1.0, fmin(1.0, 0.5 * (R1[0] + R1[4] + R1[8] - 1.0))));
  const double f = th / (2.0 * sin(th));
  memcpy(via, p0, sizeof via);
  via[0] += 0.2;
  via[3] = f * (R1[7] - R1[5]);
  via[4] = f * (R1[2] - R1[6]);
  via[5] = f * (R1[3] - R1[1]);
  memcpy(to, via, sizeof to);
  to[1] += 0.2;
  urt_ctrl_cmd_t a = rig_tool_move(&r, URT_CTRL_MOVEL, via, 1.2, 0.25, 0.05);
  urt_ctrl_cmd_t b = rig_tool_move(&r, URT_CTRL_MOVEL, to, 1.2, 0.25, 0.0);
  run_cmd(&r, &a, &k, 0);
  run_cmd(&r, &b, &k, 1);
  // the largest change of the angular velocity from one period to the next, and A's own rate
  double w_prev[3], w[3], step = 0.0, w_max = 0.0;
  angular_velocity(&k, 1, 0.002, w_prev);
  for (int i = 2; i < k.n; i++) {
    angular_velocity(&k, i, 0.002, w);
    const double dw = sqrt((w[0] - w_prev[0]) * (w[0] - w_prev[0]) +
                           (w[1] - w_prev[1]) * (w[1] - w_prev[1]) +
                           (w[2] - w_prev[2]) * (w[2] - w_prev[2]));
    step = fmax(step, dw);
    w_max = fmax(w_max, sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]));
    memcpy(w_prev, w, sizeof w);
  }
  print_message("turning movel into a straight one: angular speed up to %.3f rad/s, its largest "
                "change in one period %.4f rad/s (%.1f rad/s²); joints' largest acceleration "
                "%.1f rad/s²\n", w_max, step, step / 0.002, k.qdd_max);
  // A turns at 0.6 rad / 0.2 m · 0.25 m/s = 0.75 rad/s and accelerates with the tool at
  // 1.2 m/s² (4.5 rad/s², 0.009 rad/s a period); a step is a good part of the 0.75
  assert_true(w_max > 0.7);
  assert_true(step < 0.05);
  assert_true(k.qdd_max < 20.0);  // and so do the joints (before: 238 rad/s²)
  double end[6];
  tcp_set(&r, end);
  assert_true(dist3(end, to) < 1e-8);
  rig_free(&r);
}

static void test_blend__movej_passes_within_r_without_stopping(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  go_work(&r);
  static rec_t k;
  k.n = 0;
  k.qdd_max = 0.0;
  double q1[URT_NJ], q2[URT_NJ], via[6], to[6];
  memcpy(q1, kWork, sizeof q1);
  q1[0] += 0.5;
  memcpy(q2, q1, sizeof q2);
  q2[1] += 0.4;
  urt_ctrl_forward_kinematics_tcp(r.m, r.c->tcp_offset, q1, via);
  urt_ctrl_forward_kinematics_tcp(r.m, r.c->tcp_offset, q2, to);
  urt_ctrl_cmd_t a = rig_cmd(&r, URT_CTRL_MOVEJ), b = rig_cmd(&r, URT_CTRL_MOVEJ);
  memcpy(a.q, q1, sizeof a.q);
  memcpy(b.q, q2, sizeof b.q);
  a.a = b.a = 1.4;
  a.v = b.v = 1.05;
  a.r = 0.05;
  run_cmd(&r, &a, &k, 0);
  run_cmd(&r, &b, &k, 1);
  double dmin = 1e9, qd_min = 1e9;
  for (int i = 0; i < k.n; i++) {
    dmin = fmin(dmin, dist3(k.p[i], via));
    if (dist3(k.p[i], via) < 0.05) qd_min = fmin(qd_min, k.qd[i]);
  }
  print_message("movej blend r 0.05: %d periods, closest to the via point %.5f m, min |qd| "
                "within r %.4f rad/s, end off %.2e rad\n",
                k.n, dmin, qd_min, fabs(r.c->q1[1] - q2[1]));
  assert_true(dmin < 0.05 && dmin > 0.002);
  assert_true(qd_min > 0.1);
  for (int j = 0; j < URT_NJ; j++) assert_near(r.c->q1[j], q2[j], 1e-12);
  rig_free(&r);
}

/* a joint move and a tool move, both ways, and a movec into a movel: a joint-space blend between
 * the points where the TCP is d from the via point; the path passes inside r, the joints never
 * rest near the via point, the last move ends on its target */
static void mixed_case(int kind_a, int kind_b, double rad) {
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  go_work(&r);
  static rec_t k;
  k.n = 0;
  k.qdd_max = 0.0;
  double p0[6], via[6], to[6];
  tcp_set(&r, p0);
  memcpy(via, p0, sizeof via);
  via[0] += 0.15;
  memcpy(to, via, sizeof to);
  to[1] += 0.15;
  to[2] -= 0.05;
  urt_ctrl_cmd_t a = rig_cmd(&r, kind_a), b = rig_cmd(&r, kind_b);
  double qv[URT_NJ], qt[URT_NJ];
  assert_int_equal(urt_ctrl_inverse_kinematics_tcp(r.m, r.c->tcp_offset, via, r.c->q1, qv), 0);
  assert_int_equal(urt_ctrl_inverse_kinematics_tcp(r.m, r.c->tcp_offset, to, qv, qt), 0);
  if (kind_a == URT_CTRL_MOVEJ) {
    memcpy(a.q, qv, sizeof a.q);
    a.a = 1.4;
    a.v = 0.6;
  } else {
    memcpy(a.pose, via, sizeof a.pose);
    a.a = 1.2;
    a.v = 0.25;
  }
  if (kind_a == URT_CTRL_MOVEC) {  // an arc bulging along -y through the via point's x
    a.q[0] = p0[0] + 0.075;
    a.q[1] = p0[1] - 0.03;
    a.q[2] = p0[2];
  }
  a.r = rad;
  if (kind_b == URT_CTRL_MOVEJ) {
    memcpy(b.q, qt, sizeof b.q);
    b.a = 1.4;
    b.v = 0.6;
  } else {
    memcpy(b.pose, to, sizeof b.pose);
    // optimovel: fractions (of qdd_max, which the test model keeps at a sanity bound of 100
    // rad/s²: a = 0.5 would ask for more torque than the drives have)
    b.a = kind_b == URT_CTRL_OPTIMOVEL ? 0.1 : 1.2;
    b.v = kind_b == URT_CTRL_OPTIMOVEL ? 0.2 : 0.25;
  }
  run_cmd(&r, &a, &k, 0);
  run_cmd(&r, &b, &k, 1);
  double dmin = 1e9, qd_min = 1e9, end[6];
  for (int i = 0; i < k.n; i++) {
    const double dv = dist3(k.p[i], via);
    dmin = fmin(dmin, dv);
    if (dv < rad) qd_min = fmin(qd_min, k.qd[i]);
  }
  tcp_set(&r, end);
  print_message("blend kind %d -> %d, r %.3f: %d periods, closest to the via point %.5f m, "
                "min |qd| within r %.4f rad/s, end off %.2e m\n",
                kind_a, kind_b, rad, k.n, dmin, qd_min, dist3(end, to));
  print_message("  largest joint set-point acceleration %.2f rad/s²\n", k.qdd_max);
  assert_true(k.qdd_max < 20.0);
  assert_true(dmin < rad && dmin > 0.05 * rad);
  assert_true(qd_min > 0.05);
  assert_true(dist3(end, to) < 1e-8);
  assert_int_equal(r.c->motion, URT_MOTION_IDLE);
  assert_int_equal(r.d->pstop, 0);
  rig_free(&r);
}

static void test_blend__movej_into_movel(void **state) {
  (void)state;
  mixed_case(URT_CTRL_MOVEJ, URT_CTRL_MOVEL, 0.04);
}

static void test_blend__movel_into_movej(void **state) {
  (void)state;
  mixed_case(URT_CTRL_MOVEL, URT_CTRL_MOVEJ, 0.04);
}

static void test_blend__movec_into_movel(void **state) {
  (void)state;
  mixed_case(URT_CTRL_MOVEC, URT_CTRL_MOVEL, 0.03);
}

static void test_blend__movel_into_optimovel(void **state) {
  (void)state;
  mixed_case(URT_CTRL_MOVEL, URT_CTRL_OPTIMOVEL, 0.04);
}

/* a pair that is not blended (a pure rotation first): the move stops at its target, at rest,
 * and the next one starts from there */
static void test_blend__a_pure_rotation_stops_at_its_target_then_the_next_starts(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  go_work(&r);
  double p[6], rot[6], to[6];
  tcp_set(&r, p);
  memcpy(rot, p, sizeof rot);
  rot[5] += 0.3;  // about the base z: the TCP does not move
  urt_ctrl_cmd_t a = rig_tool_move(&r, URT_CTRL_MOVEL, rot, 1.0, 0.5, 0.05);
  rig_period(&r, &a);
  for (int i = 0; i < 5000 && r.c->motion_done_id < a.id; i++) rig_period(&r, NULL);
  tcp_set(&r, to);
  memcpy(to, rot, 3 * sizeof(double));
  to[0] += 0.1;
  urt_ctrl_cmd_t b = rig_tool_move(&r, URT_CTRL_MOVEL, to, 1.2, 0.25, 0.0);
  rig_period(&r, &b);
  // until the arm rests at a's target; b is queued meanwhile
  int rested = 0;
  double at_rest[6];
  for (int i = 0; i < 5000 && r.c->motion_done_id < b.id; i++) {
    rig_period(&r, NULL);
    if (!rested && max_abs_qd(&r) == 0.0) {
      rested = 1;
      tcp_set(&r, at_rest);
    }
  }
  double end[6];
  tcp_set(&r, end);
  print_message("pure rotation r 0.05 then movel: rested %.2e m from the rotation's target, end "
                "off %.2e m\n",
                rested ? dist3(at_rest, rot) : -1.0, dist3(end, to));
  assert_true(rested);
  assert_true(dist3(at_rest, rot) < 1e-8);
  assert_true(dist3(end, to) < 1e-8);
  rig_free(&r);
}

/* HALT while a move runs with the next one queued behind it: both ids are done, the arm stops */
static void test_blend__halt_ends_the_move_and_the_queued_one(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  go_work(&r);
  double p[6], via[6], to[6];
  tcp_set(&r, p);
  memcpy(via, p, sizeof via);
  via[0] += 0.2;
  memcpy(to, via, sizeof to);
  to[1] += 0.2;
  urt_ctrl_cmd_t a = rig_tool_move(&r, URT_CTRL_MOVEL, via, 1.2, 0.25, 0.05);
  urt_ctrl_cmd_t b = rig_tool_move(&r, URT_CTRL_MOVEL, to, 1.2, 0.25, 0.0);
  rig_period(&r, &a);
  run_for(&r, 0.1);
  rig_period(&r, &b);  // early: queued behind a
  assert_true(r.c->motion_done_id < b.id);
  assert_int_equal(r.c->has_pending, 1);
  urt_ctrl_cmd_t h = rig_cmd(&r, URT_CTRL_HALT);
  rig_period(&r, &h);
  assert_true(r.c->motion_done_id >= b.id);
  run_for(&r, 0.5);
  assert_true(max_abs_qd(&r) == 0.0);
  assert_int_equal(r.c->motion, URT_MOTION_IDLE);
  rig_free(&r);
}

static void test_blend__the_last_move_stops_at_its_target(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  go_work(&r);
  static rec_t k;
  k.n = 0;
  k.qdd_max = 0.0;
  double p[6], end[6];
  tcp_set(&r, p);
  p[2] += 0.1;
  urt_ctrl_cmd_t a = rig_tool_move(&r, URT_CTRL_MOVEL, p, 1.2, 0.25, 0.05);
  run_cmd(&r, &a, &k, 1);
  tcp_set(&r, end);
  print_message("movel r 0.05 alone: stops %.2e m from its target\n", dist3(end, p));
  assert_true(dist3(end, p) < 1e-8);
  assert_true(max_abs_qd(&r) == 0.0);
  assert_true(r.c->motion_done_id >= a.id);
  rig_free(&r);
}

/* movec: three points on a circle of radius 0.08 about c in the base x-y plane, start at 0°,
 * via at 60°, to at 150°: every set-point on that circle, the arc length 0.08 · 5π/6 run at v
 * (a trapezoid: L/v + v/a), mode 1 keeps the tangent fixed in the tool frame, mode 0 ends in
 * pose_to's orientation */
static void movec_case(int mode) {
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  go_work(&r);
  static rec_t k;
  k.n = 0;
  k.qdd_max = 0.0;
  double p[6];
  tcp_set(&r, p);
  const double rho = 0.08, c[3] = {p[0] - rho, p[1], p[2]};
  urt_ctrl_cmd_t m = rig_cmd(&r, URT_CTRL_MOVEC);
  m.q[0] = c[0] + rho * cos(M_PI / 3);
  m.q[1] = c[1] + rho * sin(M_PI / 3);
  m.q[2] = c[2];
  memcpy(m.pose, p, sizeof m.pose);
  m.pose[0] = c[0] + rho * cos(5 * M_PI / 6);
  m.pose[1] = c[1] + rho * sin(5 * M_PI / 6);
  m.pose[5] += mode ? 0.0 : 0.3;  // mode 0: turns to this orientation
  m.a = 1.0;
  m.v = 0.1;
  m.index = mode;
  run_cmd(&r, &m, &k, 1);
  double off = 0.0, tan_dev = 0.0, t0[3] = {0};
  for (int i = 0; i < k.n; i++) {
    off = fmax(off, fabs(dist3(k.p[i], c) - rho));
    off = fmax(off, fabs(k.p[i][2] - c[2]));
    // the tangent of the circle at the point, in the tool frame (Rᵀ t)
    const double ang = atan2(k.p[i][1] - c[1], k.p[i][0] - c[0]);
    const double t[3] = {-sin(ang), cos(ang), 0.0};
    const double *R = k.R[i];
    double tl[3];
    for (int a = 0; a < 3; a++) tl[a] = R[0 + a] * t[0] + R[3 + a] * t[1] + R[6 + a] * t[2];
    if (i == 0) memcpy(t0, tl, sizeof t0);
    tan_dev = fmax(tan_dev, dist3(tl, t0));
  }
  const double L = rho * 5 * M_PI / 6, T = L / 0.1 + 0.1 / 1.0, t = k.n * 0.002;
  double end[6];
  tcp_set(&r, end);
  print_message("movec mode %d: %d periods (%.4f s, trapezoid %.4f s), off the circle %.2e m, "
                "tangent in the tool frame moved %.2e, end off %.2e m, rz %.4f (asked %.4f)\n",
                mode, k.n, t, T, off, tan_dev, dist3(end, m.pose), end[5], m.pose[5]);
  assert_true(off < 1e-7);
  assert_true(fabs(t - T) < 0.02);
  assert_true(dist3(end, m.pose) < 1e-8);
  if (mode == 1) {
    assert_true(tan_dev < 1e-6);
  } else {
    // the end orientation is pose_to's (rotation matrices: a rotation vector near π flips)
    double Re[9], Rt[9];
    rotm(end, Re);
    rotm(m.pose, Rt);
    for (int i = 0; i < 9; i++) assert_near(Re[i], Rt[i], 1e-8);
  }
  rig_free(&r);
}

static void test_movec__every_point_on_the_circle_mode_1_fixed_to_the_tangent(void **state) {
  (void)state;
  movec_case(1);
}

static void test_movec__mode_0_interpolates_to_pose_to(void **state) {
  (void)state;
  movec_case(0);
}

static void test_movec__three_points_on_a_line_are_refused(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  go_work(&r);
  double p[6];
  tcp_set(&r, p);
  urt_ctrl_cmd_t m = rig_cmd(&r, URT_CTRL_MOVEC);
  memcpy(m.pose, p, sizeof m.pose);
  m.pose[0] += 0.1;
  m.q[0] = p[0] + 0.05;
  m.q[1] = p[1];
  m.q[2] = p[2];
  m.a = 1.0;
  m.v = 0.1;
  rig_period(&r, &m);
  assert_true(r.c->fault & URT_CTRL_FAULT_BAD_ARGUMENT);
  assert_true(r.c->motion_done_id >= m.id);
  assert_int_equal(r.c->motion, URT_MOTION_IDLE);
  rig_free(&r);
}

/* optimovel: the tool speed is the fraction v of what the joints allow along the line, so at
 * cruise the leading joint runs at v of its planned maximum (0.98 qd_max) */
static void test_optimovel__fractions_of_what_the_joints_allow(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  go_work(&r);
  double p[6], end[6];
  tcp_set(&r, p);
  p[0] += 0.25;
  p[2] -= 0.1;
  const double fv = 0.2;
  urt_ctrl_cmd_t o = rig_tool_move(&r, URT_CTRL_OPTIMOVEL, p, 0.5, fv, 0.0);
  rig_period(&r, &o);
  double peak = 0.0;
  for (int i = 0; i < 10000 && r.c->motion_done_id < o.id; i++) {
    for (int j = 0; j < URT_NJ; j++) {
      peak = fmax(peak, fabs(r.c->qd1[j]) / (0.98 * r.m->joint[j].qd_max));
    }
    rig_period(&r, NULL);
  }
  tcp_set(&r, end);
  print_message("optimovel v %.2f: leading joint's peak %.4f of 0.98 qd_max, end off %.2e m\n",
                fv, peak, dist3(end, p));
  assert_true(peak <= fv * 1.02 && peak >= fv * 0.95);
  assert_true(dist3(end, p) < 1e-8);
  const double bad[][2] = {{0.0, 0.5}, {1.5, 0.5}, {0.5, 0.0}, {0.5, 1.01}, {NAN, 0.5}};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    urt_ctrl_cmd_t b = rig_tool_move(&r, URT_CTRL_OPTIMOVEL, p, bad[i][0], bad[i][1], 0.0);
    rig_period(&r, &b);
    assert_true(r.c->fault & URT_CTRL_FAULT_BAD_ARGUMENT);
    assert_true(r.c->motion_done_id >= b.id);
  }
  rig_free(&r);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_blend__movel_corner_is_the_arc_tangent_to_both_lines),
      cmocka_unit_test(test_blend__radius_over_half_the_segment_shrinks_to_half),
      cmocka_unit_test(test_movep__constant_tool_speed_through_a_circular_blend),
      cmocka_unit_test(test_blend__a_turning_line_into_a_straight_one_turns_the_tool_without_a_step),
      cmocka_unit_test(test_blend__movej_passes_within_r_without_stopping),
      cmocka_unit_test(test_blend__movej_into_movel),
      cmocka_unit_test(test_blend__movel_into_movej),
      cmocka_unit_test(test_blend__movec_into_movel),
      cmocka_unit_test(test_blend__movel_into_optimovel),
      cmocka_unit_test(test_blend__a_pure_rotation_stops_at_its_target_then_the_next_starts),
      cmocka_unit_test(test_blend__halt_ends_the_move_and_the_queued_one),
      cmocka_unit_test(test_blend__the_last_move_stops_at_its_target),
      cmocka_unit_test(test_movec__every_point_on_the_circle_mode_1_fixed_to_the_tangent),
      cmocka_unit_test(test_movec__mode_0_interpolates_to_pose_to),
      cmocka_unit_test(test_movec__three_points_on_a_line_are_refused),
      cmocka_unit_test(test_optimovel__fractions_of_what_the_joints_allow),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
