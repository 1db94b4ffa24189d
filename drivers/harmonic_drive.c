/* SPDX-License-Identifier: Apache-2.0
 * drivers/harmonic_drive.c — the 4-DoF strain-wave gear of paper eqs. (2)–(6). Equations in the
 * header. */
#include "urt/drivers/harmonic_drive.h"

#include <math.h>

#include "urt/errors.h"

static double damping(double zeta, double k, double m_red) { return 2.0 * zeta * sqrt(k * m_red); }

void urt_harmonic_drive_derive(urt_harmonic_drive_params_t *p, double j_m) {
  p->ratio = p->z_cs / (p->z_cs - p->z_fs);
  p->alpha_n = atan(1.0 / (p->ratio * tan(p->alpha_t)));
  p->m_fs = p->j_fs / (p->r_g * p->r_g);
  p->sin_n = sin(p->alpha_n);
  p->cos_n = cos(p->alpha_n);
  p->tan_n = tan(p->alpha_n);
  p->sin_t = sin(p->alpha_t);
  p->cos_t = cos(p->alpha_t);

  // "damping all set equal to 0.1" read as a damping ratio on each spring, with the reduced
  // inertia of the two bodies it joins (model.md §2.2)
  double m_cs = p->j_cs / (p->r_g * p->r_g);
  p->c_wg = damping(p->zeta, p->k_wg, j_m * p->j_wg / (j_m + p->j_wg));
  p->c_b = damping(p->zeta, p->k_b, p->m_fs);
  p->c_m = damping(p->zeta, p->k_m, p->m_fs * m_cs / (p->m_fs + m_cs));
  p->c_fs = damping(p->zeta, p->k_fs, p->j_fs);
  p->c_cs = damping(p->zeta, p->k_cs, p->j_cs);
}

urt_harmonic_drive_out_t urt_harmonic_drive_eval(const urt_harmonic_drive_params_t *p,
                                                 const urt_harmonic_drive_state_t *s,
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

int urt_harmonic_drive_equilibrium(const urt_harmonic_drive_params_t *p, double q0, double t0,
                                   double u[5], double *t_in) {
  double sn = sin(p->alpha_n), cn = cos(p->alpha_n);
  double st = sin(p->alpha_t), ct = cos(p->alpha_t);
  double tn = tan(p->alpha_n);
  double rg = p->r_g;
  if (!(st > 0.0 && ct > 0.0 && tn > 0.0 && rg > 0.0)) {
    return URT_ESOLVER;
  }

  // the augmented eq. (6) is triangular once solved from the output back to the motor:
  // the CS carries t0, the mesh force follows, then the FS, the WG bearing and the WG spring
  double q_cs = q0 + t0 / p->k_cs;
  double f_m = t0 / (rg * ct);
  double y_fs = f_m * ct * rg * rg / p->k_fs;
  double y_cs = rg * q_cs;
  double x_fs = (f_m / p->k_m + (y_cs + y_fs) * ct) / st;
  double f_b = f_m * st;
  double x_wg = x_fs + f_b / p->k_b;
  double q_wg = x_wg / (rg * tn);
  double tin = f_b * rg * sn * cn;
  double q_m = q_wg + tin / p->k_wg;

  u[0] = q_m;
  u[1] = q_wg;
  u[2] = x_fs;
  u[3] = y_fs;
  u[4] = q_cs;
  *t_in = tin;
  return URT_OK;
}
