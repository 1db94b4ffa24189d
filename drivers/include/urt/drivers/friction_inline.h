/* SPDX-License-Identifier: Apache-2.0
 * urt/drivers/friction_inline.h — urt_friction_eval's body (LuGre, paper eq. (7); equations
 * in friction.h) as a static inline function. The core's right-hand side (core/joint.cpp)
 * runs it tens of times per step; as a call into the drivers library its result struct went
 * through memory. urt_friction_eval in the library is this same code, so both give the same
 * bits. Context: RT. Pure. */
#ifndef URT_DRIVERS_FRICTION_INLINE_H
#define URT_DRIVERS_FRICTION_INLINE_H

#include <math.h>

#include "urt/drivers/friction.h"

// g(|q̇|) and |q̇|·g'(|q̇|), which stays finite at rest although g' does not. One exp and one
// cbrt serve both.
static inline void urt__friction_g_and_vdg(const urt_friction_params_t *p, double v, double *g,
                                           double *v_dg) {
  double e = exp(-p->k_q * v / p->qd_s);
  double v23 = cbrt(v * v);  // |q̇|^{2/3}: the printed q̇^{2/3} is NaN for q̇ < 0 (model.md §1.6)
  *g = p->f_c * (1.0 + p->k_static * e) + p->f_v * v23;
  *v_dg = -p->f_c * p->k_static * (p->k_q / p->qd_s) * e * v + (2.0 / 3.0) * p->f_v * v23;
}

static inline urt_friction_out_t urt_friction_eval_inline(const urt_friction_params_t *p,
                                                         const urt_friction_state_t *s,
                                                         double qd) {
  double z = s->z;
  urt_friction_out_t out = {0.0, 0.0, 0.0, 0.0};
  if (!p->enabled) {
    return out;
  }
  double v = fabs(qd), g, v_dg;
  urt__friction_g_and_vdg(p, v, &g, &v_dg);

  // ż = q̇ − σ0 |q̇| z / g
  double r = v / g;
  out.dz = qd - p->sigma0 * r * z;
  out.ddz_dz = -p->sigma0 * r;

  // d(|q̇|/g)/dq̇ = sgn(q̇) [1/g − |q̇| g'(|q̇|)/g²]
  double sgn = qd > 0.0 ? 1.0 : (qd < 0.0 ? -1.0 : 0.0);
  double dr = sgn * (1.0 / g - v_dg / (g * g));
  out.ddz_dqd = 1.0 - p->sigma0 * z * dr;

  out.t_f = p->sigma0 * z + p->sigma1 * out.dz;
  return out;
}

#endif
