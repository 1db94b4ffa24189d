/* SPDX-License-Identifier: Apache-2.0
 * urt/drivers/harmonic_drive_inline.h — urt_harmonic_drive_eval's body (the strain-wave gear rates
 * of paper eq. (5); equations in harmonic_drive.h) as a static inline function. The core's right-
 * hand side (core/joint.cpp) runs it tens of times per step; as a call into the drivers library
 * its argument and result structs went through memory and cost more than the arithmetic.
 * urt_harmonic_drive_eval in the library is this same code, Context: RT. Pure. */
#ifndef URT_DRIVERS_HARMONIC_DRIVE_INLINE_H
#define URT_DRIVERS_HARMONIC_DRIVE_INLINE_H

#include "urt/drivers/harmonic_drive.h"

static inline urt_harmonic_drive_out_t urt_harmonic_drive_eval_inline(
    const urt_harmonic_drive_params_t *p, const urt_harmonic_drive_state_t *s,
    const urt_harmonic_drive_ends_t *e) {
  double sn = p->sin_n, cn = p->cos_n, st = p->sin_t, ct = p->cos_t, tn = p->tan_n;
  double rg = p->r_g;

  // kinematic relations of eq. (6): the WG cam and the CS pitch circle as translations
  double x_wg = rg * tn * s->q_wg, xd_wg = rg * tn * s->qd_wg;
  double y_cs = rg * s->q_cs, yd_cs = rg * s->qd_cs;

  // spring-damper forces
  double t_in = p->k_wg * (e->q_m - s->q_wg) + p->c_wg * (e->qd_m - s->qd_wg);
  double f_b = p->k_b * (x_wg - s->x_fs) + p->c_b * (xd_wg - s->xd_fs);
  double f_m = p->k_m * (s->x_fs * st - (y_cs + s->y_fs) * ct) +
               p->c_m * (s->xd_fs * st - (yd_cs + s->yd_fs) * ct);
  double f_t = (p->k_fs * s->y_fs + p->c_fs * s->yd_fs) / (rg * rg);
  double t_cs = p->k_cs * (s->q_cs - e->q) + p->c_cs * (s->qd_cs - e->qd);

  // eq. (5)
  urt_harmonic_drive_out_t out;
  out.t_in = t_in;
  out.t_cs = t_cs;
  out.d.q_wg = s->qd_wg;
  out.d.qd_wg = (t_in - f_b * rg * sn * cn) / p->j_wg;
  out.d.x_fs = s->xd_fs;
  out.d.xd_fs = (f_b - f_m * st) / p->m_fs;
  out.d.y_fs = s->yd_fs;
  out.d.yd_fs = (f_m * ct - f_t) / p->m_fs;
  out.d.q_cs = s->qd_cs;
  out.d.qd_cs = (f_m * rg * ct - t_cs) / p->j_cs;
  return out;
}

#endif
