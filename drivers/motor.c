/* SPDX-License-Identifier: Apache-2.0
 * drivers/motor.c — DC-equivalent PMSM, paper eq. (1). Equations in the header. */
#include "urt/drivers/motor.h"

urt_motor_deriv_t urt_motor_deriv(const urt_motor_params_t *p, const urt_motor_state_t *s,
                                  double v_sup, double t_in) {
  urt_motor_deriv_t out;
  out.di = (v_sup - p->r * s->i - p->ke * s->qd_m) / p->l;
  out.dq = s->qd_m;
  out.dqd = (p->kt * s->i - t_in) / p->j;
  return out;
}
