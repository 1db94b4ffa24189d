/* SPDX-License-Identifier: Apache-2.0
 * urt/drivers/sensors_inline.h — urt_sensors_deriv's body (the sensor filters' rates; equations in
 * sensors.h) as a static inline function. The core's right-hand side (core/joint.cpp) runs it tens
 * of times per step; as a call into the drivers library its argument and result structs went
 * through memory and cost more than the arithmetic. urt_sensors_deriv in the library is this same
 * code, Context: RT. Pure. */
#ifndef URT_DRIVERS_SENSORS_INLINE_H
#define URT_DRIVERS_SENSORS_INLINE_H

#include "urt/drivers/sensors.h"

static inline urt_sensors_state_t urt_sensors_deriv_inline(const urt_sensors_params_t *p,
                                                          const urt_sensors_state_t *s, double i,
                                                          double qd_m, double q) {
  const double two_pi = 6.283185307179586;
  double tau_i = 1.0 / (two_pi * p->f_i);
  double w_w = two_pi * p->f_w, w_q = two_pi * p->f_q;
  urt_sensors_state_t d;
  d.i_f = (i - s->i_f) / tau_i;
  d.w = s->wd;
  d.wd = w_w * w_w * (qd_m - s->w) - 2.0 * p->zeta_w * w_w * s->wd;
  d.p = s->pd;
  d.pd = w_q * w_q * (q - s->p) - 2.0 * p->zeta_q * w_q * s->pd;
  return d;
}

#endif
