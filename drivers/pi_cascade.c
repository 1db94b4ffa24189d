/* SPDX-License-Identifier: Apache-2.0
 * drivers/pi_cascade.c — position P, speed PI, current PI with clamping anti-windup and the
 * averaged 48 V PWM stage. Equations in the header. */
#include "urt/drivers/pi_cascade.h"

static double clamp(double x, double lim) { return x > lim ? lim : (x < -lim ? -lim : x); }

urt_pi_cascade_out_t urt_pi_cascade_eval(const urt_pi_cascade_params_t *p, double ratio,
                                         const urt_pi_cascade_state_t *s,
                                         const urt_pi_cascade_in_t *in) {
  urt_pi_cascade_out_t out;

  // position loop: joint-side error to a motor-speed reference, plus the speed feed-forward
  out.qdm_ref = p->p_pos * (in->q_set - in->q_fb) + ratio * in->qd_set;

  // speed loop: the integrator stops while the limit holds and the error pushes further out,
  // so it unwinds as soon as the error changes sign
  double e_v = out.qdm_ref - in->qdm_fb;
  if (in->torque) {
    // torque mode: the current reference is the feed-forward alone, ξ_v held
    out.i_ref = clamp(in->i_ff, p->i_max);
    out.i_sat = out.i_ref != in->i_ff;
    out.d.xi_v = 0.0;
  } else {
    double u_v = p->p_vel * e_v + p->i_vel * s->xi_v + in->i_ff;
    out.i_ref = clamp(u_v, p->i_max);
    out.i_sat = out.i_ref != u_v;
    out.d.xi_v = (out.i_sat && e_v * u_v > 0.0) ? 0.0 : e_v;
  }

  // current loop and PWM saturation, same anti-windup
  double e_c = out.i_ref - in->i_fb;
  double u_c = p->p_cur * e_c + p->i_cur * s->xi_c;
  out.v_sup = clamp(u_c, p->v_net);
  out.v_sat = out.v_sup != u_c;
  out.d.xi_c = (out.v_sat && e_c * u_c > 0.0) ? 0.0 : e_c;
  return out;
}
