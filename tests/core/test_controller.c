/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_controller.c — core/controller.cpp and core/snapshot.cpp, each run the way
 * the hard loop runs them: per period urt_ctrl_apply the commands, urt_ctrl_tick, then
 * n_sub × (urt_ctrl_setpoint(k), urt_command_set, urt_step). Sensor noise on as configured
 * unless a test says otherwise. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_model.h"
#include "test_support.h"
#include "urt/controller.h"
#include "urt/snapshot.h"

typedef struct rig {
  urt_model_t *m;
  urt_data_t *d;
  urt_ctrl_t *c;
  uint64_t next_id;
} rig_t;

static rig_t rig_new(const char *const *overrides, double period, int powered) {
  rig_t r;
  r.m = urt_test_model(overrides);
  r.d = calloc(1, sizeof *r.d);
  r.c = calloc(1, sizeof *r.c);
  assert_non_null(r.d);
  assert_non_null(r.c);
  assert_int_equal(urt_data_init(r.m, r.d, NULL), 0);
  assert_int_equal(urt_ctrl_init(r.m, r.c, r.d, period, powered), 0);
  r.next_id = 1;
  return r;
}

static void rig_free(rig_t *r) {
  free(r->d);
  free(r->c);
  urt_model_free(r->m);
}

/* one controller period: commands, tick, physics steps */
static void rig_period(rig_t *r, const urt_ctrl_cmd_t *cmd) {
  if (cmd) {
    urt_ctrl_apply(r->m, r->c, r->d, cmd);
  }
  urt_ctrl_tick(r->m, r->c, r->d);
  for (int k = 0; k < r->c->n_sub; k++) {
    urt_command_t sp;
    urt_ctrl_setpoint(r->m, r->c, k, &sp);
    urt_command_set(r->m, r->d, &sp);
    urt_step(r->m, r->d);
  }
}

static double q_act(const rig_t *r, int j) { return r->d->x[j][URT_X_Q]; }

static urt_ctrl_cmd_t cmd_of(rig_t *r, int kind) {
  urt_ctrl_cmd_t c;
  memset(&c, 0, sizeof c);
  c.kind = kind;
  if (kind >= URT_CTRL_MOVEJ && kind <= URT_CTRL_DIRECT) {
    c.id = r->next_id++;
  }
  return c;
}

static urt_ctrl_cmd_t movej_to(rig_t *r, const double *q, double a, double v) {
  urt_ctrl_cmd_t c = cmd_of(r, URT_CTRL_MOVEJ);
  memcpy(c.q, q, sizeof c.q);
  c.a = a;
  c.v = v;
  return c;
}

/* run until the motion id is done (or max_t); returns the time it took [s] */
static double run_until_done(rig_t *r, const urt_ctrl_cmd_t *cmd, double max_t) {
  double t = 0.0;
  rig_period(r, cmd);
  t += r->c->period;
  while (r->c->motion_done_id < cmd->id && t < max_t) {
    rig_period(r, NULL);
    t += r->c->period;
  }
  return t;
}

static void run_for(rig_t *r, double t) {
  int n = (int)lround(t / r->c->period);
  for (int i = 0; i < n; i++) {
    rig_period(r, NULL);
  }
}

/* ideal trapezoid time of a distance D at a, v */
static double trap_time(double D, double a, double v) {
  return D * a <= v * v ? 2.0 * sqrt(D / a) : D / v + v / a;
}

static void movej_shoulder(double period) {
  rig_t r = rig_new(NULL, period, 1);
  double q[URT_NJ];
  for (int j = 0; j < URT_NJ; j++) {
    q[j] = q_act(&r, j);
  }
  double D = 30.0 * M_PI / 180.0;
  q[1] += D;
  urt_ctrl_cmd_t c = movej_to(&r, q, 1.4, 1.05);
  double t = run_until_done(&r, &c, 5.0);
  double ideal = trap_time(D, 1.4, 1.05);
  double err_end = fabs(q_act(&r, 1) - q[1]);
  run_for(&r, 0.5);
  double err = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    err = fmax(err, fabs(q_act(&r, j) - q[j]));
  }
  print_message("movej 30 deg shoulder, period %.3f s: %.4f s (ideal %.4f s, %+.2f %%); error at "
                "done %.2e rad, 0.5 s later %.2e rad; pstop %u\n",
                period, t, ideal, 100.0 * (t - ideal) / ideal, err_end, err, r.d->pstop);
  assert_int_equal(r.d->pstop, 0);
  assert_true(fabs(t - ideal) <= 0.1 * ideal);
  assert_true(err <= 1e-4);
  rig_free(&r);
}

static void test_movej__trapezoid_time_and_settling_e_series(void **state) {
  (void)state;
  movej_shoulder(0.002);
}

static void test_movej__trapezoid_time_and_settling_cb3(void **state) {
  (void)state;
  movej_shoulder(0.008);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_movej__trapezoid_time_and_settling_e_series),
      cmocka_unit_test(test_movej__trapezoid_time_and_settling_cb3),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
