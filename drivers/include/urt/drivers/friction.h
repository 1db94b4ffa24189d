/* SPDX-License-Identifier: Apache-2.0
 * drivers/include/urt/drivers/friction.h — LuGre friction at the joint output, paper eq. (7),
 * sign convention of model.md §1.6.
 *
 *   T_f  = σ0 z + σ1 ż               (acts against the joint: T_u = T_CS − T_f)
 *   ż    = q̇ − σ0 |q̇| z / g(q̇) − λ z
 *   g(q̇) = f_c,± [1 + K_s exp(−k_q |q̇| / q̇_s)] + f_v |q̇|^{2/3}    (> 0)
 *   f_c,± = f_c (1 ± a)   for q̇ > 0 / q̇ < 0   (f_c at q̇ = 0, where g does not enter ż)
 *
 * Symbols: z [rad] bristle deflection, σ0 [N m/rad], σ1 [N m s/rad], f_c [N m],
 * f_v [N m (s/rad)^{2/3}], q̇_s [rad/s], K_s, k_q [-], a [-] the direction asymmetry of the
 * Coulomb (and Stribeck) level, |a| < 1. With a = 0, g is even in q̇ (the paper's law) and
 * every result is bit-for-bit the symmetric one. ż stays continuous through q̇ = 0 for any a:
 * g enters only through |q̇|/g, which vanishes there from either side.
 * With enabled = 0, T_f = 0 and ż = 0.
 */
#ifndef URT_DRIVERS_FRICTION_H
#define URT_DRIVERS_FRICTION_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_friction_params {
  int enabled;       /* 0: frictionless joint                              */
  double sigma0;     /* bristle stiffness                     [N m/rad]    */
  double sigma1;     /* bristle damping                       [N m s/rad]  */
  double qd_s;       /* Stribeck velocity                     [rad/s]      */
  double k_static;   /* static-to-Coulomb excess K_s          [-]          */
  double f_c;        /* Coulomb level                         [N m]        */
  double f_v;        /* viscous level (|q̇|^{2/3} law)         [N m (s/rad)^{2/3}] */
  double k_q;        /* Stribeck shape factor                 [-]          */
  double asym;       /* direction asymmetry a of f_c, |a| < 1 [-]          */
  double relax;      /* bristle relaxation rate λ ≥ 0 (0: the paper's law) [1/s] */
} urt_friction_params_t;

typedef struct urt_friction_state {
  double z;       /* bristle deflection              [rad]      */
} urt_friction_state_t;

typedef struct urt_friction_out {
  double t_f;     /* friction torque                 [N m]      */
  double dz;      /* ż                               [rad/s]    */
  double ddz_dz;  /* ∂ż/∂z                           [1/s]      */
  double ddz_dqd; /* ∂ż/∂q̇                           [-]        */
} urt_friction_out_t;

/* g(q̇) of eq. (7), on the side of q̇'s sign. Context: RT. Pure. */
double urt_friction_g(const urt_friction_params_t *p, double qd);

/* dg/dq̇; singular at 0 (returns 0 there). Context: any. Pure. */
double urt_friction_dg(const urt_friction_params_t *p, double qd);

/* Torque, bristle rate and their partial derivatives at joint speed qd [rad/s].
 * Context: RT. Pure. */
urt_friction_out_t urt_friction_eval(const urt_friction_params_t *p,
                                     const urt_friction_state_t *s, double qd);

#ifdef __cplusplus
}
#endif
#endif
