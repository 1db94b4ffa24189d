/* SPDX-License-Identifier: Apache-2.0
 * core/command.c — the only door from commands into the physics: every value is checked
 * before it can reach the state, as a real controller refuses a target it cannot follow. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "step_internal.h"
#include "urt/core.h"

// Which protective-stop causes a command carries (0: acceptable).
static uint32_t command_faults(const urt_model_t *m, const urt_command_t *c) {
  uint32_t bad = 0;
  for (int j = 0; j < URT_NJ; j++) {
    const urt_joint_params_t *jp = &m->joint[j];
    if (!isfinite(c->q[j]) || !isfinite(c->qd[j]) || !isfinite(c->qdd[j]) ||
        !isfinite(c->tau_ff[j])) {
      bad |= URT_PSTOP_NONFINITE_CMD;
      continue;
    }
    if (c->q[j] < jp->q_min || c->q[j] > jp->q_max) {
      bad |= URT_PSTOP_POS_LIMIT;
    }
    if (fabs(c->qd[j]) > jp->qd_max) {
      bad |= URT_PSTOP_SPEED_LIMIT;
    }
    if (fabs(c->qdd[j]) > jp->qdd_max) {
      bad |= URT_PSTOP_ACC_LIMIT;
    }
    if (fabs(c->tau_ff[j]) > jp->torque_max) {
      bad |= URT_PSTOP_TORQUE_LIMIT;
    }
  }
  return bad;
}

void urt__command_hold(urt_data_t *d) {
  memset(&d->cmd, 0, sizeof d->cmd);
  for (int j = 0; j < URT_NJ; j++) {
    d->cmd.q[j] = urt__measured_q(d, j);
  }
}

int urt__command_check(const urt_model_t *m, urt_data_t *d) {
  uint32_t bad = command_faults(m, &d->cmd);
  if (bad) {
    d->pstop |= bad;
    urt__command_hold(d);
    return URT_EPSTOP;
  }
  return URT_OK;
}

int urt_command_set(const urt_model_t *m, urt_data_t *d, const urt_command_t *cmd) {
  // in protective stop the set-point stays where the stop left it until urt_pstop_reset
  if (d->pstop) {
    return URT_EPSTOP;
  }
  d->cmd = *cmd;
  return urt__command_check(m, d);
}

void urt_pstop_reset(const urt_model_t *m, urt_data_t *d) {
  (void)m;
  d->pstop = 0;
  urt__command_hold(d);
}

const char *urt_pstop_text(uint32_t bits, char *buf, size_t n) {
  static const char *const names[] = {"non-finite command", "position limit", "speed limit",
                                      "acceleration limit", "torque limit",
                                      "non-finite state", "encoder disagreement"};
  size_t used = 0;
  if (n == 0) {
    return buf;
  }
  buf[0] = '\0';
  for (int b = 0; b < (int)(sizeof names / sizeof names[0]); b++) {
    if (bits & (1u << b)) {
      int k = snprintf(buf + used, n - used, "%s%s", used ? ", " : "", names[b]);
      used = k < 0 ? used : used + (size_t)k < n ? used + (size_t)k : n - 1;
    }
  }
  if (used == 0) {
    snprintf(buf, n, "none");
  }
  return buf;
}
