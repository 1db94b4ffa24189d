/* SPDX-License-Identifier: Apache-2.0
 * drivers/harmonic_drive.c — the 4-DoF strain-wave gear of paper eqs. (2)–(6). Equations in the
 * header. */
#include "urt/drivers/harmonic_drive.h"
#include "urt/drivers/harmonic_drive_inline.h"

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
  return urt_harmonic_drive_eval_inline(p, s, e);
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
