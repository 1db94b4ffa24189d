/* SPDX-License-Identifier: Apache-2.0
 * urt/drivers/motor_inline.h — urt_motor_deriv's body (the DC-equivalent motor rates of paper eq.
 * (1); equations in motor.h) as a static inline function. The core's right-hand side
 * (core/joint.cpp) runs it tens of times per step; as a call into the drivers library its argument
 * and result structs went through memory and cost more than the arithmetic. urt_motor_deriv in the
 * library is this same code, Context: RT. Pure. */
#ifndef URT_DRIVERS_MOTOR_INLINE_H
#define URT_DRIVERS_MOTOR_INLINE_H

#include "urt/drivers/motor.h"

static inline urt_motor_deriv_t urt_motor_deriv_inline(const urt_motor_params_t *p,
                                                       const urt_motor_state_t *s, double v_sup,
                                                       double t_in) {
  urt_motor_deriv_t out;
  out.di = (v_sup - p->r * s->i - p->ke * s->qd_m) / p->l;
  out.dq = s->qd_m;
  out.dqd = (p->kt * s->i - t_in) / p->j;
  return out;
}

#endif
