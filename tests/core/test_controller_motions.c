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

static urt_ctrl_cmd_t cmd_of(rig_t *r, int kind) {
  urt_ctrl_cmd_t c;
  memset(&c, 0, sizeof c);
  c.kind = kind;
  c.id = r->next_id++;
  return c;
}

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

static void test_optimovej__fractions_of_the_joint_limits_set_the_time(void **state) {
  (void)state;
  rig_t r = rig_new(urt_test_quiet, 0.002, 1);
  const double D = 0.5, fa = 0.3, fv = 0.3;
  urt_ctrl_cmd_t c = cmd_of(&r, URT_CTRL_OPTIMOVEJ);
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
  // the planner's margins on the model's limits (0.98 qd_max, 0.9 qdd_max)
  const double v = fv * 0.98 * r.m->joint[0].qd_max, a = fa * 0.9 * r.m->joint[0].qdd_max;
  const double T = trapezoid_time(D, v, a);
  print_message("optimovej %.1f/%.1f over %.2f rad: done after %.4f s, trapezoid %.4f s; peak "
                "set-point speed %.6f rad/s (expected %.6f)\n",
                fa, fv, D, t, T, vmax, v);
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
    urt_ctrl_cmd_t c = cmd_of(&r, URT_CTRL_OPTIMOVEJ);
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
  urt_ctrl_cmd_t c = cmd_of(&r, URT_CTRL_OPTIMOVEJ);
  memcpy(c.q, r.c->q1, sizeof c.q);
  c.q[5] += 0.2;
  c.a = c.v = 1.0;
  double t = time_to_done(&r, &c, 3.0);
  const double T =
      trapezoid_time(0.2, 0.98 * r.m->joint[5].qd_max, 0.9 * r.m->joint[5].qdd_max);
  print_message("optimovej 1/1 over 0.2 rad: %.4f s, trapezoid %.4f s\n", t, T);
  assert_true(t >= T - 1e-9 && t <= T + 2.0 * r.c->period);
  rig_free(&r);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_optimovej__fractions_of_the_joint_limits_set_the_time),
      cmocka_unit_test(test_optimovej__fractions_outside_0_1_are_refused),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
