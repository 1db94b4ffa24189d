/* SPDX-License-Identifier: Apache-2.0
 * urt/drivers/friction_inline.h — urt_friction_eval's body (LuGre, paper eq. (7); equations
 * in friction.h) as a static inline function. The core's right-hand side (core/joint.cpp)
 * runs it tens of times per step; as a call into the drivers library its result struct went
 * through memory. urt_friction_eval in the library is this same code, so both give the same
 * bits. Context: RT. Pure. */
#ifndef URT_DRIVERS_FRICTION_INLINE_H
#define URT_DRIVERS_FRICTION_INLINE_H

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "urt/drivers/friction.h"

// ∛a for a ≥ 0 without libm's cbrt, which cost more than the rest of the friction law (its
// frexp/ldexp calls included). An exponent-bit guess of a^(−1/3) (≈ 3 % off), four Newton
// steps r ← r (4 − a r³)/3 that need no division (3 % → 2e−3 → 1e−5 → 3e−10 → 1e−19), then
// one Newton step on t = a r² with its residual t³ − a taken exactly by FMA. The result is
// the correctly rounded ∛a in all but ~2 of 10⁴ cases (1 ulp there), checked against cbrtl
// for |q̇| over 10⁻¹²…10 rad/s; glibc's cbrt is 1 ulp off in more than half of them, so the two
// differ in the last bit. Zero, subnormal, infinite and NaN arguments go to cbrt.
static inline double urt__friction_cbrt(double a) {
  if (!(a >= DBL_MIN && a <= DBL_MAX)) {
    return cbrt(a);
  }
  uint64_t bits;
  memcpy(&bits, &a, sizeof bits);
  bits = 0x553ef0ff289dd794ULL - bits / 3;
  double r;
  memcpy(&r, &bits, sizeof r);
  for (int k = 0; k < 4; k++) {
    r = r * (4.0 - a * r * r * r) * (1.0 / 3.0);
  }
  double t = a * r * r;
  double t2 = t * t, t2_err = fma(t, t, -t2);
  double res = fma(t2, t, -a) + t2_err * t;
  return t - res * (r * r) * (1.0 / 3.0);
}

// The Coulomb level on the side of q̇'s sign: f_c (1 ± a). With a = 0 it is f_c itself (not
// f_c · 1.0 computed), so the symmetric law keeps its bits.
static inline double urt__friction_fc(const urt_friction_params_t *p, double qd) {
  if (p->asym == 0.0 || qd == 0.0) {
    return p->f_c;
  }
  return p->f_c * (1.0 + (qd > 0.0 ? p->asym : -p->asym));
}

// g(|q̇|) and |q̇|·g'(|q̇|) for Coulomb level fc, which stays finite at rest although g' does
// not. One exp and one cube root serve both.
static inline void urt__friction_g_and_vdg(const urt_friction_params_t *p, double fc, double v,
                                           double *g, double *v_dg) {
  double e = exp(-p->k_q * v / p->qd_s);
  // |q̇|^{2/3}: the printed q̇^{2/3} is NaN for q̇ < 0 (model.md §1.6)
  double v23 = urt__friction_cbrt(v * v);
  *g = fc * (1.0 + p->k_static * e) + p->f_v * v23;
  *v_dg = -fc * p->k_static * (p->k_q / p->qd_s) * e * v + (2.0 / 3.0) * p->f_v * v23;
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
  urt__friction_g_and_vdg(p, urt__friction_fc(p, qd), v, &g, &v_dg);

  // ż = q̇ − σ0 |q̇| z / g
  double r = v / g;
  out.dz = qd - p->sigma0 * r * z;
  out.ddz_dz = -p->sigma0 * r;
  if (p->relax > 0.0) {
    // stuck bristles relax (− λ z): a held joint lets go of the friction it stopped with
    out.dz -= p->relax * z;
    out.ddz_dz -= p->relax;
  }

  // d(|q̇|/g)/dq̇ = sgn(q̇) [1/g − |q̇| g'(|q̇|)/g²]
  double sgn = qd > 0.0 ? 1.0 : (qd < 0.0 ? -1.0 : 0.0);
  double dr = sgn * (1.0 / g - v_dg / (g * g));
  out.ddz_dqd = 1.0 - p->sigma0 * z * dr;

  out.t_f = p->sigma0 * z + p->sigma1 * out.dz;
  return out;
}

#endif
