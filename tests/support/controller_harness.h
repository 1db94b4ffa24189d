/* SPDX-License-Identifier: Apache-2.0
 * tests/support/controller_harness.h — the controller tests' rig: model, data and controller,
 * run the way the hard loop runs them (per period urt_ctrl_apply the command, urt_ctrl_tick,
 * then n_sub × (urt_ctrl_setpoint(k), urt_command_set, urt_step)). Fails the test on error. */
#ifndef URT_TEST_CONTROLLER_HARNESS_H
#define URT_TEST_CONTROLLER_HARNESS_H

#include <stdint.h>

#include "urt/controller.h"
#include "urt/core.h"

typedef struct rig {
  urt_model_t *m;
  urt_data_t *d;
  urt_ctrl_t *c;
  uint64_t next_id; /* the id the next motion command gets */
} rig_t;

/* The test model with overrides (NULL-terminated "key=value" list or NULL), its data, and a
 * controller at period [s], powered on or not. */
rig_t rig_new(const char *const *overrides, double period, int powered);
void rig_free(rig_t *r);

/* One controller period: the command (NULL for none), tick, physics steps. */
void rig_period(rig_t *r, const urt_ctrl_cmd_t *cmd);

/* Periods without commands for t [s]. */
void run_for(rig_t *r, double t);

/* The TCP pose of the actual joint angles (x y z rx ry rz, controller's TCP offset). */
void tcp_actual(const rig_t *r, double pose[6]);

/* A command of this kind with the rig's next motion id, every other field 0. */
urt_ctrl_cmd_t rig_cmd(rig_t *r, int kind);

/* A movej to joint positions q with acceleration a and speed v. */
urt_ctrl_cmd_t rig_movej(rig_t *r, const double q[6], double a, double v);

/* A tool-space motion (movel, movep, optimovel, …) to pose with acceleration a, speed v and
 * blend radius rad. */
urt_ctrl_cmd_t rig_tool_move(rig_t *r, int kind, const double pose[6], double a, double v,
                             double rad);

#endif
