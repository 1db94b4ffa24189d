/* SPDX-License-Identifier: Apache-2.0
 * urt/drivers/pi_cascade_inline.h — urt_pi_cascade_eval's body (the PI cascade with anti-windup
 * and the PWM stage; equations in pi_cascade.h) as a static inline function. The core's right-hand
 * side (core/joint.cpp) runs it tens of times per step; as a call into the drivers library its
 * argument and result structs went through memory and cost more than the arithmetic.
 * urt_pi_cascade_eval in the library is this same code, Context: RT. Pure. */
#ifndef URT_DRIVERS_PI_CASCADE_INLINE_H
#define URT_DRIVERS_PI_CASCADE_INLINE_H

#include "urt/drivers/pi_cascade.h"

static inline double urt__pi_cascade_clamp(double x, double lim) {
  return x > lim ? lim : (x < -lim ? -lim : x);
}

static inline urt_pi_cascade_out_t urt_pi_cascade_eval_inline(
    const urt_pi_cascade_params_t *p, double ratio, const urt_pi_cascade_state_t *s,
    const urt_pi_cascade_in_t *in) {
  urt_pi_cascade_out_t out;

  // position loop: joint-side error to a motor-speed reference, plus the speed feed-forward
  out.qdm_ref = p->p_pos * (in->q_set - in->q_fb) + ratio * in->qd_set;

  // speed loop: the integrator stops while the limit holds and the error pushes further out,
  // so it unwinds as soon as the error changes sign
  double e_v = out.qdm_ref - in->qdm_fb;
  if (in->torque) {
    // torque mode: the current reference is the feed-forward alone, ξ_v held
    out.i_ref = urt__pi_cascade_clamp(in->i_ff, p->i_max);
    out.i_sat = out.i_ref != in->i_ff;
    out.d.xi_v = 0.0;
  } else {
    double u_v = p->p_vel * e_v + p->i_vel * s->xi_v + in->i_ff;
    out.i_ref = urt__pi_cascade_clamp(u_v, p->i_max);
    out.i_sat = out.i_ref != u_v;
    out.d.xi_v = (out.i_sat && e_v * u_v > 0.0) ? 0.0 : e_v;
  }

  // current loop and PWM saturation, same anti-windup
  double e_c = out.i_ref - in->i_fb;
  double u_c = p->p_cur * e_c + p->i_cur * s->xi_c;
  out.v_sup = urt__pi_cascade_clamp(u_c, p->v_net);
  out.v_sat = out.v_sup != u_c;
  out.d.xi_c = (out.v_sat && e_c * u_c > 0.0) ? 0.0 : e_c;
  return out;
}

#endif
