/* SPDX-License-Identifier: Apache-2.0
 * tests/support/controller_harness.c — the controller tests' rig (see controller_harness.h). */
#include "controller_harness.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_model.h"
#include "test_support.h"

rig_t rig_new(const char *const *overrides, double period, int powered) {
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

void rig_free(rig_t *r) {
  free(r->d);
  free(r->c);
  urt_model_free(r->m);
}

void rig_period(rig_t *r, const urt_ctrl_cmd_t *cmd) {
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

void run_for(rig_t *r, double t) {
  int n = (int)lround(t / r->c->period);
  for (int i = 0; i < n; i++) {
    rig_period(r, NULL);
  }
}

void tcp_actual(const rig_t *r, double pose[6]) {
  double q[URT_NJ];
  for (int j = 0; j < URT_NJ; j++) {
    q[j] = r->d->x[j][URT_X_Q];
  }
  urt_ctrl_forward_kinematics_tcp(r->m, r->c->tcp_offset, q, pose);
}

urt_ctrl_cmd_t rig_cmd(rig_t *r, int kind) {
  urt_ctrl_cmd_t c;
  memset(&c, 0, sizeof c);
  c.kind = kind;
  c.id = r->next_id++;
  return c;
}

urt_ctrl_cmd_t rig_movej(rig_t *r, const double q[6], double a, double v) {
  urt_ctrl_cmd_t c = rig_cmd(r, URT_CTRL_MOVEJ);
  memcpy(c.q, q, sizeof c.q);
  c.a = a;
  c.v = v;
  return c;
}

urt_ctrl_cmd_t rig_tool_move(rig_t *r, int kind, const double pose[6], double a, double v,
                             double rad) {
  urt_ctrl_cmd_t c = rig_cmd(r, kind);
  memcpy(c.pose, pose, sizeof c.pose);
  c.a = a;
  c.v = v;
  c.r = rad;
  return c;
}
